//! Translucency (seed 002 §3.4) against the blending equation worked by hand:
//! layers of emissive translucent quads over an emissive opaque wall.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::scene::mesh::shapes;
use kage::scene::{Material, Object, Scene, TranslucencyOrder};
use kage::shading::{Component, ComponentSet};
use kage::{render, RenderOptions};

/// An emissive material of colour `e` and opacity `alpha`, unlit by anything else.
fn glow(e: Vec3, alpha: f32) -> Material {
    Material { ka: Vec3::ZERO, kd: Vec3::ZERO, ks: Vec3::ZERO, ke: e, opacity: alpha, ..Material::default() }
}

/// A square facing +z at depth `z`, `size` wide, turned `tilt` degrees about y.
fn quad(name: &str, z: f32, size: f32, tilt: f32, material: usize) -> Object {
    let turn = Quat::from_rotation_y(tilt.to_radians()) * Quat::from_rotation_x(90f32.to_radians());
    let transform = Affine3A::from_scale_rotation_translation(Vec3::splat(size), turn, Vec3::new(0.0, 0.0, z));
    Object::mesh(name, Arc::new(shapes::plane()), transform, material)
}

/// An orthographic view down −z of a red opaque wall at z = −2 and the given quads.
fn layered(materials: Vec<Material>, quads: Vec<Object>) -> Scene {
    let camera = Camera {
        eye: Vec3::new(0.0, 0.0, 5.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        near: 0.1,
        far: 20.0,
        projection: Projection::Orthographic { height: 2.0 },
        shift: Vec2::ZERO,
    };
    let mut scene = common::scene_with(shapes::plane(), camera, 64, 64, true);
    scene.lights.clear();
    scene.materials = vec![glow(Vec3::new(1.0, 0.0, 0.0), 1.0)];
    scene.materials.extend(materials);
    scene.objects = vec![quad("wall", -2.0, 4.0, 0.0, 0)];
    scene.objects.extend(quads);
    scene
}

#[test]
fn layers_blend_as_the_over_operator_in_either_drawing_order() {
    let (g, b) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 1.0));
    let mats = vec![glow(g, 0.5), glow(b, 0.25)];
    // Green at z = 1 (near), blue at z = 0 (far): over the red wall.
    let want = 0.5 * g + 0.5 * (0.25 * b + 0.75 * Vec3::X);
    for flip in [false, true] {
        let mut quads = vec![quad("green", 1.0, 4.0, 0.0, 1), quad("blue", 0.0, 4.0, 0.0, 2)];
        if flip {
            quads.reverse();
        }
        let frame = render(&layered(mats.clone(), quads), &RenderOptions::default()).unwrap();
        assert_eq!(frame.stats.translucent_fragments, 2 * 64 * 64);
        for p in frame.image.pixels() {
            assert!((*p - want).abs().max_element() < 1e-6, "flip {flip}: {p} vs {want}");
        }
    }
}

#[test]
fn the_unsorted_fallback_blends_in_drawing_order() {
    let (g, b) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 1.0));
    // Near green drawn first, far blue drawn over it: the paper's artefact.
    let mut scene = layered(
        vec![glow(g, 0.5), glow(b, 0.25)],
        vec![quad("green", 1.0, 4.0, 0.0, 1), quad("blue", 0.0, 4.0, 0.0, 2)],
    );
    scene.translucency = TranslucencyOrder::Unsorted;
    let want = 0.25 * b + 0.75 * (0.5 * g + 0.5 * Vec3::X);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    assert!((frame.image.get(32, 32) - want).abs().max_element() < 1e-6, "{} vs {want}", frame.image.get(32, 32));
}

#[test]
fn intersecting_translucent_surfaces_blend_correctly_on_both_sides() {
    let (g, b) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 1.0));
    // Green faces the eye at z = 0; blue is turned 45° about y through it: left
    // of the centre blue is nearer, right of it green is.
    let quads = vec![quad("green", 0.0, 4.0, 0.0, 1), quad("blue", 0.0, 4.0, 45.0, 2)];
    let frame = render(&layered(vec![glow(g, 0.5), glow(b, 0.5)], quads), &RenderOptions::default()).unwrap();
    let over = |near: Vec3, far: Vec3| 0.5 * near + 0.5 * (0.5 * far + 0.5 * Vec3::X);
    let (left, right) = (frame.image.get(16, 32), frame.image.get(48, 32));
    assert!((left - over(b, g)).abs().max_element() < 1e-6, "left {left}");
    assert!((right - over(g, b)).abs().max_element() < 1e-6, "right {right}");
}

#[test]
fn lit_translucent_layers_keep_the_component_sum() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/glass.toml");
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height) = (160, 90);
    let options = RenderOptions { aovs: ComponentSet::ALL, ..RenderOptions::default() };
    let frame = render(&scene, &options).unwrap();
    assert!(frame.stats.translucent_fragments > 1000);
    for (i, p) in frame.image.pixels().iter().enumerate() {
        let sum: Vec3 = frame.aovs.iter().map(|(_, a)| a.pixels()[i]).sum();
        assert!((sum - *p).abs().max_element() <= 1e-5 * p.max_element().max(1.0), "pixel {i}: {sum} vs {p}");
    }
    assert!(frame.aovs.iter().any(|(c, a)| *c == Component::Diffuse && a.pixels().iter().any(|p| p.z > 0.05)));
}

/// The reference renderer blends translucent surfaces the same way (α · surface +
/// (1 − α) · what the ray meets behind it), so without shadows the two agree on
/// nearly every pixel of the glass example.
#[test]
fn the_reference_blends_translucent_layers_as_the_raster_does() {
    use kage::raytrace::reference::{render_reference, ReferenceOptions};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/glass.toml");
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height) = (240, 135);
    scene.lights.iter_mut().for_each(|l| l.shadow = kage::scene::ShadowSettings::NONE);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let opts = ReferenceOptions::CENTRES;
    let truth = render_reference(&scene, &opts, &|_| {});
    let c = kage::compare::compare(&frame.image, &truth, 2e-3).unwrap();
    assert!(frame.stats.translucent_fragments > 5000);
    assert!(
        c.share_over < 0.01,
        "{:.3}% of pixels differ by more than 2e-3 (rmse {:.5})",
        100.0 * c.share_over,
        c.rmse
    );
}

/// Translucent surfaces are shadowed by the same maps as opaque ones (fitted
/// to the casters, not to the whole scene with its floor): the glass example
/// with its glass made all but opaque (α = 0.9999, drawn by the translucency
/// pass) renders as with it opaque (drawn by the opaque passes).
#[test]
fn translucent_surfaces_are_shadowed_by_the_opaque_passes_maps() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/glass.toml");
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height) = (240, 135);
    scene.antialias = kage::scene::Antialias::None;
    // Coarse maps, so that maps fitted differently show it along the edges;
    // the white ball moved between the light and the blue glass box, so its
    // shadow's edge crosses the box.
    scene.lights.iter_mut().for_each(|l| (l.shadow.resolution, l.shadow.by_need) = (256, false));
    let ball = scene.objects.iter_mut().find(|o| o.name == "white ball").unwrap();
    ball.transform =
        Affine3A::from_scale_rotation_translation(Vec3::splat(0.3), Quat::IDENTITY, Vec3::new(-1.0, 2.4, 1.9));
    let glass: Vec<usize> = (0..scene.materials.len()).filter(|&m| scene.materials[m].opacity < 1.0).collect();
    assert!(!glass.is_empty(), "the glass example has translucent materials");
    let mut opaque = scene.clone();
    glass.iter().for_each(|&m| opaque.materials[m].opacity = 1.0);
    glass.iter().for_each(|&m| scene.materials[m].opacity = 0.9999);
    let almost = render(&scene, &RenderOptions::default()).unwrap();
    assert!(almost.stats.translucent_fragments > 1000);
    let solid = render(&opaque, &RenderOptions::default()).unwrap();
    let c = kage::compare::compare(&almost.image, &solid.image, 0.02).unwrap();
    assert!(
        c.share_over < 0.001,
        "{:.3}% of pixels differ by more than 0.02 (rmse {:.5})",
        100.0 * c.share_over,
        c.rmse
    );
}
