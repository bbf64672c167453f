//! Whole frames: known shading answers, thread-count independence, memory, and the
//! model loaders on the shared real-world assets (skipped when absent).

mod common;
#[path = "common/skip.rs"]
mod skip;

use std::path::Path;

use glam::Vec3;
use kage::camera::{Camera, Projection};
use kage::scene::mesh::shapes;
use kage::scene::model::scene_for_model;
use kage::scene::{Falloff, Light, LightKind};
use kage::{render, RenderOptions};

fn plane_scene(light: Light) -> kage::Scene {
    let camera = Camera {
        eye: Vec3::new(0.0, 3.0, 0.001),
        target: Vec3::ZERO,
        up: Vec3::NEG_Z,
        near: 0.1,
        far: 10.0,
        projection: Projection::Orthographic { height: 0.5 },
        shift: glam::Vec2::ZERO,
    };
    let mut s = common::scene_with(shapes::plane(), camera, 16, 16, false);
    s.lights = vec![light];
    s
}

/// An unoccluded plane under a directional light at angle θ: every pixel is
/// Ka·Ia + Kd·I·cosθ + Ks·I·(cosα)^n, computed here by hand.
#[test]
fn unoccluded_plane_matches_equation_one() {
    let theta: f32 = 0.6;
    let dir = Vec3::new(theta.sin(), -theta.cos(), 0.0);
    let light = Light {
        kind: LightKind::Directional { direction: dir },
        color: Vec3::new(1.0, 0.5, 0.25),
        intensity: 2.0,
        ambient: 0.1,
        size: 0.0,
        falloff: Falloff::None,
        ..Light::default()
    };
    let scene = plane_scene(light);
    let m = &scene.materials[0];
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let c = Vec3::new(1.0, 0.5, 0.25);
    // Orthographic view straight down: V = +y; R = mirror of L about +y.
    let l = -dir;
    let r = Vec3::new(-l.x, l.y, -l.z);
    let want =
        c * 0.1 * m.ka + c * 2.0 * m.kd * theta.cos() + c * 2.0 * m.ks * r.dot(Vec3::Y).max(0.0).powf(m.shininess);
    for p in frame.image.pixels() {
        assert!((*p - want).abs().max_element() < 1e-4, "{p} vs {want}");
    }
}

/// Two coincident lights of intensity 1 give the image of one light of intensity 2
/// (ambient aside, which both carry).
#[test]
fn lights_add_up() {
    let light = |intensity, ambient| Light {
        kind: LightKind::Point { position: Vec3::new(0.3, 1.0, 0.2) },
        color: Vec3::ONE,
        intensity,
        ambient,
        size: 0.0,
        falloff: Falloff::InverseSquare,
        ..Light::default()
    };
    let one = plane_scene(light(2.0, 0.2));
    let mut two = plane_scene(light(1.0, 0.1));
    two.lights.push(light(1.0, 0.1));
    let (a, b) = (render(&one, &RenderOptions::default()).unwrap(), render(&two, &RenderOptions::default()).unwrap());
    for (p, q) in a.image.pixels().iter().zip(b.image.pixels()) {
        assert!((*p - *q).abs().max_element() < 1e-5, "{p} vs {q}");
    }
}

/// What is computed does not depend on how it is parallelised.
#[test]
fn one_two_five_and_sixteen_threads_give_identical_frames() {
    let scene = kage::scene::demo::demo_scene().unwrap();
    let a = render(&scene, &RenderOptions { threads: Some(1), ..Default::default() }).unwrap();
    let b = render(&scene, &RenderOptions { threads: Some(2), ..Default::default() }).unwrap();
    let c = render(&scene, &RenderOptions { threads: Some(5), ..Default::default() }).unwrap();
    let d = render(&scene, &RenderOptions { threads: Some(16), ..Default::default() }).unwrap();
    assert_eq!(a.visibility.items(), b.visibility.items());
    assert_eq!(a.visibility.depths(), c.visibility.depths());
    assert_eq!(a.visibility.items(), d.visibility.items());
    assert_eq!(a.image, b.image);
    assert_eq!(a.image, c.image);
    assert_eq!(a.image, d.image);
}

/// The demo is not a silent black image: every object shows and is lit.
#[test]
fn demo_scene_shows_every_object() {
    let scene = kage::scene::demo::demo_scene().unwrap();
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    for (i, o) in scene.objects.iter().enumerate() {
        let n = frame.visibility.items().iter().filter(|it| it.object == i as u32).count();
        assert!(n > 1000, "object {} covers only {n} pixels", o.name);
    }
    let mean = frame.image.pixels().iter().copied().sum::<Vec3>() / frame.image.pixels().len() as f32;
    assert!(mean.min_element() > 0.1, "mean colour {mean}");
}

/// A 1920x1080 frame's buffers, shadow maps included, stay under 128 MB.
#[test]
fn full_hd_buffers_fit_in_128_mb() {
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    scene.width = 1920;
    scene.height = 1080;
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    assert!(frame.stats.buffer_bytes < 128 << 20, "{} bytes", frame.stats.buffer_bytes);
}

/// The share of the image the model covers (its ground aside).
fn coverage(path: &Path) -> f32 {
    let scene = scene_for_model(path, 96, 72).unwrap();
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let model = |i: &&kage::visibility::ItemId| !i.is_none() && scene.objects[i.object as usize].name != "ground";
    frame.visibility.items().iter().filter(model).count() as f32 / (96.0 * 72.0)
}

/// Every kind of model file loads and, framed automatically, fills a fair part of
/// the image without overflowing it.
#[test]
fn real_models_load_and_frame() {
    for rel in [
        "meshes/utah-teapot/teapot.obj",
        "meshes/suzanne/suzanne.obj",
        "meshes/dragon/dragon.obj",
        "gltf/Box/Box.glb",
        "gltf/Duck/Duck.glb",
        "gltf/CesiumMilkTruck/CesiumMilkTruck.glb",
        "gltf/Avocado/Avocado.gltf",
        "csg/ex004_cube_minus_sphere.stl",
        "scenes/cornell-box/CornellBox-Original.obj",
    ] {
        let Some(p) = skip::asset(rel) else { continue };
        let c = coverage(&p);
        assert!(c > 0.05 && c < 0.95, "{rel}: covers {:.0}% of the image", 100.0 * c);
    }
}

/// glTF cameras and KHR_lights_punctual lights are honoured.
#[test]
fn gltf_cameras_and_lights() {
    if let Some(p) = skip::asset("gltf/Cameras/Cameras.gltf") {
        let own = kage::scene::model::ModelOptions { file_camera: true, ..Default::default() };
        let scene = kage::scene::model::scene_for_model_with(&p, 64, 48, &own).unwrap();
        assert!(scene.camera.eye.z > 1.0, "the file's camera, not a fitted one: {:?}", scene.camera);
    }
    if let Some(p) = skip::asset("gltf/LightsPunctualLamp/LightsPunctualLamp.gltf") {
        let scene = scene_for_model(&p, 64, 48).unwrap();
        assert!(
            !scene.lights.is_empty()
                && scene
                    .lights
                    .iter()
                    .all(|l| l.falloff == Falloff::InverseSquare || matches!(l.kind, LightKind::Directional { .. }))
        );
    }
}

/// The eight-lane shading path computes what the scalar reference computes, on a
/// scene with textures, every light type, both falloffs and a fractional exponent,
/// and on an orthographic view.
#[test]
fn simd_shading_matches_the_scalar_reference() {
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    scene.lights.push(Light {
        kind: LightKind::Spot {
            position: Vec3::new(1.0, 3.0, 2.0),
            direction: Vec3::new(-0.2, -1.0, -0.4).normalize(),
            inner: 0.3,
            outer: 0.5,
        },
        color: Vec3::new(0.9, 0.7, 0.5),
        intensity: 3.0,
        ambient: 0.05,
        size: 0.0,
        falloff: Falloff::InverseSquare,
        ..Light::default()
    });
    scene.materials[1].shininess = 17.5;
    let ortho = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/cad-ortho.toml");
    for mut scene in [scene, kage::scene::file::load_scene(&ortho).unwrap()] {
        scene.antialias = kage::scene::Antialias::None; // the scalar shader has no edge pass
        let frame = render(&scene, &RenderOptions::default()).unwrap();
        let mut scalar = kage::image::LinearImage::new(scene.width, scene.height);
        kage::shading::shade_into_scalar(&scene, &frame.visibility, &mut scalar);
        let diffs: Vec<f32> =
            frame.image.pixels().iter().zip(scalar.pixels()).map(|(a, b)| (*a - *b).abs().max_element()).collect();
        // Rounding may move a shadow-map lookup across a texel border, flipping one
        // of the area light's eight samples on a rare pixel; everything else agrees.
        let off = diffs.iter().filter(|&&d| d >= 2e-3).count();
        let worst = diffs.iter().copied().fold(0.0f32, f32::max);
        assert!(off * 1000 < diffs.len() && worst < 0.2, "{off} of {} pixels differ, worst {worst}", diffs.len());
    }
}

/// Sub-pixel samples taken at pixel centres get what the lit passes write there
/// (samples shaded eight at a time from their own surface points, against the
/// passes' rows of pixels): every pass and shadow term of a scene with three
/// shadowed spot lights, and the demo's textured surfaces (whose samples take
/// their texture footprints from samples nearby on the same triangle).
#[test]
fn subpixel_samples_at_pixel_centres_match_the_passes() {
    subpixel_samples_match_the_passes_in("spotlights.toml");
    subpixel_samples_match_the_passes_in("demo.toml");
}

fn subpixel_samples_match_the_passes_in(name: &str) {
    use kage::shading::{shade_lit, ComponentSet, SubpixelSample, SubpixelShading, Target};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes").join(name);
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height) = (240, 135);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let vb = &frame.visibility;
    let pixels: Vec<(u32, u32)> =
        (0..scene.height).step_by(3).flat_map(|y| (0..scene.width).step_by(7).map(move |x| (x, y))).collect();
    let centre = |(x, y): (u32, u32)| glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    let samples = pixels.iter().map(|&p| SubpixelSample { pixel: p, at: centre(p) }).collect();
    let mut subpixel = SubpixelShading::new(&scene, vb, samples);
    let mut image = kage::image::LinearImage::new(scene.width, scene.height);
    let mut targets = [Target { parts: ComponentSet::ALL, image: &mut image }];
    shade_lit(&scene, vb, &mut targets, &mut kage::shadows::MapPool::default(), &mut subpixel);
    let mut off = 0;
    for (k, &(x, y)) in pixels.iter().enumerate() {
        let colour = subpixel.colour(k, ComponentSet::ALL);
        if vb.item(x, y).is_none() {
            assert_eq!(colour, None, "nothing seen: no colour");
            continue;
        }
        let colour = colour.expect("a surface seen: a colour");
        let d = (colour - image.get(x, y)).abs().max_element();
        off += usize::from(d >= 2e-3);
        assert!(d < 0.2, "{name}, pixel ({x}, {y}): sample {colour} vs pass {}", image.get(x, y));
    }
    assert!(off * 100 < pixels.len(), "{name}: {off} of {} samples differ from their pixels", pixels.len());
    // Set up while the first pass shades the pixels (as the edge pass does),
    // the samples get the same passes.
    let mut beside = SubpixelShading::default();
    let mut image = kage::image::LinearImage::new(scene.width, scene.height);
    let mut targets = [Target { parts: ComponentSet::ALL, image: &mut image }];
    let mut pool = kage::shadows::MapPool::default();
    let prepare = |s: &mut SubpixelShading| s.reset(&scene, vb, subpixel.samples.clone());
    kage::shading::shade_lit_beside(&scene, vb, &mut targets, &mut pool, &mut beside, None, prepare);
    for k in 0..pixels.len() {
        assert_eq!(beside.colour(k, ComponentSet::ALL), subpixel.colour(k, ComponentSet::ALL), "{name}: sample {k}");
    }
}

/// A renderer reused for a view that shows less (the camera turned half away)
/// holds exactly a fresh renderer's items: pixels the new view leaves empty
/// keep nothing of the frame before.
#[test]
fn a_reused_renderer_keeps_no_item_of_the_frame_before() {
    let scene = kage::scene::demo::demo_scene().unwrap();
    let mut aside = scene.clone();
    aside.camera.target = aside.camera.eye + (aside.camera.target - aside.camera.eye).cross(Vec3::Y);
    let mut renderer = kage::Renderer::new(&RenderOptions::default()).unwrap();
    renderer.render(&scene).unwrap();
    let reused = renderer.render(&aside).unwrap().visibility.items().to_vec();
    let fresh = render(&aside, &RenderOptions::default()).unwrap();
    let empty = fresh.visibility.items().iter().filter(|i| i.is_none()).count();
    assert!(empty > reused.len() / 10, "the turned view leaves pixels empty ({empty})");
    assert!(reused == fresh.visibility.items(), "items differ from a fresh renderer's");
}

/// Open shares handed to the passes scale each pixel's ambient term and
/// nothing else: the demo (textured, shadowed lights, a reflecting floor)
/// shaded with a share varying over the image equals the shading without
/// shares less `(1 − share)` times its ambient component, pixel by pixel.
#[test]
fn open_shares_scale_the_ambient_term_alone() {
    use kage::shading::{shade_lit_beside, Component, ComponentSet, OpenShares, SubpixelShading, Target};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/demo.toml");
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height) = (240, 135);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let vb = &frame.visibility;
    let (w, h) = (scene.width, scene.height);
    let shares: Vec<Vec3> =
        (0..w * h).map(|i| Vec3::splat(((i % w) as f32 / w as f32 + (i / w) as f32 / h as f32) * 0.5)).collect();
    let shade = |open: Option<OpenShares>| {
        let mut all = kage::image::LinearImage::new(w, h);
        let mut ambient = kage::image::LinearImage::new(w, h);
        let mut targets = [
            Target { parts: ComponentSet::ALL, image: &mut all },
            Target { parts: ComponentSet::only(Component::Ambient), image: &mut ambient },
        ];
        let mut pool = kage::shadows::MapPool::default();
        shade_lit_beside(&scene, vb, &mut targets, &mut pool, &mut SubpixelShading::default(), open, |_| {});
        (all, ambient)
    };
    let (plain, ambient) = shade(None);
    let (darkened, darkened_ambient) = shade(Some(OpenShares::new(&shares, w as usize, (0, 0))));
    let mut checked = 0;
    for (i, share) in shares.iter().enumerate() {
        let expected = plain.pixels()[i] - (1.0 - share.x) * ambient.pixels()[i];
        let d = (darkened.pixels()[i] - expected).abs().max_element();
        assert!(d < 1e-4, "pixel {i}: {} against {expected}", darkened.pixels()[i]);
        let d = (darkened_ambient.pixels()[i] - share.x * ambient.pixels()[i]).abs().max_element();
        assert!(d < 1e-4, "pixel {i}'s ambient");
        checked += usize::from(ambient.pixels()[i].max_element() > 1e-3 && share.x < 0.9);
    }
    assert!(checked > 1000, "{checked} pixels with an ambient term darkened");
}
