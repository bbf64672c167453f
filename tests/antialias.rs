//! Jittered sub-pixel passes (seed 002 §4): a shifted camera moves the whole frame —
//! polygons, shading and traced rays — by exactly the shift, and averaging jittered
//! item buffers brings the traced image towards a supersampled ray-traced truth.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec2, Vec3};
use kage::compare::compare;
use kage::raytrace::reference::{render_reference, ReferenceOptions};
use kage::scene::mesh::shapes;
use kage::scene::{Antialias, Material, Object, Scene};
use kage::{render, RenderOptions};
use rand::rngs::StdRng;
use rand::SeedableRng;

/// Renders `scene` with its camera shifted by `pixels` (x right, y down).
fn shifted(scene: &Scene, pixels: Vec2) -> kage::frame::Frame {
    let mut s = scene.clone();
    s.camera.shift = Vec2::new(pixels.x, -pixels.y) * 2.0 / Vec2::new(s.width as f32, s.height as f32);
    render(&s, &RenderOptions::default()).expect("render")
}

#[test]
fn a_one_pixel_shift_moves_the_image_by_one_pixel() {
    let mut rng = StdRng::seed_from_u64(7);
    for ortho in [false, true] {
        let scene = common::scene_with(
            common::triangle_soup(&mut rng, 40),
            common::random_camera(&mut rng, ortho),
            160,
            120,
            true,
        );
        let plain = render(&scene, &RenderOptions::default()).expect("render");
        let (w, h) = (scene.width as usize, scene.height as usize);
        for (step, (dx, dy)) in [(Vec2::X, (1, 0)), (Vec2::Y, (0, 1))] {
            let moved = shifted(&scene, step);
            let (mut same, mut total) = (0, 0);
            for y in 0..h - dy {
                for x in 0..w - dx {
                    let a = moved.image.pixels()[y * w + x];
                    let b = plain.image.pixels()[(y + dy) * w + x + dx];
                    same += usize::from((a - b).abs().max_element() < 1e-3);
                    total += 1;
                }
            }
            let share = same as f64 / total as f64;
            assert!(share > 0.99, "ortho {ortho}, shift {step}: only {share:.4} of pixels moved along");
        }
    }
}

/// A mirror floor under an emissive ball and a lit ball: hard edges seen directly
/// and in the mirror.
fn mirror_scene() -> Scene {
    let mut rng = StdRng::seed_from_u64(3);
    let mut scene = common::scene_with(shapes::sphere(24), common::random_camera(&mut rng, false), 96, 72, false);
    scene.camera.eye = Vec3::new(0.0, 1.2, 4.0);
    scene.camera.target = Vec3::new(0.0, 0.2, 0.0);
    scene.camera.far = 100.0;
    // Compared with a reference without shadow rays.
    scene.lights[0].shadow = kage::scene::ShadowSettings::NONE;
    let mirror =
        Material { ka: Vec3::ZERO, kd: Vec3::splat(0.1), ks: Vec3::ZERO, kr: Vec3::splat(0.9), ..Material::default() };
    let glow = Material { ke: Vec3::new(1.0, 0.3, 0.1), ..Material::default() };
    scene.materials.extend([mirror, glow]);
    let floor = Affine3A::from_scale_rotation_translation(Vec3::splat(10.0), Quat::IDENTITY, Vec3::new(0.0, -0.6, 0.0));
    let ball = Affine3A::from_scale_rotation_translation(Vec3::splat(0.4), Quat::IDENTITY, Vec3::new(1.1, 0.0, 0.5));
    scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(0.6));
    scene.objects.push(Object::mesh("floor", Arc::new(shapes::plane()), floor, 1));
    scene.objects.push(Object::mesh("glow", Arc::new(shapes::sphere(24)), ball, 2));
    scene
}

#[test]
fn jittered_item_buffers_approach_the_supersampled_reference() {
    let mut scene = mirror_scene();
    let opts = ReferenceOptions {
        pixel_samples: 8,
        light_samples: 1,
        shadows: false,
        max_depth: 4,
        ..ReferenceOptions::default()
    };
    let truth = render_reference(&scene, &opts, &|_| {});
    let aliased = render(&scene, &RenderOptions::default()).expect("render");
    scene.antialias = Antialias::Jitter(16);
    let jittered = render(&scene, &RenderOptions::default()).expect("render");
    assert_eq!(jittered.stats.passes, 16);
    assert!(jittered.stats.traced_pixels > 16 * 500, "the mirror is traced in every pass");
    let e_aliased = compare(&aliased.image, &truth, 0.1).expect("same size");
    let e_jitter = compare(&jittered.image, &truth, 0.1).expect("same size");
    assert!(
        e_jitter.rmse < 0.4 * e_aliased.rmse && e_jitter.share_over < 0.25 * e_aliased.share_over,
        "jitter 16: rmse {:.4}, {:.4} over 0.1; aliased: rmse {:.4}, {:.4} over",
        e_jitter.rmse,
        e_jitter.share_over,
        e_aliased.rmse,
        e_aliased.share_over
    );
}
