//! Item-buffer ray tracing (seed 002 §4) against analytic answers: a plane mirror
//! shows a sphere where its mirror image says, Snell's law bends rays, and total
//! internal reflection starts at the critical angle.

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec2, Vec3};
use kage::raytrace::reference::{refract, render_reference, ReferenceOptions};
use kage::scene::mesh::shapes;
use kage::scene::{Camera, Material, Object, Projection, Scene};
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
        camera: Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            near: 0.1,
            far: 100.0,
            projection: Projection::Perspective { fov_y_deg: 50.0 },
        },
        lights: Vec::new(),
        materials: vec![mirror, red],
        objects: vec![
            Object { name: "mirror".into(), mesh: Arc::new(shapes::plane()), transform: plane, material: 0 },
            Object { name: "ball".into(), mesh: Arc::new(shapes::sphere(32)), transform: ball, material: 1 },
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
    let opts = ReferenceOptions { pixel_samples: 1, light_samples: 1, shadows: true, max_depth: 2 };
    let reference = render_reference(&scene, &opts, &|_| {});
    assert!((reference.get(seen.0, seen.1) - at(seen)).abs().max_element() < 1e-3);
    assert!((reference.get(opposite.0, opposite.1) - at(opposite)).abs().max_element() < 1e-3);
    // Without bounces the mirror is black.
    let flat = render(&scene, &RenderOptions { ray_depth: 0, ..Default::default() }).unwrap();
    assert!(flat.image.get(seen.0, seen.1).max_element() < 0.01);
}
