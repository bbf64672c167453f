//! Item-buffer ray tracing (seed 002 §4) against analytic answers: a plane mirror
//! shows a sphere where its mirror image says, Snell's law bends rays, and total
//! internal reflection starts at the critical angle.

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::raytrace::reference::{render_reference, ReferenceOptions};
use kage::raytrace::tracer::refract;
use kage::scene::mesh::shapes;
use kage::scene::{Material, Object, Scene};
use kage::{render, RenderOptions};

#[test]
fn refraction_follows_snell_and_total_internal_reflection_starts_at_the_critical_angle() {
    let n = Vec3::Y;
    for deg in [0.0f32, 10.0, 30.0, 41.0, 41.9, 60.0] {
        let theta = deg.to_radians();
        let d = Vec3::new(theta.sin(), -theta.cos(), 0.0); // going down into the surface
                                                           // From glass (1.5) into air (1): critical angle asin(1/1.5) = 41.81°.
        let out = refract(d, n, 1.5);
        let critical = (1.0f32 / 1.5).asin();
        assert_eq!(out.is_none(), theta > critical, "{deg}°");
        if let Some(t) = out {
            assert!((t.x - 1.5 * theta.sin()).abs() < 1e-5, "sin θt = η sin θi at {deg}°");
        }
        // Into glass never reflects totally.
        assert!(refract(d, n, 1.0 / 1.5).is_some());
    }
}

fn mirror_scene() -> Scene {
    let mirror = Material { ka: Vec3::ZERO, kd: Vec3::ZERO, ks: Vec3::ZERO, kr: Vec3::ONE, ..Material::default() };
    let red = Material {
        ka: Vec3::ZERO,
        kd: Vec3::ZERO,
        ks: Vec3::ZERO,
        ke: Vec3::new(1.0, 0.0, 0.0),
        ..Material::default()
    };
    let plane = Affine3A::from_scale_rotation_translation(
        Vec3::splat(20.0),
        Quat::from_rotation_x(90f32.to_radians()),
        Vec3::ZERO,
    );
    let ball = Affine3A::from_scale_rotation_translation(Vec3::splat(0.3), Quat::IDENTITY, Vec3::new(1.0, 0.0, 2.0));
    Scene {
        width: 200,
        height: 150,
        background: Vec3::ZERO,
        exposure: Default::default(),
        antialias: Default::default(),
        fog: None,
        ambient_occlusion: None,
        lines: None,
        environment: None,
        translucency: Default::default(),
        tone: Default::default(),
        limits: Default::default(),
        camera_path: None,
        lights_follow_camera: false,
        camera: Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            near: 0.1,
            far: 100.0,
            projection: Projection::Perspective { fov_y_deg: 50.0 },
            shift: Vec2::ZERO,
        },
        lights: Vec::new(),
        materials: vec![mirror, red],
        objects: vec![
            Object::mesh("mirror", Arc::new(shapes::plane()), plane, 0),
            Object::mesh("ball", Arc::new(shapes::sphere(32)), ball, 1),
        ],
        warnings: Vec::new(),
    }
}

/// The pixel where world point `p` projects.
fn pixel_of(scene: &Scene, p: Vec3) -> (u32, u32) {
    let c = scene.camera.view_projection(scene.width as f32 / scene.height as f32) * p.extend(1.0);
    let ndc = Vec2::new(c.x / c.w, c.y / c.w);
    let x = (ndc.x * 0.5 + 0.5) * scene.width as f32;
    let y = (0.5 - ndc.y * 0.5) * scene.height as f32;
    (x as u32, y as u32)
}

#[test]
fn a_plane_mirror_shows_the_sphere_at_its_mirror_image() {
    let scene = mirror_scene();
    // Mirror image of the ball's centre (1, 0, 2) is (1, 0, −2); the eye ray to it
    // crosses the mirror (z = 0) at x = 5/7.
    let seen = pixel_of(&scene, Vec3::new(5.0 / 7.0, 0.0, 0.0));
    let opposite = pixel_of(&scene, Vec3::new(-5.0 / 7.0, 0.0, 0.0));
    let direct = pixel_of(&scene, Vec3::new(1.0, 0.0, 2.0));
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    assert!(frame.stats.traced_pixels > 10_000, "the mirror pixels are traced: {}", frame.stats.traced_pixels);
    let at = |(x, y): (u32, u32)| frame.image.get(x, y);
    assert_eq!(frame.visibility.item(seen.0, seen.1).object, 0, "the mirror is what the pixel sees");
    assert!(at(seen).x > 0.99 && at(seen).y < 0.01, "mirror image pixel {:?} = {}", seen, at(seen));
    assert!(at(opposite).max_element() < 0.01, "nothing to reflect at {:?}: {}", opposite, at(opposite));
    assert!(at(direct).x > 0.99, "the ball itself at {direct:?}");
    // The reference renderer agrees.
    let opts = ReferenceOptions {
        pixel_samples: 1,
        light_samples: 1,
        shadows: true,
        max_depth: 2,
        ..ReferenceOptions::default()
    };
    let reference = render_reference(&scene, &opts, &|_| {});
    assert!((reference.get(seen.0, seen.1) - at(seen)).abs().max_element() < 1e-3);
    assert!((reference.get(opposite.0, opposite.1) - at(opposite)).abs().max_element() < 1e-3);
    // Without bounces the mirror is black.
    let flat = render(&scene, &RenderOptions { ray_depth: 0, ..Default::default() }).unwrap();
    assert!(flat.image.get(seen.0, seen.1).max_element() < 0.01);
}

/// A renderer keeps its BVH while only the view changes, and a moved object is
/// seen in the mirror where a fresh renderer sees it (a stale BVH would show it at
/// its old place).
#[test]
fn the_bvh_is_kept_between_frames_until_the_geometry_moves() {
    let mut scene = mirror_scene();
    let mut renderer = kage::Renderer::new(&RenderOptions::default()).unwrap();
    assert!(renderer.render(&scene).unwrap().stats.bvh_built, "the first frame builds it");
    scene.camera.eye.x += 0.2;
    assert!(!renderer.render(&scene).unwrap().stats.bvh_built, "a new viewpoint keeps it");
    scene.objects[1].transform = Affine3A::from_translation(Vec3::new(-2.0, 0.0, 0.0)) * scene.objects[1].transform;
    let kept = renderer.render(&scene).unwrap();
    assert!(kept.stats.bvh_built, "a moved object rebuilds it");
    let fresh = render(&scene, &RenderOptions::default()).unwrap();
    assert_eq!(kept.image.pixels(), fresh.image.pixels(), "the reused renderer sees the moved ball");
    // Mirror image of the moved ball (−1, 0, 2) is where the eye ray crosses the
    // mirror at x = (−1 − 0.2)·5/7 + 0.2 (the eye is at x = 0.2).
    let seen = pixel_of(&scene, Vec3::new(-1.2 * 5.0 / 7.0 + 0.2, 0.0, 0.0));
    assert!(kept.image.get(seen.0, seen.1).x > 0.99, "moved ball's mirror image at {seen:?}");
}

/// A thin emissive vertical line at x = 0 behind (−z) a glass slab of thickness
/// `t` turned `deg` degrees about y, seen by an orthographic camera looking down −z.
fn slab_scene(deg: f32, t: f32) -> Scene {
    let glass =
        Material { ka: Vec3::ZERO, kd: Vec3::ZERO, ks: Vec3::ZERO, kt: Vec3::ONE, ior: 1.5, ..Material::default() };
    let line = Material { ka: Vec3::ZERO, kd: Vec3::ZERO, ks: Vec3::ZERO, ke: Vec3::X, ..Material::default() };
    let slab = Affine3A::from_scale_rotation_translation(
        Vec3::new(6.0, 6.0, t),
        Quat::from_rotation_y(deg.to_radians()),
        Vec3::ZERO,
    );
    let bar = Affine3A::from_scale_rotation_translation(
        Vec3::new(0.04, 4.0, 0.04),
        Quat::IDENTITY,
        Vec3::new(0.0, 0.0, -3.0),
    );
    let mut scene = mirror_scene();
    (scene.width, scene.height) = (400, 60);
    scene.camera = Camera {
        eye: Vec3::new(0.0, 0.0, 5.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        near: 0.1,
        far: 100.0,
        projection: Projection::Orthographic { height: 1.2 },
        shift: Vec2::ZERO,
    };
    scene.materials = vec![glass, line];
    scene.objects = vec![
        Object::mesh("slab", Arc::new(shapes::cube()), slab, 0),
        Object::mesh("line", Arc::new(shapes::cube()), bar, 1),
    ];
    scene
}

/// World x of the red line's centre on the middle row (intensity-weighted).
fn line_x(scene: &Scene, image: &kage::image::LinearImage) -> f32 {
    let (w, y) = (scene.width as usize, scene.height as usize / 2);
    let row = &image.pixels()[y * w..(y + 1) * w];
    let (sum, weight) = row.iter().enumerate().fold((0.0, 0.0), |(s, m), (x, p)| (s + p.x * (x as f32 + 0.5), m + p.x));
    assert!(weight > 0.5, "the line is visible through the slab");
    let pixel = 1.2 / scene.height as f32; // world units per pixel (orthographic)
    (sum / weight - w as f32 / 2.0) * pixel
}

#[test]
fn a_glass_slab_shifts_a_line_by_the_snell_offset() {
    let t = 0.8;
    for deg in [0.0f32, 20.0, 40.0, 60.0] {
        // 16 samples per pixel put the line's centre to a fraction of a pixel.
        let mut scene = slab_scene(deg, t);
        scene.antialias = kage::scene::Antialias::Jitter(16);
        // Lateral displacement of a ray crossing a parallel slab: t·sin(θi − θt)/cos θt.
        let (ti, tt) = (deg.to_radians(), (deg.to_radians().sin() / 1.5).asin());
        let expected = t * (ti - tt).sin() / tt.cos();
        let raster = render(&scene, &RenderOptions::default()).expect("render");
        let opts = ReferenceOptions {
            pixel_samples: 4,
            light_samples: 1,
            shadows: false,
            max_depth: 4,
            ..ReferenceOptions::default()
        };
        let traced = render_reference(&scene, &opts, &|_| {});
        for (what, image) in [("item buffer", &raster.image), ("reference", &traced)] {
            let x = line_x(&scene, image);
            // Turning the slab about +y tilts its normal towards +x; inside, the ray
            // bends towards −normal, i.e. to −x, so the eye ray that reaches the
            // line at x = 0 started at +offset: the line is seen moved to +x.
            assert!(
                (x - expected).abs() < 0.2 * 1.2 / 60.0,
                "{what} at {deg}°: line at x = {x}, Snell says {expected}"
            );
        }
    }
}

/// What a mirror shows is antialiased where it has edges: inside the chrome
/// ball of `reflections.toml` (away from its outline, which the edge pass
/// handles), the default frame — traced pixels that differ from a neighbour
/// traced again at four sub-pixel points — is much closer to a supersampled
/// ray-traced truth than the aliased frame's one sample per pixel.
#[test]
fn reflections_are_refined_where_what_they_show_has_edges() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/reflections.toml");
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height) = (320, 180);
    let ball = scene.objects.iter().position(|o| o.name == "chrome ball").expect("the scene has a chrome ball") as u32;
    let opts = ReferenceOptions { pixel_samples: 4, light_samples: 2, ..ReferenceOptions::default() };
    let truth = render_reference(&scene, &opts, &|_| {});
    let frame = |antialias| {
        let mut s = scene.clone();
        s.antialias = antialias;
        render(&s, &RenderOptions::default()).unwrap()
    };
    let (aliased, default) = (frame(kage::scene::Antialias::None), frame(kage::scene::Antialias::default()));
    assert_eq!(aliased.stats.traced_refined, 0);
    assert!(default.stats.traced_refined > 50, "{} pixels refined", default.stats.traced_refined);
    let vb = &aliased.visibility;
    let inside = |x: u32, y: u32| {
        (x.saturating_sub(1)..=(x + 1).min(319)).all(|i| {
            (y.saturating_sub(1)..=(y + 1).min(179)).all(|j| vb.item(i, j).object == ball && !vb.item(i, j).is_none())
        })
    };
    let pixels: Vec<(u32, u32)> =
        (0..180).flat_map(|y| (0..320).map(move |x| (x, y))).filter(|&(x, y)| inside(x, y)).collect();
    assert!(pixels.len() > 1000, "the ball's inside covers {} pixels", pixels.len());
    let rmse = |image: &kage::image::LinearImage| {
        let sum: f32 = pixels.iter().map(|&(x, y)| (image.get(x, y) - truth.get(x, y)).length_squared()).sum();
        (sum / pixels.len() as f32).sqrt()
    };
    let (a, d) = (rmse(&aliased.image), rmse(&default.image));
    assert!(d < 0.75 * a, "inside the chrome ball: refined rmse {d:.4}, aliased {a:.4}");
}

/// The quick frames' traced term ([`RenderOptions::sparse_traced`]): a
/// mirror that reflects one colour is the same traced at a quarter of its
/// pixels, and on `reflections.toml` a quarter of the rays give an image
/// close to the one traced at every pixel (measured: RMSE 0.026 between
/// them) and almost as close to the truth (0.029 against 0.025).
#[test]
fn a_sparse_traced_term_traces_fewer_rays_for_nearly_the_same_image() {
    let sparse = RenderOptions { sparse_traced: true, ..RenderOptions::default() };
    let mut scene = mirror_scene();
    (scene.background, scene.antialias) = (Vec3::new(0.2, 0.4, 0.6), kage::scene::Antialias::None);
    scene.objects.pop();
    let (all, few) = (render(&scene, &RenderOptions::default()).unwrap(), render(&scene, &sparse).unwrap());
    assert!(
        few.stats.traced_pixels * 3 < all.stats.traced_pixels,
        "{} of {}",
        few.stats.traced_pixels,
        all.stats.traced_pixels
    );
    for (a, b) in all.image.pixels().iter().zip(few.image.pixels()) {
        assert!((*a - *b).abs().max_element() < 1e-5, "{a} vs {b}");
    }

    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/reflections.toml");
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height, scene.antialias) = (320, 180, kage::scene::Antialias::None);
    let opts = ReferenceOptions { pixel_samples: 4, light_samples: 2, ..ReferenceOptions::default() };
    let truth = render_reference(&scene, &opts, &|_| {});
    let (all, few) = (render(&scene, &RenderOptions::default()).unwrap(), render(&scene, &sparse).unwrap());
    let rmse = |a: &kage::image::LinearImage, b: &kage::image::LinearImage| {
        let sum: f32 = a.pixels().iter().zip(b.pixels()).map(|(p, q)| (*p - *q).length_squared()).sum();
        (sum / a.pixels().len() as f32).sqrt()
    };
    let (ratio, apart) =
        (few.stats.traced_pixels as f32 / all.stats.traced_pixels as f32, rmse(&all.image, &few.image));
    let (to_truth_all, to_truth_few) = (rmse(&all.image, &truth), rmse(&few.image, &truth));
    eprintln!("rays {ratio:.3}; apart {apart:.4}; truth: all {to_truth_all:.4}, sparse {to_truth_few:.4}");
    assert!(ratio < 0.4, "{ratio} of the rays");
    assert!(apart < 0.03, "RMSE {apart} between the two");
    assert!(to_truth_few < 1.25 * to_truth_all, "to the truth: sparse {to_truth_few}, every pixel {to_truth_all}");
}
