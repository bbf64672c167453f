//! The environment map (seed 002 eq. 4's Mape): what the background shows, and the
//! reflection-map pass against the reference renderer's own reflection-map term.

use std::path::Path;

use glam::Vec2;
use kage::raytrace::reference::{render_reference, ReferenceOptions};
use kage::{render, RenderOptions};

fn scene() -> kage::Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/environment.toml");
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height) = (240, 135);
    scene
}

#[test]
fn pixels_that_see_nothing_show_the_environment_along_their_ray() {
    let scene = scene();
    let env = scene.environment.clone().expect("the example has an environment");
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let rays = scene.camera.pixel_rays(Vec2::new(scene.width as f32, scene.height as f32));
    let mut sky = 0;
    for y in 0..scene.height {
        for x in 0..scene.width {
            if frame.visibility.item(x, y).is_none() {
                let want = env.radiance(rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).dir);
                assert!((frame.image.get(x, y) - want).abs().max_element() < 1e-5, "({x}, {y})");
                sky += 1;
            }
        }
    }
    assert!(sky > 5000, "{sky} background pixels");
}

#[test]
fn the_reflection_map_pass_matches_the_reference() {
    let mut scene = scene();
    scene.lights.iter_mut().for_each(|l| l.shadow = kage::scene::ShadowSettings::NONE);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let opts = ReferenceOptions { pixel_samples: 1, light_samples: 1, shadows: false, max_depth: 4 };
    let truth = render_reference(&scene, &opts, &|_| {});
    // Pixels on the reflection-mapped ball (object 1), where both see the ball.
    let rays = scene.camera.pixel_rays(Vec2::new(scene.width as f32, scene.height as f32));
    let trace = kage::raytrace::TraceScene::new(&scene);
    let (mut agree, mut total) = (0, 0);
    for y in 0..scene.height {
        for x in 0..scene.width {
            let item = frame.visibility.item(x, y);
            let hit = trace.intersect(&rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)), f32::INFINITY);
            if item.object != 1 || hit.map(|h| h.item) != Some(item) {
                continue;
            }
            total += 1;
            agree += usize::from((frame.image.get(x, y) - truth.get(x, y)).abs().max_element() < 2e-3);
        }
    }
    assert!(total > 1000 && agree * 1000 >= total * 995, "{agree} of {total} mapped-ball pixels agree");
}
