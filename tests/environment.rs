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
    // Aliased: compared pixel centre for pixel centre with rays.
    scene.antialias = kage::scene::Antialias::None;
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

/// The reflection-map pass computes the reference's term: against 6 × 6 rays
/// a pixel, the mapped ball's pixels agree (the pass filters each pixel's
/// lookup over its spread of mirror directions, the reference averages rays).
#[test]
fn the_reflection_map_pass_matches_the_reference() {
    let mut scene = scene();
    scene.lights.iter_mut().for_each(|l| l.shadow = kage::scene::ShadowSettings::NONE);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let opts = ReferenceOptions {
        pixel_samples: 6,
        light_samples: 1,
        shadows: false,
        max_depth: 4,
        ..ReferenceOptions::default()
    };
    let truth = render_reference(&scene, &opts, &|_| {});
    // Pixels inside the reflection-mapped ball (object 1).
    let vb = &frame.visibility;
    let (mut agree, mut total) = (0, 0);
    for y in 1..scene.height - 1 {
        for x in 1..scene.width - 1 {
            let around = [(x, y), (x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)];
            if around.iter().any(|&(a, b)| vb.item(a, b).object != 1) {
                continue;
            }
            total += 1;
            agree += usize::from((frame.image.get(x, y) - truth.get(x, y)).abs().max_element() < 0.03);
        }
    }
    assert!(total > 1000 && agree * 100 >= total * 90, "{agree} of {total} mapped-ball pixels agree");
}

/// The reflection-mapped ball, seen small, against an 8 × 8-ray truth: its
/// pixels filtered over the spread of mirror directions come out closer to
/// the truth than one lookup at each pixel centre (which aliases the map's
/// checkered ground into moiré) — on the inside of the ball, where both see
/// only it, and the ball mirrors the ground.
#[test]
fn the_reflection_map_is_filtered_not_aliased() {
    let mut scene = scene();
    (scene.width, scene.height) = (160, 90);
    scene.lights.iter_mut().for_each(|l| l.shadow = kage::scene::ShadowSettings::NONE);
    // Only the mapped ball's reflection: no lights' share to compare.
    scene.lights.iter_mut().for_each(|l| (l.intensity, l.ambient) = (0.0, 0.0));
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let opts = ReferenceOptions {
        pixel_samples: 8,
        light_samples: 1,
        shadows: false,
        max_depth: 0,
        ..ReferenceOptions::default()
    };
    let truth = render_reference(&scene, &opts, &|_| {});
    let env = scene.environment.clone().unwrap();
    let frames = kage::shading::ObjectFrames::new(&scene);
    let rays = scene.camera.pixel_rays(Vec2::new(scene.width as f32, scene.height as f32));
    let vb = &frame.visibility;
    let (mut filtered, mut point, mut n) = (0.0f64, 0.0f64, 0);
    for y in 1..scene.height - 1 {
        for x in 1..scene.width - 1 {
            let item = vb.item(x, y);
            let around = [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)].map(|(a, b)| vb.item(a, b));
            if item.object != 1 || around.iter().any(|o| o.object != 1) {
                continue;
            }
            let s = frames.surface_at(&scene, vb, x, y, &rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)));
            let km = scene.materials[s.material].km;
            let mirror = 2.0 * s.normal.dot(s.to_eye) * s.normal - s.to_eye;
            if mirror.normalize().y > -0.2 {
                continue; // the sky and the horizon: smooth, or one edge
            }
            let centre = km * env.radiance(mirror);
            let t = truth.get(x, y);
            filtered += f64::from((frame.image.get(x, y) - t).length_squared());
            point += f64::from((centre - t).length_squared());
            n += 1;
        }
    }
    assert!(n > 300, "{n} ball pixels");
    let (filtered, point) = ((filtered / n as f64).sqrt(), (point / n as f64).sqrt());
    assert!(filtered < 0.4 * point, "RMSE against 64 rays a pixel: filtered {filtered:.4}, one lookup {point:.4}");
}
