//! The ray-traced reference against the raster pipeline: with one ray per pixel
//! and no shadows they compute the same thing, so on every pixel whose primary hit
//! agrees the colours must agree; shadows only ever darken.

#[path = "common/skip.rs"]
mod skip;

use kage::camera::Ray;
use kage::image::LinearImage;
use kage::raytrace::reference::{render_reference, ReferenceOptions};
use kage::raytrace::TraceScene;
use kage::scene::ShadowSettings;
use kage::{render, RenderOptions};

#[test]
fn one_ray_per_pixel_without_shadows_matches_the_rasterizer() {
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    scene.width = 240;
    scene.height = 135;
    scene.antialias = kage::scene::Antialias::None; // one ray per pixel centre, as the reference
    scene.lights.iter_mut().for_each(|l| l.shadow = ShadowSettings::NONE);
    // The reference filters textures by supersampling, so it reads the finest
    // level; so does the rasterizer with bilinear filtering.
    scene.materials.iter_mut().for_each(|m| m.maps.filter = kage::scene::material::Filter::Bilinear);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let mut scalar = LinearImage::new(scene.width, scene.height);
    kage::shading::shade_into_scalar(&scene, &frame.visibility, &mut scalar);
    let opts = ReferenceOptions::CENTRES;
    let reference = render_reference(&scene, &opts, &|_| {});
    let trace = TraceScene::new(&scene);
    let rays = scene.camera.pixel_rays(glam::Vec2::new(scene.width as f32, scene.height as f32));
    let (mut agree, mut differ) = (0, 0);
    for y in 0..scene.height {
        for x in 0..scene.width {
            let ray: Ray = rays.ray(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let hit = trace.intersect(&ray, f32::INFINITY).map(|h| h.item);
            let item = frame.visibility.item(x, y);
            if hit.unwrap_or(kage::visibility::ItemId::NONE) != item {
                differ += 1;
                continue;
            }
            agree += 1;
            let (r, s, f) = (reference.get(x, y), scalar.get(x, y), frame.image.get(x, y));
            assert!((r - s).abs().max_element() < 1e-5, "({x}, {y}): reference {r} vs scalar raster {s}");
            assert!((r - f).abs().max_element() < 2e-3, "({x}, {y}): reference {r} vs raster {f}");
        }
    }
    assert!(differ * 200 < agree, "{differ} pixels see a different item than the ray ({agree} agree)");
}

/// A single-sided wall seen from behind is culled by the eye's pass; the
/// reference's rays pass through it too, so both show what lies beyond (a
/// room's near wall seen from outside).
#[test]
fn rays_pass_back_faces_the_rasterizer_culls() {
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    (scene.width, scene.height) = (96, 54);
    scene.antialias = kage::scene::Antialias::None;
    scene.lights.iter_mut().for_each(|l| l.shadow = ShadowSettings::NONE);
    scene.materials.iter_mut().for_each(|m| m.maps.filter = kage::scene::material::Filter::Bilinear);
    let cam = scene.camera;
    let dir = (cam.target - cam.eye).normalize();
    // Facing away from the eye (its +y along the view), filling the view.
    let place = glam::Affine3A::from_scale_rotation_translation(
        glam::Vec3::splat(100.0),
        glam::Quat::from_rotation_arc(glam::Vec3::Y, dir),
        cam.eye + dir * 0.2 * (cam.target - cam.eye).length(),
    );
    let material = scene.materials.len();
    scene.materials.push(kage::scene::Material { two_sided: false, ..kage::scene::Material::default() });
    let wall = std::sync::Arc::new(kage::scene::mesh::shapes::plane());
    scene.objects.push(kage::scene::Object::mesh("wall", wall, place, material));
    let raster = render(&scene, &RenderOptions::default()).unwrap().image;
    let opts = ReferenceOptions::CENTRES;
    let reference = render_reference(&scene, &opts, &|_| {});
    let c = kage::compare::compare(&raster, &reference, 0.05).unwrap();
    assert!(c.share_over < 0.02, "the reference sees the wall's back the raster culls: {c:?}");
}

#[test]
fn shadows_only_darken_and_antialiasing_stays_close() {
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    scene.width = 120;
    scene.height = 68;
    let plain = render_reference(&scene, &ReferenceOptions::CENTRES, &|_| {});
    let shadowed = render_reference(
        &scene,
        &ReferenceOptions {
            pixel_samples: 1,
            light_samples: 3,
            shadows: true,
            max_depth: 0,
            ..ReferenceOptions::default()
        },
        &|_| {},
    );
    let mut darker = 0;
    for (p, s) in plain.pixels().iter().zip(shadowed.pixels()) {
        assert!(s.cmple(*p + glam::Vec3::splat(1e-5)).all(), "shadowed {s} brighter than unshadowed {p}");
        darker += usize::from((*p - *s).max_element() > 0.02);
    }
    assert!(darker > 200, "the demo's objects must cast visible shadows ({darker} pixels)");
    let aa = render_reference(
        &scene,
        &ReferenceOptions {
            pixel_samples: 3,
            light_samples: 1,
            shadows: false,
            max_depth: 0,
            ..ReferenceOptions::default()
        },
        &|_| {},
    );
    let c = kage::compare::compare(&aa, &plain, 0.05).unwrap();
    assert!(c.rmse < 0.05 && c.share_over < 0.2, "{c:?}");
}

#[test]
fn an_interrupted_reference_keeps_the_rows_already_traced() {
    use kage::raytrace::reference::render_reference_until;
    use std::sync::atomic::{AtomicBool, Ordering};
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    scene.width = 64;
    scene.height = 48;
    let opts = ReferenceOptions::CENTRES;
    let full = render_reference(&scene, &opts, &|_| {});
    let stop = AtomicBool::new(false);
    // Stop after ten rows have been reported finished.
    let (partial, rows) = render_reference_until(&scene, &opts, &|n| stop.store(n >= 10, Ordering::Relaxed), &stop);
    assert!((10..48).contains(&rows), "{rows} rows");
    let finished: Vec<u32> = (0..48).filter(|&y| partial.get(0, y) != glam::Vec3::ZERO).collect();
    assert_eq!(finished.len(), rows as usize, "every traced row is kept, the others are black");
    for &y in &finished {
        for x in 0..64 {
            assert_eq!(partial.get(x, y), full.get(x, y));
        }
    }
}

/// The scenes the reference is held to: the demo, every example scene, and
/// models framed and lit by kage's defaults (a plain STL part, the same part as
/// CSG, and the Cornell box, a room seen through its open side).
fn reference_cases() -> Vec<(String, kage::Scene)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut scenes: Vec<(String, kage::Scene)> = vec![("demo".into(), kage::scene::demo::demo_scene().unwrap())];
    let mut paths: Vec<_> =
        std::fs::read_dir(root.join("examples/scenes")).unwrap().map(|e| e.unwrap().path()).collect();
    paths.sort();
    for path in paths.into_iter().filter(|p| p.extension().is_some_and(|e| e == "toml")) {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        scenes.push((name, kage::scene::file::load_scene(&path).unwrap()));
    }
    let mut models = vec![
        root.join("tests/data/csg/ex004_cube_minus_sphere.stl"),
        root.join("tests/data/csg/ex004_cube_minus_sphere.csg"),
    ];
    models.extend(skip::asset("scenes/cornell-box/CornellBox-Original.obj"));
    for path in models {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        scenes.push((name, kage::scene::model::scene_for_model(&path, 128, 72).unwrap()));
    }
    scenes
}

/// Most RMSE (linear values clipped to [0, 1]) each case's raster frame may
/// stand from its reference at 128 × 72: about 1.5 × what it measures, where
/// the reference's own noise (4 × 4 rays a pixel, 4 × 4 per area light) and
/// the raster's shadow maps (texels, four jittered maps for a sized key light)
/// are what is left. A scene the two render differently (an unshadowed light
/// shadowed by one of them, fog on one side only, a wall culled by one) lies
/// far outside: 0.07–0.2.
const REFERENCE_RMSE: &[(&str, f64)] = &[
    ("demo", 0.022),
    ("atrium", 0.022),
    ("cad-ortho", 0.012),
    ("csg", 0.011),
    ("environment", 0.015),
    ("fog", 0.006),
    ("glass", 0.008),
    ("heatsink", 0.017),
    ("reflections", 0.010),
    ("showroom", 0.011),
    ("soft-shadows", 0.012),
    ("spotlights", 0.010),
    ("ex004_cube_minus_sphere.stl", 0.016),
    ("ex004_cube_minus_sphere.csg", 0.016),
    ("CornellBox-Original.obj", 0.025),
];

/// Every scene of [`reference_cases`], small: the reference against the raster
/// pipeline's `jitter:16` (16 jittered passes, the product's own shadows), each
/// within its bound in [`REFERENCE_RMSE`].
#[test]
fn every_example_scene_renders_as_its_reference() {
    let clip = |im: &LinearImage| {
        let mut out = im.clone();
        out.pixels_mut().iter_mut().for_each(|p| *p = p.clamp(glam::Vec3::ZERO, glam::Vec3::ONE));
        out
    };
    let mut failed = Vec::new();
    for (name, mut scene) in reference_cases() {
        let bound = REFERENCE_RMSE.iter().find(|(n, _)| *n == name).map(|b| b.1);
        let bound = bound.unwrap_or_else(|| panic!("{name}: no bound in REFERENCE_RMSE for this example scene"));
        let aspect = scene.width as f32 / scene.height as f32;
        scene.height = 72;
        scene.width = (72.0 * aspect).round() as u32;
        scene.antialias = kage::scene::Antialias::Jitter(16);
        let raster = render(&scene, &RenderOptions::default()).unwrap().image;
        let opts = ReferenceOptions {
            pixel_samples: 4,
            light_samples: 4,
            shadows: true,
            max_depth: 4,
            ..ReferenceOptions::default()
        };
        let reference = render_reference(&scene, &opts, &|_| {});
        let c = kage::compare::compare(&clip(&raster), &clip(&reference), 0.05).unwrap();
        println!("{name:<28} rmse {:.4} (bound {bound}), {:.1}% of pixels off by > 0.05", c.rmse, 100.0 * c.share_over);
        if c.rmse > bound {
            failed.push(format!("{name}: rmse {:.4} > {bound}", c.rmse));
        }
    }
    assert!(failed.is_empty(), "the raster frame strays from its reference: {failed:?}");
}
