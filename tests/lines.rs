//! Feature lines against the geometry they draw, projected here by hand: a
//! cube seen from a corner has every pixel along its silhouette and its three
//! visible creases drawn (as a mesh and as a CSG solid), its three hidden
//! edges only when hidden lines are asked for (dashed, fainter); a smooth
//! sphere has its rim drawn and nothing inside it.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::csg::{ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Shape};
use kage::scene::mesh::shapes;
use kage::scene::{Antialias, Body, FeatureLines, Mesh, Object, Scene};
use kage::{render, RenderOptions};
use rand::rngs::StdRng;
use rand::SeedableRng;

/// Pixels across the image (square).
const SIZE: u32 = 200;
/// World units across the view's height.
const VIEW: f32 = 2.0;

/// `mesh` seen in parallel projection along `-dir`, no antialiasing; black
/// lines when `lines` says.
fn view(mesh: Mesh, dir: Vec3, lines: Option<FeatureLines>) -> Scene {
    let mut rng = StdRng::seed_from_u64(5);
    let mut scene = common::scene_with(mesh, common::random_camera(&mut rng, true), SIZE, SIZE, false);
    scene.camera = Camera {
        eye: dir.normalize() * 5.0,
        target: Vec3::ZERO,
        up: Vec3::Y,
        near: 0.1,
        far: 20.0,
        projection: Projection::Orthographic { height: VIEW },
        ..scene.camera
    };
    scene.antialias = Antialias::None;
    scene.lines = lines.map(|l| FeatureLines { colour: Vec3::ZERO, ..l });
    scene
}

/// The same cube as a CSG solid.
fn solid_cube(scene: &mut Scene) {
    let cube = Primitive {
        shape: Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
        transform: Affine3A::from_translation(Vec3::splat(-0.5)),
        color: None,
        source: 0..0,
    };
    let solid = CsgSolid { primitives: vec![cube], tree: Some(CsgTree::Leaf(0)) };
    scene.objects[0] =
        Object { body: Body::Solid { solid: Arc::new(solid), materials: Arc::from([0]) }, ..scene.objects[0].clone() };
}

/// A world point's place on the screen (pixels, centres at +0.5), by the
/// parallel projection's own basis.
fn project(camera: &Camera, p: Vec3) -> Vec2 {
    let forward = (camera.target - camera.eye).normalize();
    let right = forward.cross(camera.up).normalize();
    let up = right.cross(forward);
    let scale = SIZE as f32 / VIEW;
    Vec2::new(SIZE as f32 * 0.5 + p.dot(right) * scale, SIZE as f32 * 0.5 - p.dot(up) * scale)
}

/// Luminance of each pixel of the image.
fn luminance(scene: &Scene) -> Vec<f32> {
    let frame = render(scene, &RenderOptions::default()).expect("render");
    frame.image.pixels().iter().map(|c| c.dot(Vec3::new(0.2126, 0.7152, 0.0722))).collect()
}

/// How far each pixel moved towards black: 1 − with / without.
fn darkening(with: &[f32], without: &[f32]) -> Vec<f32> {
    with.iter().zip(without).map(|(w, o)| if *o > 0.0 { 1.0 - w / o } else { 0.0 }).collect()
}

fn distance_to_segment(p: Vec2, a: Vec2, b: Vec2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (p - (a + ab * t)).length()
}

/// The pixels whose centre lies within `reach` of segment `a`–`b`, taking
/// only the middle of it (`from..to` of its length).
fn pixels_along(a: Vec2, b: Vec2, reach: f32, (from, to): (f32, f32)) -> Vec<usize> {
    let (a, b) = (a.lerp(b, from), a.lerp(b, to));
    (0..SIZE * SIZE)
        .filter(|&i| {
            let centre = Vec2::new((i % SIZE) as f32 + 0.5, (i / SIZE) as f32 + 0.5);
            distance_to_segment(centre, a, b) <= reach
        })
        .map(|i| i as usize)
        .collect()
}

/// The convex hull of `points` (counter-clockwise on screen is not needed:
/// only its edges are).
fn hull(mut points: Vec<Vec2>) -> Vec<Vec2> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let half = |points: &mut dyn Iterator<Item = Vec2>| {
        let mut out: Vec<Vec2> = Vec::new();
        for p in points {
            while out.len() >= 2 && cross(out[out.len() - 2], out[out.len() - 1], p) <= 1e-6 {
                out.pop();
            }
            out.push(p);
        }
        out.pop();
        out
    };
    let mut lower = half(&mut points.clone().into_iter());
    lower.extend(half(&mut points.into_iter().rev()));
    lower
}

/// The cube's corners (side 1, centred), the one towards `dir` and the one away.
fn corners() -> Vec<Vec3> {
    (0..8).map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32) - 0.5).collect()
}

const CORNER: Vec3 = Vec3::new(1.0, 0.8, 0.6);

/// A line on the screen, from one end to the other.
type Segment = (Vec2, Vec2);

/// The cube's visible lines from `CORNER` on the screen: its silhouette (a
/// hexagon) and the three creases from the corner nearest the eye.
fn cube_lines(camera: &Camera) -> (Vec<Segment>, Vec<Segment>) {
    let outline = hull(corners().iter().map(|&c| project(camera, c)).collect());
    let sides = (0..outline.len()).map(|i| (outline[i], outline[(i + 1) % outline.len()])).collect();
    let front = Vec3::splat(0.5);
    let creases = [Vec3::X, Vec3::Y, Vec3::Z]
        .iter()
        .map(|&axis| (project(camera, front), project(camera, front - axis)))
        .collect();
    (sides, creases)
}

/// Whether pixel `i`'s centre lies farther than `reach` from every segment.
fn away_from(i: usize, segments: &[(Vec2, Vec2)], reach: f32) -> bool {
    let centre = Vec2::new((i as u32 % SIZE) as f32 + 0.5, (i as u32 / SIZE) as f32 + 0.5);
    segments.iter().all(|&(a, b)| distance_to_segment(centre, a, b) > reach)
}

#[test]
fn every_silhouette_and_crease_pixel_of_a_cube_seen_from_a_corner_is_drawn() {
    for solid in [false, true] {
        let mut plain = view(shapes::cube(), CORNER, None);
        let mut lined = view(shapes::cube(), CORNER, Some(FeatureLines::default()));
        if solid {
            solid_cube(&mut plain);
            solid_cube(&mut lined);
        }
        let moved = darkening(&luminance(&lined), &luminance(&plain));
        let (sides, creases) = cube_lines(&plain.camera);
        assert_eq!(sides.len(), 6, "a cube from a corner: a hexagon");
        for (what, segments) in [("silhouette", &sides), ("crease", &creases)] {
            let pixels: Vec<usize> = segments.iter().flat_map(|&(a, b)| pixels_along(a, b, 0.5, (0.1, 0.9))).collect();
            assert!(pixels.len() > 100, "{what}: {} pixels", pixels.len());
            let faint: Vec<&usize> = pixels.iter().filter(|&&i| moved[i] < 0.5).collect();
            assert!(
                faint.is_empty(),
                "solid {solid}: {} of {} {what} pixels darkened less than half, e.g. {:?}",
                faint.len(),
                pixels.len(),
                faint.iter().take(5).map(|&&i| (i as u32 % SIZE, i as u32 / SIZE, moved[i])).collect::<Vec<_>>()
            );
        }
        // Far from every line (inside the faces) nothing changes.
        let all: Vec<(Vec2, Vec2)> = sides.iter().chain(&creases).copied().collect();
        let touched = (0..(SIZE * SIZE) as usize).filter(|&i| away_from(i, &all, 3.0) && moved[i] != 0.0).count();
        assert_eq!(touched, 0, "solid {solid}: pixels away from the lines drawn on");
    }
}

#[test]
fn a_cubes_hidden_edges_are_drawn_dashed_only_when_asked_for() {
    let plain = luminance(&view(shapes::cube(), CORNER, None));
    let shown = darkening(&luminance(&view(shapes::cube(), CORNER, Some(FeatureLines::default()))), &plain);
    let hidden_lines = FeatureLines { hidden: true, ..FeatureLines::default() };
    let dashed = darkening(&luminance(&view(shapes::cube(), CORNER, Some(hidden_lines))), &plain);
    let camera = view(shapes::cube(), CORNER, None).camera;
    let (sides, creases) = cube_lines(&camera);
    let shown_lines: Vec<(Vec2, Vec2)> = sides.into_iter().chain(creases).collect();
    let back = Vec3::splat(-0.5);
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        let (a, b) = (project(&camera, back), project(&camera, back + axis));
        // Where a hidden edge passes under a shown line, that line is drawn.
        let pixels: Vec<usize> =
            pixels_along(a, b, 0.5, (0.2, 0.8)).into_iter().filter(|&i| away_from(i, &shown_lines, 3.0)).collect();
        assert!(pixels.len() > 20);
        let wrong: Vec<(u32, u32, f32)> = pixels
            .iter()
            .filter(|&&i| shown[i] != 0.0)
            .map(|&i| (i as u32 % SIZE, i as u32 / SIZE, shown[i]))
            .collect();
        assert!(wrong.is_empty(), "hidden edge {axis} drawn without hidden lines: {wrong:?} of {a} {b}");
        let drawn = pixels.iter().filter(|&&i| dashed[i] > 0.2).count() as f32 / pixels.len() as f32;
        assert!((0.3..0.9).contains(&drawn), "hidden edge {axis}: dashes cover {drawn} of it");
        let darkest = pixels.iter().map(|&i| dashed[i]).fold(0.0, f32::max);
        assert!(darkest < 0.75, "hidden lines are fainter than shown ones: {darkest}");
    }
}

#[test]
fn a_smooth_sphere_has_its_rim_drawn_and_no_line_inside() {
    let plain = view(shapes::sphere(48), Vec3::new(0.3, 0.4, 1.0), None);
    let lined = view(shapes::sphere(48), Vec3::new(0.3, 0.4, 1.0), Some(FeatureLines::default()));
    let moved = darkening(&luminance(&lined), &luminance(&plain));
    let centre = Vec2::splat(SIZE as f32 * 0.5);
    let radius = SIZE as f32 / VIEW;
    let at = |i: usize| (Vec2::new((i as u32 % SIZE) as f32 + 0.5, (i as u32 / SIZE) as f32 + 0.5) - centre).length();
    let inside = (0..moved.len()).filter(|&i| at(i) < radius - 3.0);
    assert_eq!(inside.filter(|&i| moved[i] != 0.0).count(), 0, "a line inside the smooth sphere");
    // The rim: every pixel within half a pixel of the true circle (a 48-stack
    // sphere's outline lies within 0.05 of it, a third of a pixel).
    let rim: Vec<usize> = (0..moved.len()).filter(|&i| (at(i) - radius).abs() <= 0.5).collect();
    assert!(rim.len() > 500);
    let faint = rim.iter().filter(|&&i| moved[i] < 0.4).count();
    assert_eq!(faint, 0, "{faint} of {} rim pixels darkened less than 40%", rim.len());
}

#[test]
fn a_scene_files_lines_table_sets_them_and_a_bad_width_says_where() {
    use kage::scene::file::SceneFile;
    use kage::scene::load::FileSystem;
    let fs = FileSystem { base: std::env::temp_dir() };
    let load = |text: &str| SceneFile::parse(text, std::path::Path::new("lines.toml")).and_then(|f| f.build(&fs));
    let text = "[[object]]\nshape = \"cube\"\n\n[lines]\nwidth = 2.5\ncolor = [0.5, 0, 0]\nhidden = true\n";
    let lines = load(text).expect("loads").lines.expect("lines");
    assert_eq!(lines, FeatureLines { width: 2.5, colour: Vec3::new(0.5, 0.0, 0.0), hidden: true, crease_deg: 30.0 });
    let defaults = load("[[object]]\nshape = \"cube\"\n\n[lines]\n").expect("loads").lines;
    assert_eq!(defaults, Some(FeatureLines::default()));
    assert_eq!(load("[[object]]\nshape = \"cube\"\n").expect("loads").lines, None);
    let e = load("[[object]]\nshape = \"cube\"\n\n[lines]\nwidth = 40\n").expect_err("refused");
    assert!(e.to_string().starts_with("lines.toml:4:") && e.to_string().contains("width"), "{e}");
}
