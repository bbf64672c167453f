//! Seed 004's edge pass against independent answers: the exact area a triangle
//! covers in each pixel (computed here by clipping the pixel square), a seamless
//! shared edge, an occluder the hidden edge must not bleed through, thread
//! independence, a smooth sphere that keeps its interior, and a supersampled frame.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::image::LinearImage;
use kage::scene::mesh::{shapes, NormalMode};
use kage::scene::{Antialias, EdgeFilter, EdgeMode, EdgeSelection, Fog, FogMode, Material, Mesh, Object, Scene};
use kage::{render, RenderOptions, Renderer};

const SIZE: u32 = 64;

/// An orthographic camera over the z = 0 plane: world (x, y) lands on screen
/// (x, SIZE − y), one world unit per pixel.
fn flat_camera() -> Camera {
    let c = SIZE as f32 * 0.5;
    Camera {
        eye: Vec3::new(c, c, 10.0),
        target: Vec3::new(c, c, 0.0),
        up: Vec3::Y,
        near: 0.1,
        far: 100.0,
        projection: Projection::Orthographic { height: SIZE as f32 },
        shift: Vec2::ZERO,
    }
}

/// A material that shades to exactly `rgb` whatever the light: emission only.
fn flat(rgb: Vec3) -> Material {
    Material { ka: Vec3::ZERO, kd: Vec3::ZERO, ks: Vec3::ZERO, ke: rgb, two_sided: true, ..Material::default() }
}

fn mesh(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Arc<Mesh> {
    Arc::new(Mesh::new(positions, Vec::new(), Vec::new(), triangles, NormalMode::Flat).expect("valid mesh").0)
}

/// Screen-space points (y down), their triangles, the depth of the object (nearer =
/// larger) and its flat colour.
type FlatShape = (Vec<Vec2>, Vec<[u32; 3]>, f32, Vec3);

/// `shapes` drawn flat over `background`.
fn flat_scene(shapes: &[FlatShape], background: Vec3) -> Scene {
    let mut scene = common::scene_with(shapes::plane(), flat_camera(), SIZE, SIZE, true);
    scene.background = background;
    scene.materials.clear();
    scene.objects.clear();
    for (i, (points, tris, z, rgb)) in shapes.iter().enumerate() {
        let positions = points.iter().map(|p| Vec3::new(p.x, SIZE as f32 - p.y, *z)).collect();
        scene.materials.push(flat(*rgb));
        scene.objects.push(Object::mesh(format!("shape {i}"), mesh(positions, tris.clone()), Affine3A::IDENTITY, i));
    }
    scene
}

fn with_edges(scene: &Scene, selection: EdgeSelection) -> Scene {
    Scene { antialias: Antialias::Edge(EdgeMode { selection, ..EdgeMode::default() }), ..scene.clone() }
}

/// Area of the triangle `t` (screen space) inside pixel (x, y), by clipping the
/// pixel square against the triangle's three half-planes.
fn covered_area(t: &[Vec2; 3], x: u32, y: u32) -> f32 {
    let (x, y) = (x as f32, y as f32);
    let mut poly = vec![Vec2::new(x, y), Vec2::new(x + 1.0, y), Vec2::new(x + 1.0, y + 1.0), Vec2::new(x, y + 1.0)];
    let orient = (t[1] - t[0]).perp_dot(t[2] - t[0]).signum();
    for k in 0..3 {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        let inside = |p: Vec2| orient * (b - a).perp_dot(p - a) >= 0.0;
        let mut out = Vec::new();
        for i in 0..poly.len() {
            let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
            if inside(p) {
                out.push(p);
            }
            if inside(p) != inside(q) {
                let (dp, dq) = ((b - a).perp_dot(p - a), (b - a).perp_dot(q - a));
                out.push(p + (q - p) * (dp / (dp - dq)));
            }
        }
        poly = out;
    }
    let n = poly.len();
    (0..n).map(|i| poly[i].perp_dot(poly[(i + 1) % n])).sum::<f32>().abs() * 0.5
}

/// Mean and largest |coverage error| over the pixels the triangle's edges cross,
/// away from its corners, for a black triangle on white.
fn coverage_errors(t: &[Vec2; 3], image: &LinearImage) -> (f32, f32, usize) {
    let (mut sum, mut worst, mut n) = (0.0, 0.0f32, 0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let area = covered_area(t, x, y);
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let near_corner = t.iter().any(|v| (*v - centre).length() < 2.0);
            if area <= 0.01 || area >= 0.99 || near_corner {
                continue;
            }
            let err = ((1.0 - image.get(x, y).x) - area).abs();
            sum += err;
            worst = worst.max(err);
            n += 1;
        }
    }
    (sum / n as f32, worst, n)
}

#[test]
fn edge_pixels_take_their_exact_covered_area() {
    // Gentle and steep edges, rising and falling, both windings.
    let triangles = [
        [Vec2::new(6.3, 20.2), Vec2::new(58.1, 9.7), Vec2::new(40.4, 55.9)],
        [Vec2::new(12.6, 4.1), Vec2::new(52.2, 58.3), Vec2::new(21.7, 59.5)],
        [Vec2::new(5.2, 40.6), Vec2::new(59.4, 30.1), Vec2::new(30.8, 7.3)],
        [Vec2::new(50.1, 3.3), Vec2::new(9.8, 57.7), Vec2::new(33.3, 60.2)],
    ];
    for t in triangles {
        let scene = flat_scene(&[(t.to_vec(), vec![[0, 1, 2]], 0.0, Vec3::ZERO)], Vec3::ONE);
        let aliased = render(&scene, &RenderOptions::default()).unwrap();
        let edged = render(&with_edges(&scene, EdgeSelection::Outline), &RenderOptions::default()).unwrap();
        let (mean_a, _, n) = coverage_errors(&t, &aliased.image);
        let (mean, worst, _) = coverage_errors(&t, &edged.image);
        eprintln!("{t:?}: {n} edge pixels, mean error aliased {mean_a:.3} → edge pass {mean:.3}, worst {worst:.3}");
        assert!(n > 60, "{n} edge pixels");
        // Each crossed pixel of a column gets its exact share (corners aside).
        assert!(mean < 0.005, "mean coverage error {mean} (aliased {mean_a})");
        assert!(worst < 0.02, "worst coverage error {worst}");
    }
}

/// The paper's own weights (§3 (2)): along an x-major edge, the pixel P whose
/// centre lies above the edge point at distance D_P gets the edge's colour with
/// alpha Filter(D_Q) = 1 − D_P. For a black triangle below a gentle edge on white,
/// P's value is therefore D_P; and the paper's rule leaves the polygon about half a
/// pixel too fat, which the coverage filter does not.
#[test]
fn the_papers_filter_blends_the_edge_colour_by_distance_and_coverage_does_better() {
    let t = [Vec2::new(3.3, 20.4), Vec2::new(60.2, 31.8), Vec2::new(30.5, 61.1)];
    let scene = flat_scene(&[(t.to_vec(), vec![[0, 1, 2]], 0.0, Vec3::ZERO)], Vec3::ONE);
    let paper = EdgeMode { selection: EdgeSelection::All, filter: EdgeFilter::Paper };
    let frame =
        render(&Scene { antialias: Antialias::Edge(paper), ..scene.clone() }, &RenderOptions::default()).unwrap();
    let mut checked = 0;
    for x in 8..56u32 {
        // The top edge from t[0] to t[1] at this column centre (y down).
        let cx = x as f32 + 0.5;
        let y = t[0].y + (cx - t[0].x) * (t[1].y - t[0].y) / (t[1].x - t[0].x);
        let p = (y - 0.5).floor();
        let d_p = (y - 0.5) - p;
        let got = frame.image.get(x, p as u32).x;
        assert!((got - d_p).abs() < 1e-4, "column {x}: P = row {p}: {got} vs D_P = {d_p}");
        checked += 1;
    }
    assert!(checked > 40);
    let coverage = render(&with_edges(&scene, EdgeSelection::All), &RenderOptions::default()).unwrap();
    let (paper_err, _, _) = coverage_errors(&t, &frame.image);
    let (coverage_err, _, _) = coverage_errors(&t, &coverage.image);
    eprintln!("mean coverage error: paper's filter {paper_err:.3}, coverage filter {coverage_err:.4}");
    assert!(coverage_err < 0.2 * paper_err, "{coverage_err} vs {paper_err}");
}

#[test]
fn a_shared_edge_between_two_triangles_of_one_colour_leaves_no_seam() {
    let grey = Vec3::splat(0.4);
    let quad = vec![Vec2::new(8.2, 9.1), Vec2::new(55.3, 12.4), Vec2::new(51.7, 56.6), Vec2::new(10.4, 50.8)];
    let scene = flat_scene(&[(quad.clone(), vec![[0, 1, 2], [0, 2, 3]], 0.0, grey)], Vec3::ZERO);
    for selection in [EdgeSelection::Outline, EdgeSelection::All] {
        let frame = render(&with_edges(&scene, selection), &RenderOptions::default()).unwrap();
        // Pixels along the diagonal from corner 0 to corner 2, away from the ends.
        for k in 4..=36 {
            let p = quad[0].lerp(quad[2], k as f32 / 40.0);
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (-1, 0), (0, -1)] {
                let (x, y) = ((p.x as i32 + dx) as u32, (p.y as i32 + dy) as u32);
                assert_eq!(frame.image.get(x, y), grey, "{selection:?}: seam at ({x}, {y})");
            }
        }
    }
}

#[test]
fn a_hidden_edge_does_not_bleed_through_its_occluder() {
    // A black triangle whose right part lies under a nearer white square; its
    // steep (y-major) edge passes under the square's left side, so pixel pairs
    // across it straddle the square's boundary.
    let tri = vec![Vec2::new(4.5, 6.2), Vec2::new(44.3, 60.7), Vec2::new(6.1, 57.4)];
    let square = vec![Vec2::new(30.0, 0.0), Vec2::new(64.0, 0.0), Vec2::new(64.0, 64.0), Vec2::new(30.0, 64.0)];
    let scene = flat_scene(
        &[(tri, vec![[0, 1, 2]], 0.0, Vec3::ZERO), (square, vec![[0, 1, 2], [0, 2, 3]], 1.0, Vec3::ONE)],
        Vec3::splat(0.5),
    );
    let frame = render(&with_edges(&scene, EdgeSelection::Outline), &RenderOptions::default()).unwrap();
    // Inside the square (its left side lies on a pixel boundary, so its own edge
    // blends nothing): untouched white.
    for y in 0..SIZE {
        for x in 30..SIZE {
            assert_eq!(frame.image.get(x, y), Vec3::ONE, "the hidden edge shows through at ({x}, {y})");
        }
    }
    assert!(frame.stats.edge_blends > 50, "the visible edges are still blended: {}", frame.stats.edge_blends);
}

/// A lit, finely tessellated sphere on a plane under perspective.
fn sphere_scene() -> Scene {
    let camera = Camera {
        eye: Vec3::new(0.3, 1.2, 3.5),
        target: Vec3::ZERO,
        up: Vec3::Y,
        near: 0.1,
        far: 50.0,
        projection: Projection::Perspective { fov_y_deg: 40.0 },
        shift: Vec2::ZERO,
    };
    let mut scene = common::scene_with(shapes::sphere(64), camera, 240, 180, false);
    scene.materials[0].kd = Vec3::new(0.2, 0.4, 0.9);
    scene
}

#[test]
fn a_smooth_sphere_keeps_its_interior_and_only_its_outline_changes() {
    let scene = sphere_scene();
    let aliased = render(&scene, &RenderOptions::default()).unwrap();
    let vb = &aliased.visibility;
    let (w, h) = (scene.width, scene.height);
    // Interior: the pixel and its 5 × 5 neighbourhood see the sphere.
    let interior = |x: u32, y: u32| {
        (x.saturating_sub(2)..(x + 3).min(w))
            .all(|i| (y.saturating_sub(2)..(y + 3).min(h)).all(|j| !vb.item(i, j).is_none()))
    };
    // The outline leaves the interior exactly alone; every edge (the paper) blends
    // each triangle edge into its neighbours: small, but it softens the shading.
    for (selection, limit) in [(EdgeSelection::Outline, 0.0), (EdgeSelection::All, 0.005)] {
        let edged = render(&with_edges(&scene, selection), &RenderOptions::default()).unwrap();
        let (mut sum, mut n, mut worst, mut changed_outline) = (0.0f64, 0, 0.0f32, 0);
        for y in 0..h {
            for x in 0..w {
                let d = (edged.image.get(x, y) - aliased.image.get(x, y)).abs().max_element();
                if interior(x, y) {
                    (sum, n, worst) = (sum + f64::from(d * d), n + 1, worst.max(d));
                } else if d > 0.0 {
                    changed_outline += 1;
                }
            }
        }
        let rms = (sum / f64::from(n)).sqrt();
        eprintln!(
            "{selection:?}: interior RMS change {rms:.5} (largest {worst}), {changed_outline} outline pixels changed"
        );
        assert!(rms <= limit, "{selection:?}: the tessellation shows inside the sphere ({rms})");
        assert!(changed_outline > 200, "{selection:?}: the outline is antialiased ({changed_outline})");
    }
}

#[test]
fn the_edge_pass_gives_the_same_frame_on_one_thread_and_two() {
    let scene = with_edges(&sphere_scene(), EdgeSelection::All);
    let frame = |threads| {
        let mut r = Renderer::new(&RenderOptions { threads: Some(threads), ..RenderOptions::default() }).unwrap();
        r.render(&scene).unwrap().image.clone()
    };
    assert_eq!(frame(1).pixels(), frame(2).pixels());
}

#[test]
fn the_edge_pass_gives_the_same_frame_whether_its_parts_are_recorded_first_or_not() {
    // Without fog the parts of the crossed pixels are coloured as the pixels
    // are blended; a fog of zero density changes no pixel, but makes the frame
    // record the parts' colours before fogging and blend after.
    let scene = with_edges(&sphere_scene(), EdgeSelection::Outline);
    let at_once = render(&scene, &RenderOptions::default()).unwrap();
    let fog = Fog { mode: FogMode::Exp { density: 0.0 }, color: Vec3::ONE };
    let recorded = render(&Scene { fog: Some(fog), ..scene.clone() }, &RenderOptions::default()).unwrap();
    assert!(at_once.stats.edge_blends > 200, "{} blends", at_once.stats.edge_blends);
    assert_eq!(at_once.image.pixels(), recorded.image.pixels());
}

/// RMSE over the pixels where the object seen changes within the 3 × 3
/// neighbourhood (silhouettes), against `truth`.
fn silhouette_rmse(image: &LinearImage, truth: &LinearImage, vb: &kage::visibility::VisibilityBuffer) -> f64 {
    let (w, h) = (vb.width() as i64, vb.height() as i64);
    let object = |x: i64, y: i64| vb.item(x.clamp(0, w - 1) as u32, y.clamp(0, h - 1) as u32).object;
    let (mut sum, mut n) = (0.0f64, 0usize);
    for y in 0..h {
        for x in 0..w {
            let o = object(x, y);
            if (-1..=1).all(|dy| (-1..=1).all(|dx| object(x + dx, y + dy) == o)) {
                continue;
            }
            let d = image.get(x as u32, y as u32) - truth.get(x as u32, y as u32);
            sum += f64::from(d.length_squared()) / 3.0;
            n += 1;
        }
    }
    (sum / n as f64).sqrt()
}

#[test]
fn the_edge_pass_brings_silhouettes_towards_a_supersampled_frame() {
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    (scene.width, scene.height) = (320, 180);
    let aliased = render(&Scene { antialias: Antialias::None, ..scene.clone() }, &RenderOptions::default()).unwrap();
    let edged = render(&with_edges(&scene, EdgeSelection::Outline), &RenderOptions::default()).unwrap();
    let truth =
        render(&Scene { antialias: Antialias::Jitter(64), ..scene.clone() }, &RenderOptions::default()).unwrap();
    let before = silhouette_rmse(&aliased.image, &truth.image, &aliased.visibility);
    let after = silhouette_rmse(&edged.image, &truth.image, &aliased.visibility);
    eprintln!("silhouette RMSE against 64 jittered passes: aliased {before:.4}, edge pass {after:.4}");
    assert!(after < 0.6 * before, "edge pass {after} vs aliased {before}");
}

/// The demo's teapot is two meshes, its lid sitting in the body's opening
/// with a gap far thinner than a pixel. Sampled once at each pixel centre the
/// gap shows as a row of dark pinholes along the lid (pixels darker than both
/// neighbours and than a 32-pass truth); the default render's edge pass blends
/// them away.
#[test]
fn the_teapots_lid_seam_shows_no_pinholes_by_default() {
    let scene = kage::scene::demo::demo_scene().unwrap();
    let teapot: Vec<u32> =
        (0..scene.objects.len() as u32).filter(|&i| scene.objects[i as usize].name.starts_with("teapot")).collect();
    assert_eq!(teapot.len(), 2, "the teapot's body and lid");
    let truth =
        render(&Scene { antialias: Antialias::Jitter(32), ..scene.clone() }, &RenderOptions::default()).unwrap().image;
    let pinholes = |antialias: Antialias| {
        let frame = render(&Scene { antialias, ..scene.clone() }, &RenderOptions::default()).unwrap();
        let lum = |im: &kage::image::LinearImage, x: u32, y: u32| im.get(x, y).dot(Vec3::new(0.2126, 0.7152, 0.0722));
        let mut count = 0;
        for y in 1..scene.height - 1 {
            for x in 1..scene.width - 1 {
                if !teapot.contains(&frame.visibility.item(x, y).object) {
                    continue;
                }
                let c = lum(&frame.image, x, y);
                let below = |a: (u32, u32), b: (u32, u32)| {
                    lum(&frame.image, a.0, a.1) - c > 0.08 && lum(&frame.image, b.0, b.1) - c > 0.08
                };
                let pit = below((x - 1, y), (x + 1, y)) || below((x, y - 1), (x, y + 1));
                count += usize::from(pit && lum(&truth, x, y) - c > 0.05);
            }
        }
        count
    };
    let (aliased, default) = (pinholes(Antialias::None), pinholes(Antialias::default()));
    assert!(aliased >= 20, "aliased, the seam shows pinholes: {aliased}");
    assert!(default <= 3, "the default render leaves {default} pinholes (aliased: {aliased})");
}
