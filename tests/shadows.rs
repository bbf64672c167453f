//! Shadows and light passes (seed 002 §3.3) against independent answers: shadow
//! maps against shadow rays through the BVH, the exact ambient-only colour of a
//! fully shadowed point, selective lighting, and the additivity of lights.

mod common;

use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use kage::scene::mesh::shapes;
use kage::scene::{Light, LightKind, Material, Object, Scene, ShadowSettings};
use kage::shadows::{MapTerm, ShadowTerm};
use kage::{render, RenderOptions};

/// Shadow maps against shadow rays: (misclassified, compared).
fn map_vs_rays(scene: &Scene) -> (usize, usize) {
    common::terms_vs_rays(scene, &ShadowTerm::build_all(scene))
}

#[test]
fn shadow_maps_agree_with_shadow_rays_on_the_example_scenes() {
    for (name, scene) in common::shadow_example_scenes() {
        let (wrong, total) = map_vs_rays(&scene);
        let share = wrong as f64 / total as f64;
        eprintln!("{name}: {wrong} of {total} lit tests disagree ({:.3}%)", 100.0 * share);
        assert!(total > 10_000, "{name}: only {total} tests");
        assert!(share < 0.005, "{name}: {wrong} of {total} shadow-map tests disagree with shadow rays");
    }
}

/// A ground square under a directional light straight down, a roof square above it.
fn roofed(ambient: f32) -> Scene {
    let camera = kage::camera::Camera {
        eye: Vec3::new(0.0, 5.0, 0.001),
        target: Vec3::ZERO,
        up: Vec3::NEG_Z,
        near: 0.1,
        far: 20.0,
        projection: kage::camera::Projection::Orthographic { height: 4.0 },
        shift: Vec2::ZERO,
    };
    let mut scene = common::scene_with(shapes::plane(), camera, 64, 64, false);
    scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(4.0));
    scene.materials[0].ke = Vec3::new(0.01, 0.02, 0.03);
    let roof = Affine3A::from_scale_rotation_translation(Vec3::splat(1.0), glam::Quat::IDENTITY, Vec3::Y);
    scene.materials.push(Material { two_sided: true, ..Material::default() });
    scene.objects.push(Object::mesh("roof", Arc::new(shapes::plane()), roof, 1));
    scene.lights = vec![Light {
        kind: LightKind::Directional { direction: Vec3::new(0.8, -1.0, 0.05).normalize() },
        ambient,
        ..Light::default()
    }];
    scene
}

#[test]
fn a_fully_shadowed_point_receives_exactly_ambient_and_emission() {
    let scene = roofed(0.3);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let m = &scene.materials[0];
    let want = m.ka * 0.3 + m.ke;
    // The roof hides the ground's centre from the eye; its shadow falls 1 unit
    // lower, moved by the light's tilt (0.8 in x, 0.05 in z), partly in view.
    let ground = |x: u32, y: u32| frame.visibility.item(x, y).object == 0;
    let (mut shadowed, mut lit) = (0, 0);
    for y in 0..64 {
        for x in 0..64 {
            if !ground(x, y) {
                continue;
            }
            let p = frame.image.get(x, y);
            // World x, z of the pixel centre (orthographic, 4 units over 64 pixels).
            let (wx, wz) = ((x as f32 + 0.5) / 16.0 - 2.0, (y as f32 + 0.5) / 16.0 - 2.0);
            // The roof's shadow on the ground: the roof square moved by the light's
            // tilt over a drop of 1 unit, shrunk by a texel margin.
            let (sx, sz) = (wx - 0.8, wz - 0.05);
            if sx.abs() < 0.45 && sz.abs() < 0.45 {
                assert!(
                    (p - want).abs().max_element() < 1e-5,
                    "({x}, {y}) in shadow: {p} vs ambient + emission {want}"
                );
                shadowed += 1;
            } else if sx.abs() > 0.55 || sz.abs() > 0.55 {
                assert!((p - want).min_element() > 0.1, "({x}, {y}) lit: {p}");
                lit += 1;
            }
        }
    }
    assert!(shadowed > 20 && lit > 1000, "{shadowed} shadowed, {lit} lit ground pixels");
}

#[test]
fn one_light_of_intensity_two_equals_two_coincident_lights_with_shadows() {
    let mut one = roofed(0.2);
    one.lights[0].intensity = 2.0;
    let mut two = roofed(0.1);
    two.lights.push(two.lights[0].clone());
    // A light listing every object gets a pass of its own: the same sum, grouped
    // differently.
    let mut split = two.clone();
    split.lights[1].only = Some((0..split.objects.len()).collect());
    let frames = [&one, &two, &split].map(|s| render(s, &RenderOptions::default()).unwrap());
    assert_eq!(frames.each_ref().map(|f| f.stats.shading_passes), [1, 1, 2], "shadowed lights share the first pass");
    for f in &frames[1..] {
        for (p, q) in frames[0].image.pixels().iter().zip(f.image.pixels()) {
            assert!((*p - *q).abs().max_element() < 1e-5, "{p} vs {q}");
        }
    }
}

#[test]
fn a_selective_light_changes_only_its_objects_and_others_still_hide_them() {
    // Roof (object 1) in front of the ground (object 0) as the eye sees it.
    let mut base = roofed(0.1);
    base.lights[0].shadow = ShadowSettings::NONE;
    let mut with = base.clone();
    with.lights.push(Light {
        kind: LightKind::Point { position: Vec3::new(0.5, 3.0, 0.5) },
        color: Vec3::new(1.0, 0.2, 0.1),
        ambient: 0.2,
        only: Some(vec![0]),
        ..Light::default()
    });
    let (a, b) = (render(&base, &RenderOptions::default()).unwrap(), render(&with, &RenderOptions::default()).unwrap());
    let (mut changed, mut hidden) = (0, 0);
    for (i, item) in b.visibility.items().iter().enumerate() {
        let (p, q) = (a.image.pixels()[i], b.image.pixels()[i]);
        if item.object == 0 {
            changed += usize::from((q - p).max_element() > 0.05);
        } else {
            assert_eq!(p, q, "pixel {i} shows object {} which the light does not list", item.object);
            hidden += usize::from(item.object == 1);
        }
    }
    assert!(hidden > 200, "the roof hides part of the ground ({hidden} pixels)");
    assert!(changed * 10 > b.visibility.items().iter().filter(|i| i.object == 0).count() * 9, "{changed}");
}

#[test]
fn fog_in_a_shadow_is_the_lerp_to_the_fog_colour_not_black() {
    use kage::scene::{Fog, FogMode};
    let plain = roofed(0.3);
    let mut foggy = plain.clone();
    // The orthographic eye is 5 units above the ground: f = (5 − 2) / (8 − 2) = 0.5
    // (to 1e-4: the view is tilted by 0.001 / 5 to keep `up` off the view axis).
    let fog = Fog { mode: FogMode::Linear { start: 2.0, end: 8.0 }, color: Vec3::new(0.6, 0.7, 0.9) };
    foggy.fog = Some(fog);
    let (a, b) =
        (render(&plain, &RenderOptions::default()).unwrap(), render(&foggy, &RenderOptions::default()).unwrap());
    let m = &plain.materials[0];
    let shadowed = m.ka * 0.3 + m.ke;
    let (mut in_shadow, mut ground) = (0, 0);
    for (i, item) in b.visibility.items().iter().enumerate() {
        if item.object != 0 {
            continue;
        }
        let (p, q) = (a.image.pixels()[i], b.image.pixels()[i]);
        let want = p.lerp(fog.color, 0.5);
        assert!((q - want).abs().max_element() < 1e-4, "pixel {i}: fogged {q}, lerp({p}, fog, 0.5) = {want}");
        ground += 1;
        if (p - shadowed).abs().max_element() < 1e-6 {
            in_shadow += 1;
            assert!(q.min_element() > 0.3, "a fogged shadow is not black: {q}");
        }
    }
    assert!(in_shadow > 20 && ground > 3000, "{in_shadow} shadowed of {ground} ground pixels");
}

#[test]
fn jittered_area_lights_approach_the_reference_penumbra() {
    use kage::raytrace::reference::{render_reference, ReferenceOptions};
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    (scene.width, scene.height) = (240, 135);
    scene.antialias = kage::scene::Antialias::None; // one ray per pixel centre, as the reference
    scene.lights.truncate(1); // the point light with size 0.3
                              // The reference filters textures by supersampling (finest level): so here too.
    scene.materials.iter_mut().for_each(|m| m.maps.filter = kage::scene::material::Filter::Bilinear);
    assert!(scene.lights[0].size > 0.0);
    let opts = ReferenceOptions {
        pixel_samples: 1,
        light_samples: 6,
        shadows: true,
        max_depth: 0,
        ..ReferenceOptions::default()
    };
    let truth = render_reference(&scene, &opts, &|_| {});
    let mut errors = Vec::new();
    for samples in [1, 16] {
        scene.lights[0].shadow.samples = samples;
        let frame = render(&scene, &RenderOptions::default()).unwrap();
        errors.push(kage::compare::compare(&frame.image, &truth, 0.05).unwrap());
    }
    let (hard, soft) = (&errors[0], &errors[1]);
    assert!(
        soft.rmse < 0.5 * hard.rmse && soft.share_over < 0.3 * hard.share_over,
        "16 jittered maps: rmse {:.4}, {:.4} over 0.05; one map: rmse {:.4}, {:.4} over",
        soft.rmse,
        soft.share_over,
        hard.rmse,
        hard.share_over
    );
}

/// A renderer keeps last frame's shadow maps while only the camera moves (the
/// viewer's case): the point light's jittered maps are reused, the directional
/// light's map (fitted to the view) is not, and every frame equals a fresh
/// render; moving an object drops them all.
#[test]
fn shadow_maps_are_reused_while_only_the_camera_moves() {
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    (scene.width, scene.height) = (160, 90);
    let point_maps = kage::shading::frame_lights(&scene)
        .iter()
        .flat_map(|l| &l.samples)
        .filter(|l| matches!(l.kind, LightKind::Point { .. }) && l.shadow.method != kage::scene::ShadowMethod::None)
        .count();
    assert!(point_maps >= 2, "the demo's key light is a sized point light");
    let mut renderer = kage::Renderer::new(&RenderOptions::default()).unwrap();
    renderer.render(&scene).unwrap();
    let orbit = Affine3A::from_rotation_y(0.1);
    scene.camera.eye = orbit.transform_point3(scene.camera.eye);
    let frame = renderer.render(&scene).unwrap().clone();
    assert_eq!(frame.stats.shadow_maps_reused, point_maps, "only the point light's maps carry over");
    assert!(frame.image.pixels() == render(&scene, &RenderOptions::default()).unwrap().image.pixels());
    // An object moved within the scene's bounds: only the geometry says the
    // maps are stale.
    let bounds = scene.bounds();
    let last = scene.objects.len() - 1;
    scene.objects[last].transform =
        Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.0)) * scene.objects[last].transform;
    assert_eq!(scene.bounds(), bounds, "the move keeps the scene's bounds");
    let frame = renderer.render(&scene).unwrap().clone();
    assert_eq!(frame.stats.shadow_maps_reused, 0, "a moved object needs new maps");
    assert!(frame.image.pixels() == render(&scene, &RenderOptions::default()).unwrap().image.pixels());
}

/// Jittered passes shift the camera by fractions of a pixel; a directional
/// light's map, fitted to the view, is fitted to the unshifted one, so the
/// passes after the first reuse the first's maps and the next frame reuses
/// them all (jitter 4 then costs about four aliased frames).
#[test]
fn jittered_passes_share_the_maps_fitted_to_the_view() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/cad-ortho.toml");
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height) = (160, 120);
    scene.antialias = kage::scene::Antialias::Jitter(4);
    let maps = kage::shading::frame_lights(&scene)
        .iter()
        .flat_map(|l| &l.samples)
        .filter(|l| {
            matches!(l.kind, LightKind::Directional { .. }) && l.shadow.method != kage::scene::ShadowMethod::None
        })
        .count();
    assert!(maps >= 1, "the scene has a shadowed directional light");
    let mut renderer = kage::Renderer::new(&RenderOptions::default()).unwrap();
    let first = renderer.render(&scene).unwrap().stats;
    assert_eq!(first.shadow_maps_reused, 3 * maps, "passes 2-4 reuse the first pass's maps");
    let next = renderer.render(&scene).unwrap().stats;
    assert_eq!(next.shadow_maps_reused, 4 * maps, "the next frame reuses them in every pass");
    // An aliased frame after the jittered ones fits its maps to its own view
    // again: the same image as a fresh render.
    scene.antialias = kage::scene::Antialias::None;
    let aliased = renderer.render(&scene).unwrap().image.clone();
    assert!(aliased.pixels() == render(&scene, &RenderOptions::default()).unwrap().image.pixels());
}

/// A 40° perspective camera at `eye` looking at the origin, y up.
fn towards_origin(eye: Vec3) -> kage::camera::Camera {
    kage::camera::Camera {
        eye,
        target: Vec3::ZERO,
        up: Vec3::Y,
        near: 0.1,
        far: 50.0,
        projection: kage::camera::Projection::Perspective { fov_y_deg: 40.0 },
        shift: Vec2::ZERO,
    }
}

/// A wide floor that casts no shadow under a small box, lit by a point light
/// above: the light's map is fitted to the box alone.
fn box_on_a_shadowless_floor() -> Scene {
    let mut scene = common::scene_with(shapes::plane(), towards_origin(Vec3::new(0.0, 6.0, 8.0)), 160, 120, false);
    scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(40.0));
    scene.objects[0].casts_shadows = false;
    let lifted = Affine3A::from_translation(Vec3::new(0.0, 0.6, 0.0)) * Affine3A::from_scale(Vec3::splat(0.5));
    scene.objects.push(Object::mesh("box", Arc::new(shapes::cube()), lifted, 0));
    scene.lights[0].kind = LightKind::Point { position: Vec3::new(0.5, 4.0, 0.8) };
    scene.lights[0].shadow = ShadowSettings { samples: 1, ..ShadowSettings::default() };
    scene
}

/// How many plain maps a term reads: one, a cube's six, or 0 for another
/// method's term.
fn maps_of(term: &ShadowTerm) -> usize {
    term.downcast_ref::<MapTerm>().map_or(0, |t| t.maps().len())
}

#[test]
fn a_floor_that_casts_no_shadow_leaves_the_map_to_the_casters_and_still_receives() {
    let mut scene = box_on_a_shadowless_floor();
    // Fitted to the box, the point light's map is one cone; were the floor a
    // caster, the light would lie inside its bounds and need six cube faces.
    assert_eq!(maps_of(&ShadowTerm::build(&scene, &scene.lights[0])), 1, "a cone around the box");
    // The floor still receives the box's shadow: the map agrees with shadow
    // rays, which pass through the floor as the map leaves it out.
    let (wrong, total) = map_vs_rays(&scene);
    assert!(total > 5_000, "only {total} tests");
    assert!((wrong as f64) < 0.005 * total as f64, "{wrong} of {total} shadow-map tests disagree with shadow rays");
    let under_box = Vec3::new(0.0, 0.0, 0.0);
    assert!(
        ShadowTerm::build(&scene, &scene.lights[0]).lit(under_box, 1.0, &kage::shadows::Receiver::UNKNOWN) < 0.5,
        "the floor under the box is shadowed"
    );
    // A floor that casts, under everything and lit from above, casts onto
    // nothing: it is found and left out all the same.
    scene.objects[0].casts_shadows = true;
    assert_eq!(maps_of(&ShadowTerm::build(&scene, &scene.lights[0])), 1, "a cone around the box");
    // Lit from below, it shadows what stands on it: it widens the map.
    scene.lights[0].kind = LightKind::Point { position: Vec3::new(0.5, -4.0, 0.8) };
    assert_eq!(maps_of(&ShadowTerm::build(&scene, &scene.lights[0])), 6, "the floor widens the map");
}

#[test]
fn scene_files_and_the_model_rig_say_which_objects_cast_shadows() {
    let text = "[[object]]\nname = \"floor\"\nshape = \"plane\"\nscale = 40\ncasts_shadows = false\n\n\
                [[object]]\nname = \"box\"\nshape = \"cube\"\n";
    let fs = kage::scene::load::FileSystem { base: std::env::temp_dir() };
    let scene = kage::scene::file::SceneFile::parse(text, Path::new("floor.toml")).unwrap().build(&fs).unwrap();
    let casts: Vec<(&str, bool)> = scene.objects.iter().map(|o| (o.name.as_str(), o.casts_shadows)).collect();
    assert_eq!(casts, [("floor", false), ("box", true)]);
    assert_eq!(scene.caster_bounds(), scene.objects[1].world_bounds(), "the maps fit the box");
    // The ground a `.csg` model stands on casts nothing; the model does.
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/csg/ex004_cube_minus_sphere.csg");
    let rig = kage::scene::model::scene_for_model(&model, 320, 240).unwrap();
    let ground: Vec<bool> = rig.objects.iter().filter(|o| o.name == "ground").map(|o| o.casts_shadows).collect();
    assert_eq!(ground, [false]);
    assert!(rig.objects.iter().filter(|o| o.name != "ground").all(|o| o.casts_shadows));
}

/// The images `--aov shadow` writes: each light's shadow term at the surface
/// each pixel shows decides lit or not as shadow rays do (by maps and by the
/// silhouette-line buffer), is 0 where the surface faces away from the light
/// and 1 where no object is seen.
#[test]
fn shadow_images_show_each_lights_term_as_shadow_rays_say() {
    use kage::scene::ShadowMethod;
    let (_, scene) = common::shadow_example_scenes().into_iter().find(|(n, _)| *n == "spotlights").expect("spotlights");
    for (method, most) in [(ShadowMethod::Map, 0.005), (ShadowMethod::Slb, 0.001)] {
        let mut scene = scene.clone();
        scene.lights.iter_mut().for_each(|l| l.shadow = l.shadow.with_method(method));
        let frame = render(&scene, &RenderOptions { shadow_images: true, ..RenderOptions::default() }).unwrap();
        assert_eq!(frame.shadows.len(), scene.lights.len());
        let w = scene.width;
        let at = |light: usize, (x, y): (u32, u32)| frame.shadows[light].pixels()[(y * w + x) as usize].x;
        let (wrong, total) = common::decisions_vs_rays(&scene, |light, q| Some(at(light, q.pixel)));
        eprintln!("{method:?}: {wrong} of {total} shadow-image pixels disagree with shadow rays");
        assert!(total > 10_000 && (wrong as f64) < most * total as f64, "{method:?}: {wrong} of {total}");
        let frames = kage::shading::ObjectFrames::new(&scene);
        let rays = scene.camera.pixel_rays(Vec2::new(w as f32, scene.height as f32));
        let (mut away, mut background) = (0, 0);
        for (y, x) in (0..scene.height).flat_map(|y| (0..w).map(move |x| (y, x))) {
            let item = frame.visibility.item(x, y);
            if item.is_none() {
                background += 1;
                assert!((0..scene.lights.len()).all(|l| at(l, (x, y)) == 1.0), "background at ({x}, {y})");
                continue;
            }
            let s = frames.surface(&scene, item, &rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)));
            for (l, light) in scene.lights.iter().enumerate() {
                if s.normal.dot(light.incident(s.position).to_light) < -0.05 {
                    away += 1;
                    assert_eq!(at(l, (x, y)), 0.0, "({x}, {y}) faces away from light {l}");
                }
            }
        }
        assert!(away > 100 && background > 100, "{away} pixels facing away, {background} background");
    }
}

/// The memory budget of a light's maps comes from what its method builds:
/// on every example scene with shadows, for plain maps, silhouette-line
/// buffers, two-map soft shadows (two points and the ring's four, with plain
/// and silhouette-line hard shadows) and PCSS, the maps built hold no more
/// than [`ShadowTerm::bytes_needed`] said, and not less than a third of it.
#[test]
fn every_methods_maps_fit_the_memory_it_budgets() {
    use kage::scene::{HardShadows, PenumbraPoints, ShadowMethod};
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes");
    let mut scenes = common::shadow_example_scenes();
    for name in ["soft-shadows", "csg", "atrium"] {
        let mut scene = kage::scene::file::load_scene(&dir.join(format!("{name}.toml"))).unwrap();
        (scene.width, scene.height) = (320, 200);
        scenes.push((name, scene));
    }
    let base = ShadowSettings { resolution: 1024, by_need: false, samples: 1, ..ShadowSettings::default() };
    let methods = [
        ("map", ShadowSettings { method: ShadowMethod::Map, ..base }),
        ("slb", ShadowSettings { method: ShadowMethod::Slb, ..base }),
        ("soft", ShadowSettings { method: ShadowMethod::Soft, ..base }),
        (
            "soft ring slb",
            ShadowSettings { method: ShadowMethod::Soft, points: PenumbraPoints::Ring, hard: HardShadows::Slb, ..base },
        ),
        ("pcss", ShadowSettings { method: ShadowMethod::Pcss, ..base }),
    ];
    let mut failed = Vec::new();
    for (name, scene) in &scenes {
        let Some(bounds) = scene.caster_bounds() else { continue };
        for (method, settings) in &methods {
            for (i, light) in scene.lights.iter().enumerate().filter(|(_, l)| l.casts_shadows()) {
                let light = Light { shadow: *settings, size: light.size.max(0.05), ..light.clone() };
                let built = ShadowTerm::build(scene, &light).memory_bytes();
                let budget = ShadowTerm::bytes_needed(&light, bounds);
                println!("{name:<12} light {i} {method:<14} built {built:>10} budget {budget:>10}");
                if built > budget || 3 * built < budget {
                    failed.push(format!("{name} light {i} {method}: built {built} bytes, budget {budget}"));
                }
            }
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}

/// A cube on a ground, seen from `view` (azimuth, elevation in degrees), lit
/// by `light`: the cube's faces that face the light are lit everywhere (no
/// caster lies between them and it).
fn cube_on_ground(view: (f32, f32), light: Light) -> Scene {
    let dir = |(az, el): (f32, f32)| {
        let (az, el) = (az.to_radians(), el.to_radians());
        Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos())
    };
    let mut scene = common::scene_with(shapes::cube(), towards_origin(dir(view) * 4.0), 320, 240, false);
    let ground =
        Affine3A::from_scale_rotation_translation(Vec3::splat(8.0), glam::Quat::IDENTITY, Vec3::new(0.0, -0.5, 0.0));
    scene.objects.push(Object::mesh("ground", Arc::new(shapes::plane()), ground, 0));
    scene.lights = vec![light];
    scene
}

/// Pixels of the cube's faces that face the light (N·L above 0.05) whose
/// shadow term is below 0.99: acne, since nothing lies between them and the
/// light. Returns (acne, lit-face pixels).
fn acne(scene: &Scene) -> (usize, usize) {
    let options = RenderOptions { shadow_images: true, ..RenderOptions::default() };
    let frame = render(scene, &options).unwrap();
    let normals = frame.normals(scene);
    let light = &scene.lights[0];
    let rays = scene.camera.pixel_rays(Vec2::new(scene.width as f32, scene.height as f32));
    let (mut bad, mut all) = (0, 0);
    for (i, (item, n)) in frame.visibility.items().iter().zip(&normals).enumerate() {
        if item.is_none() || item.object != 0 {
            continue;
        }
        let (x, y) = (i as u32 % scene.width, i as u32 / scene.width);
        let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
        let p = ray.at(scene.camera.distance_at_depth(&ray, frame.visibility.depth(x, y)));
        let to_light = light.incident(p).to_light;
        if n.dot(to_light) > 0.05 {
            all += 1;
            bad += usize::from(frame.shadows[0].get(x, y).x < 0.99);
        }
    }
    (bad, all)
}

#[test]
fn no_acne_on_the_lit_faces_of_a_cube() {
    let mut report = Vec::new();
    for el in [30.0f32, 40.0, 50.0, 60.0, 70.0, 80.0] {
        for az in [10.0f32, 35.0, 60.0] {
            let (a, e) = (az.to_radians(), el.to_radians());
            let towards = Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos());
            for (kind, light) in [
                ("sun", Light { kind: LightKind::Directional { direction: -towards }, ..Light::default() }),
                ("lamp", Light { kind: LightKind::Point { position: towards * 6.0 }, ..Light::default() }),
            ] {
                let scene = cube_on_ground((25.0, 30.0), light);
                let (bad, all) = acne(&scene);
                println!("{kind} el {el} az {az}: {bad} of {all}");
                if bad > 0 {
                    report
                        .push(format!("{kind} at elevation {el}°, azimuth {az}°: {bad} of {all} lit pixels shadowed"));
                }
            }
        }
    }
    assert!(report.is_empty(), "{report:#?}");
}

/// A thin lid (2 × 0.01 × 2, turned 20° about y) one unit over a ground, under
/// a sun at `elevation`°, its map `resolution`² texels: where the map's
/// decision on the ground differs from a shadow ray's, the rays' boundary
/// lies within one texel (the texel's footprint on the ground). Returns
/// (decisions farther than that, decisions compared).
fn thin_lid_error(elevation: f32, resolution: u32) -> (usize, usize) {
    let e = elevation.to_radians();
    let direction = -Vec3::new(e.cos() * 0.6, e.sin(), e.cos() * 0.8).normalize();
    let mut scene =
        cube_on_ground((0.0, 89.0), Light { kind: LightKind::Directional { direction }, ..Light::default() });
    scene.objects[0].transform = Affine3A::from_scale_rotation_translation(
        Vec3::new(2.0, 0.01, 2.0),
        glam::Quat::from_rotation_y(20f32.to_radians()),
        Vec3::new(0.0, 0.5, 0.0),
    );
    scene.lights[0].shadow = ShadowSettings { resolution, by_need: false, ..ShadowSettings::default() };
    let term = ShadowTerm::build(&scene, &scene.lights[0]);
    let map = &term.downcast_ref::<MapTerm>().expect("a sun's term is a map's").maps()[0];
    let settings = &scene.lights[0].shadow;
    let trace = kage::raytrace::TraceScene::new(&scene);
    let ground = Vec3::new(0.0, -0.5, 0.0);
    let lit =
        |p: Vec3| !trace.occluded(&kage::camera::Ray { origin: p + Vec3::Y * 1e-4, dir: -direction }, f32::INFINITY);
    let receiver = kage::shadows::Receiver { object: 1, plane: Vec3::Y };
    let cos = -direction.y;
    let (mut far, mut compared) = (0, 0);
    for i in 0..200 {
        for k in 0..200 {
            let p =
                ground + Vec3::new(-2.5 + 5.0 * (i as f32 + 0.5) / 200.0, 0.0, -2.5 + 5.0 * (k as f32 + 0.5) / 200.0);
            let Some(located) = map.locate(p, cos, settings, 1.0) else { continue };
            compared += 1;
            let truth = lit(p);
            if (term.lit(p, cos, &receiver) >= 0.5) == truth {
                continue;
            }
            // One texel across the light's rays, stretched on the ground.
            let reach = located.texel / cos;
            let near = (0..16).any(|a| {
                let t = a as f32 * std::f32::consts::TAU / 16.0;
                lit(p + Vec3::new(t.cos(), 0.0, t.sin()) * reach) != truth
            });
            far += usize::from(!near);
        }
    }
    (far, compared)
}

/// A thin plate's shadow boundary lies within a texel of the shadow rays'
/// everywhere: no light leaks under it, no boundary moves off it.
#[test]
fn a_thin_lids_shadow_boundary_is_within_a_texel_of_the_rays() {
    let mut report = Vec::new();
    for elevation in [25.0, 45.0, 70.0] {
        for resolution in [256, 1024] {
            let (far, compared) = thin_lid_error(elevation, resolution);
            println!("sun at {elevation}°, {resolution}²: {far} of {compared} decisions farther than a texel");
            if far > 0 || compared < 10_000 {
                report.push(format!("{elevation}° {resolution}²: {far} of {compared}"));
            }
        }
    }
    assert!(report.is_empty(), "{report:#?}");
}

/// PCSS eight points at a time decides as one point at a time: on the
/// visible surfaces of the demo and of the Cornell box (whose lamp's map is
/// a cube), every light's term from `lit_lanes` against `lit` for each lane.
#[test]
fn pcss_eight_points_at_a_time_match_one_at_a_time() {
    pcss_lanes_match_in(kage::scene::demo::demo_scene().unwrap());
    // A lamp inside a room: its map is a cube.
    let room =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/assets/scenes/cornell-box/CornellBox-Original.obj");
    pcss_lanes_match_in(kage::scene::model::scene_for_model(&room, 160, 120).unwrap());
}

/// [`pcss_eight_points_at_a_time_match_one_at_a_time`] in `scene`.
fn pcss_lanes_match_in(scene: Scene) {
    use kage::scene::ShadowMethod;
    let pcss = ShadowSettings { method: ShadowMethod::Pcss, ..ShadowSettings::default() };
    let (compared, differ, shadowed) = lanes_against_one_at_a_time(scene, pcss, Some(0.2), (160, 90));
    assert!(shadowed > 1000, "{shadowed} of {compared} points shadowed");
    assert!(differ * 1000 <= compared, "{differ} of {compared} points differ by more than a tap");
}

/// The silhouette-line buffer decides eight points at a time (most by one
/// look at what the texels round each hold) as it decides each on its own,
/// antialiased over the pixels' footprints, on the demo's and the Cornell
/// box's visible surfaces under point lights.
#[test]
fn slb_eight_points_at_a_time_match_one_at_a_time() {
    let room =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/assets/scenes/cornell-box/CornellBox-Original.obj");
    let scenes =
        [kage::scene::demo::demo_scene().unwrap(), kage::scene::model::scene_for_model(&room, 160, 120).unwrap()];
    // Texels wider than the pixels: most footprints reach a texel or less.
    let slb = ShadowSettings { resolution: 256, ..ShadowSettings::SLB };
    for scene in scenes {
        let (compared, differ, shadowed) = lanes_against_one_at_a_time(scene, slb, None, (640, 360));
        eprintln!("{differ} of {compared} differ, {shadowed} shadowed");
        assert!(shadowed > 1000, "{shadowed} of {compared} points shadowed");
        assert!(differ * 2000 <= compared, "{differ} of {compared} points differ by more than a tap");
    }
}

/// Every shadowed light's term of `scene` (at `pixels`, its lights set to
/// `shadow`, their size raised to `size` where given, else made points)
/// from `lit_lanes` against `lit` for each lane, at the points the pixels
/// show; for an antialiased method (the SLB) the terms see the pixels' rays
/// and each point's object and plane. (Points compared, differing by more
/// than a tap, shadowed.)
fn lanes_against_one_at_a_time(
    mut scene: Scene,
    shadow: ShadowSettings,
    size: Option<f32>,
    pixels: (u32, u32),
) -> (usize, usize, usize) {
    let antialiased = shadow.method == kage::scene::ShadowMethod::Slb;
    (scene.width, scene.height) = pixels;
    scene.lights.iter_mut().filter(|l| l.casts_shadows()).for_each(|l| {
        l.shadow = shadow;
        l.size = size.map_or(0.0, |s| l.size.max(s));
    });
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let normals = frame.normals(&scene);
    let rays = scene.camera.pixel_rays(Vec2::new(scene.width as f32, scene.height as f32));
    let points: Vec<(Vec3, Vec3, u32)> = (0..scene.height)
        .flat_map(|y| (0..scene.width).map(move |x| (x, y)))
        .filter(|&(x, y)| !frame.visibility.item(x, y).is_none())
        .map(|(x, y)| {
            let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let p = ray.at(scene.camera.distance_at_depth(&ray, frame.visibility.depth(x, y)));
            (p, normals[(y * scene.width + x) as usize], frame.visibility.item(x, y).object)
        })
        .collect();
    let (mut compared, mut differ, mut shadowed) = (0, 0, 0);
    for light in scene.lights.iter().filter(|l| l.casts_shadows()) {
        let mut term = ShadowTerm::build(&scene, light);
        if antialiased {
            term.set_view(Some(kage::shadows::PixelView::new(&rays)));
        }
        for chunk in points.chunks_exact(8) {
            let lane = |k: usize| wide::f32x8::new(std::array::from_fn(|i| chunk[i].0[k]));
            let cos: [f32; 8] = std::array::from_fn(|i| chunk[i].1.dot(light.incident(chunk[i].0).to_light).max(0.01));
            let receivers = if antialiased {
                let plane = |k: usize| wide::f32x8::new(std::array::from_fn(|i| chunk[i].1[k]));
                kage::shadows::ReceiverLanes {
                    objects: std::array::from_fn(|i| chunk[i].2),
                    planes: [0, 1, 2].map(plane),
                }
            } else {
                kage::shadows::ReceiverLanes::UNKNOWN
            };
            let lanes = term.lit_lanes([lane(0), lane(1), lane(2)], wide::f32x8::new(cos), &receivers).to_array();
            for i in 0..8 {
                let one = term.lit(chunk[i].0, cos[i], &receivers.lane(i));
                compared += 1;
                shadowed += usize::from(one < 1.0);
                differ += usize::from((one - lanes[i]).abs() > 1.0 / 16.0 + 1e-6);
            }
        }
    }
    (compared, differ, shadowed)
}
