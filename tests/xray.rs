//! The x-ray view: every object but the ground see-through, blended in depth
//! order, so the image does not depend on the order the scene lists its
//! objects in, and a part inside another shows.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec3};
use kage::scene::mesh::shapes;
use kage::scene::{Antialias, Material, Object, Scene, TranslucencyOrder, XRAY_OPACITY};
use kage::{render, RenderOptions};
use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use rand::SeedableRng;

/// A box holding a ball, a ring through the box's side, a floor; each in a
/// material of its own.
fn parts(with_ball: bool) -> Scene {
    let mut rng = StdRng::seed_from_u64(11);
    let mut scene = common::scene_with(shapes::cube(), common::random_camera(&mut rng, false), 120, 90, false);
    scene.camera.eye = Vec3::new(2.5, 2.0, 3.5);
    scene.camera.target = Vec3::ZERO;
    scene.camera.near = 0.1;
    scene.camera.far = 50.0;
    scene.antialias = Antialias::None;
    let colours = [Vec3::new(0.8, 0.3, 0.2), Vec3::new(0.2, 0.4, 0.9), Vec3::new(0.3, 0.8, 0.3), Vec3::splat(0.6)];
    scene.materials = colours.map(|kd| Material { kd, ka: kd, ..Material::default() }).to_vec();
    scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(1.6));
    let place = |s: f32, r: Quat, t: Vec3| Affine3A::from_scale_rotation_translation(Vec3::splat(s), r, t);
    if with_ball {
        scene.objects.push(Object::mesh(
            "ball",
            Arc::new(shapes::sphere(16)),
            place(0.5, Quat::IDENTITY, Vec3::ZERO),
            1,
        ));
    }
    let ring = place(0.9, Quat::from_rotation_x(1.2), Vec3::new(0.8, 0.2, 0.0));
    scene.objects.push(Object::mesh("ring", Arc::new(shapes::torus(24, 12, 0.25)), ring, 2));
    let floor = place(8.0, Quat::IDENTITY, Vec3::new(0.0, -1.2, 0.0));
    scene.objects.push(Object::mesh("floor", Arc::new(shapes::plane()), floor, 3));
    scene
}

fn image(scene: &Scene) -> Vec<Vec3> {
    render(scene, &RenderOptions::default()).expect("render").image.pixels().to_vec()
}

#[test]
fn an_xray_is_the_same_for_any_order_of_the_objects() {
    let mut scene = parts(true);
    scene.xray(XRAY_OPACITY);
    for o in &scene.objects {
        let opacity = scene.materials[o.material].opacity;
        assert_eq!(opacity == 1.0, o.name == "floor", "{}: opacity {opacity} (the ground stays solid)", o.name);
    }
    let first = image(&scene);
    let mut rng = StdRng::seed_from_u64(5);
    for _ in 0..4 {
        let mut shuffled = scene.clone();
        shuffled.objects.shuffle(&mut rng);
        assert!(image(&shuffled) == first, "the image changed with the objects' order");
    }
    // Drawing order, as the paper's fallback blends, is not order-free: the
    // comparison above can fail.
    scene.translucency = TranslucencyOrder::Unsorted;
    let unsorted = image(&scene);
    let mut reversed = scene.clone();
    reversed.objects.reverse();
    assert!(image(&reversed) != unsorted, "unsorted blending depends on the order");
}

#[test]
fn an_xray_shows_a_part_inside_another() {
    let (mut with, mut without) = (parts(true), parts(false));
    with.xray(XRAY_OPACITY);
    without.xray(XRAY_OPACITY);
    let (a, b) = (image(&with), image(&without));
    let changed = a.iter().zip(&b).filter(|(p, q)| (**p - **q).abs().max_element() > 0.02).count();
    // The ball (radius 0.5 in a box of side 1.6) covers some 170 pixels.
    assert!(changed > 120, "only {changed} pixels show the ball inside the box");
    let opaque = image(&parts(true));
    let hidden = image(&parts(false));
    assert!(opaque == hidden, "without x-ray the box hides the ball");
}
