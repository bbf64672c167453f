//! The ray-traced reference against the raster pipeline: with one ray per pixel
//! and no shadows they compute the same thing, so on every pixel whose primary hit
//! agrees the colours must agree; shadows only ever darken.

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
    let opts = ReferenceOptions { pixel_samples: 1, light_samples: 1, shadows: false, max_depth: 0 };
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

#[test]
fn shadows_only_darken_and_antialiasing_stays_close() {
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    scene.width = 120;
    scene.height = 68;
    let plain = render_reference(
        &scene,
        &ReferenceOptions { pixel_samples: 1, light_samples: 1, shadows: false, max_depth: 0 },
        &|_| {},
    );
    let shadowed = render_reference(
        &scene,
        &ReferenceOptions { pixel_samples: 1, light_samples: 3, shadows: true, max_depth: 0 },
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
        &ReferenceOptions { pixel_samples: 3, light_samples: 1, shadows: false, max_depth: 0 },
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
    let opts = ReferenceOptions { pixel_samples: 1, light_samples: 1, shadows: false, max_depth: 0 };
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
