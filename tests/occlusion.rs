//! Ambient occlusion in the raster frame: open where nothing is near, dark at
//! the foot of a box, and the reference renderer's ambient occlusion (many
//! rays) within a bound once the passes of a progressive preview add up.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use kage::compare::compare;
use kage::raytrace::reference::{render_reference, ReferenceOptions};
use kage::raytrace::TraceScene;
use kage::scene::mesh::shapes;
use kage::scene::{AmbientOcclusion, Antialias, Material, Object, Scene, ShadowSettings};
use kage::{render, Frame, RenderOptions};
use rand::rngs::StdRng;
use rand::SeedableRng;

/// A 10 × 10 floor seen from above and aside, a strong ambient light, no
/// shadows (so the raster frame and the reference differ by ambient
/// occlusion alone), a unit cube standing on the floor when `with_box`.
fn floor_scene(with_box: bool, ao: Option<AmbientOcclusion>) -> Scene {
    let mut rng = StdRng::seed_from_u64(7);
    let mut scene = common::scene_with(shapes::plane(), common::random_camera(&mut rng, false), 160, 120, false);
    scene.camera.eye = Vec3::new(2.5, 3.5, 4.0);
    scene.camera.target = Vec3::new(0.0, 0.0, 0.0);
    scene.camera.near = 0.1;
    scene.camera.far = 100.0;
    scene.lights[0].ambient = 0.6;
    scene.lights[0].shadow = ShadowSettings::NONE;
    scene.materials[0] = Material { ka: Vec3::splat(0.8), kd: Vec3::splat(0.5), ..Material::default() };
    scene.objects[0].transform = Affine3A::from_scale(Vec3::new(10.0, 1.0, 10.0));
    if with_box {
        let place = Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0));
        scene.objects.push(Object::mesh("box", Arc::new(shapes::cube()), place, 0));
    }
    scene.ambient_occlusion = ao;
    scene
}

fn ao(rays: u32) -> Option<AmbientOcclusion> {
    Some(AmbientOcclusion { radius: Some(1.0), rays, ..AmbientOcclusion::default() })
}

fn frame(scene: &Scene) -> Frame {
    render(scene, &RenderOptions::default()).expect("render")
}

#[test]
fn a_floor_alone_is_open_everywhere_and_keeps_its_image() {
    let plain = frame(&floor_scene(false, None));
    let with = frame(&floor_scene(false, ao(16)));
    assert!(plain.occlusion.pixels().is_empty(), "no occlusion image without ambient occlusion");
    assert_eq!(with.occlusion.pixels().len(), with.image.pixels().len());
    assert!(with.occlusion.pixels().iter().all(|&p| p == Vec3::ONE), "every ray leaves the floor");
    assert!(with.image.pixels() == plain.image.pixels(), "nothing darkened");
}

#[test]
fn a_box_on_a_floor_darkens_the_floor_at_its_foot_and_not_far_away() {
    let scene = floor_scene(true, ao(64));
    let f = frame(&scene);
    let plain = frame(&floor_scene(true, None));
    let trace = TraceScene::new(&scene);
    let rays = scene.camera.pixel_rays(Vec2::new(scene.width as f32, scene.height as f32));
    let (mut near, mut far, mut dimmed_far) = (Vec::new(), 0, 0);
    for y in 0..scene.height {
        for x in 0..scene.width {
            let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let Some(hit) = trace.intersect(&ray, f32::INFINITY) else { continue };
            if hit.item.object != 0 {
                continue; // the box
            }
            let p = ray.origin + ray.dir * hit.t;
            // Distance from the box's footprint on the floor.
            let d = (p.x.abs() - 0.5).max(p.z.abs() - 0.5);
            let i = (y * scene.width + x) as usize;
            let open = f.occlusion.pixels()[i].x;
            if d > 0.0 && d < 0.08 {
                near.push(open);
                let darker = f.image.pixels()[i].max_element() < plain.image.pixels()[i].max_element();
                assert!(darker, "pixel ({x}, {y}) at the foot is darkened");
            } else if d > 1.05 {
                far += 1;
                dimmed_far += usize::from(open != 1.0 || f.image.pixels()[i] != plain.image.pixels()[i]);
            }
        }
    }
    let mean = near.iter().sum::<f32>() / near.len() as f32;
    assert!(near.len() > 50 && mean < 0.75, "{} pixels at the foot, mean open share {mean}", near.len());
    assert!(far > 5000 && dimmed_far == 0, "{dimmed_far} of {far} pixels beyond the radius darkened");
}

#[test]
fn sixty_four_preview_passes_match_the_references_ambient_occlusion() {
    // The viewer's refinement: 64 jittered passes of 4 rays a pixel.
    let mut scene = floor_scene(true, ao(4));
    scene.antialias = Antialias::Jitter(64);
    let raster = frame(&scene);
    let opts = ReferenceOptions { pixel_samples: 4, shadows: false, occlusion_rays: 64, ..ReferenceOptions::default() };
    let truth = render_reference(&floor_scene(true, ao(4)), &opts, &|_| {});
    let open_truth = render_reference(&floor_scene(true, None), &opts, &|_| {});
    let e = compare(&raster.image, &truth, 0.05).expect("same size");
    let effect = compare(&open_truth, &truth, 0.05).expect("same size");
    assert!(
        e.rmse < 0.02 && e.rmse < 0.25 * effect.rmse,
        "raster against the reference's ambient occlusion: rmse {:.4}; the occlusion itself: {:.4}",
        e.rmse,
        effect.rmse
    );
}

/// The quick form: the same radius, estimated from the frame's depth buffer.
fn screen(rays: u32) -> Option<AmbientOcclusion> {
    ao(rays).map(|a| AmbientOcclusion { screen_space: true, ..a })
}

#[test]
fn the_screen_space_form_leaves_a_floor_open_darkens_a_boxs_foot_and_nears_the_reference() {
    screen_space_against_the_traced(&|s| s);
}

/// The same through an orthographic camera (whose stored depth is linear in
/// the distance, not its reciprocal).
#[test]
fn the_screen_space_form_does_the_same_through_an_orthographic_camera() {
    screen_space_against_the_traced(&|mut s| {
        s.camera.projection = kage::camera::Projection::Orthographic { height: 4.0 };
        s
    });
}

fn screen_space_against_the_traced(view: &dyn Fn(Scene) -> Scene) {
    let floor_scene = |with_box, ao| view(floor_scene(with_box, ao));
    let alone = frame(&floor_scene(false, screen(16)));
    assert!(alone.occlusion.pixels().iter().all(|&p| p == Vec3::ONE), "a floor alone closes nothing");
    let scene = floor_scene(true, screen(16));
    let quick = frame(&scene);
    let plain = frame(&floor_scene(true, None));
    let darkened = quick.image.pixels().iter().zip(plain.image.pixels()).filter(|(q, p)| q.x < p.x - 1e-4).count();
    assert!(darkened > 300, "{darkened} pixels darkened");
    // Against the traced open share of the same pixels (256 rays each):
    // far nearer than no occlusion at all.
    let traced = frame(&floor_scene(true, ao(256))).occlusion;
    let mut open = kage::image::LinearImage::new(traced.width(), traced.height());
    open.pixels_mut().fill(Vec3::ONE);
    let e = compare(&quick.occlusion, &traced, 0.05).expect("same size");
    let effect = compare(&open, &traced, 0.05).expect("same size");
    assert!(
        e.rmse < 0.5 * effect.rmse,
        "screen-space open share against the traced: rmse {:.4}; the occlusion itself: {:.4}",
        e.rmse,
        effect.rmse
    );
}
