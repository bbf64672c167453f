//! The silhouette-line buffer (seed 000) against shadow rays through the BVH:
//! the example scenes, random scenes of meshes and CSG solids at scales 1, 16
//! and 64, a
//! closed mesh's lines, an object shadowing itself, and the antialiased term
//! against 16 × 16 shadow rays per pixel; the scene file's keys.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::csg::{ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Shape};
use kage::raytrace::shadow_truth;
use kage::scene::mesh::shapes;
use kage::scene::{Body, Light, LightKind, Material, Mesh, Object, Scene, ShadowMethod};
use kage::shadows::ShadowTerm;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// `scene` with every light's shadows by `method`.
fn with_method(mut scene: Scene, method: ShadowMethod) -> Scene {
    scene.lights.iter_mut().for_each(|l| l.shadow = l.shadow.with_method(method));
    scene
}

/// Share of lit tests where the term and shadow rays disagree, and the count.
fn disagreement(scene: &Scene) -> (f64, usize, usize) {
    let (wrong, total) = common::terms_vs_rays(scene, &ShadowTerm::build_all(scene));
    (wrong as f64 / total.max(1) as f64, wrong, total)
}

#[test]
fn slb_agrees_with_shadow_rays_on_the_example_scenes_better_than_maps() {
    for (name, scene) in common::shadow_example_scenes() {
        let (map, map_wrong, _) = disagreement(&with_method(scene.clone(), ShadowMethod::Map));
        let (slb, slb_wrong, total) = disagreement(&with_method(scene, ShadowMethod::Slb));
        eprintln!("{name}: map {:.3}%, slb {:.3}% of {total}", 100.0 * map, 100.0 * slb);
        assert!(total > 10_000, "{name}: only {total} tests");
        assert!(slb < 0.0005, "{name}: the SLB disagrees with shadow rays on {slb_wrong} of {total}");
        assert!(slb_wrong <= map_wrong, "{name}: SLB {slb_wrong} > map {map_wrong}");
    }
}

/// A 45° camera at `eye` looking at the origin, far plane `far`.
fn looking_at_origin(eye: Vec3, far: f32) -> Camera {
    let projection = Projection::Perspective { fov_y_deg: 45.0 };
    Camera { eye, target: Vec3::ZERO, up: Vec3::Y, near: 0.1, far, projection, shift: Vec2::ZERO }
}

/// A CSG solid of two primitives (sphere, cylinder or cone, box) joined,
/// intersected or one cut from the other, placed at random.
fn random_solid(rng: &mut StdRng, name: String) -> Object {
    let primitive = |rng: &mut StdRng| {
        let shape = match rng.gen_range(0..3) {
            0 => Shape::Sphere,
            1 => Shape::Frustum { bottom: 1.0, top: if rng.gen_bool(0.5) { 1.0 } else { rng.gen_range(0.0..1.0) } },
            _ => Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
        };
        let s = Vec3::new(rng.gen_range(0.3..0.9), rng.gen_range(0.3..0.9), rng.gen_range(0.3..0.9));
        let r = Quat::from_euler(glam::EulerRot::XYZ, rng.gen_range(0.0..3.0), rng.gen_range(0.0..3.0), 0.0);
        let t = Vec3::new(rng.gen_range(-0.4..0.4), rng.gen_range(-0.4..0.4), rng.gen_range(-0.4..0.4));
        Primitive { shape, transform: Affine3A::from_scale_rotation_translation(s, r, t), color: None, source: 0..0 }
    };
    let primitives = vec![primitive(rng), primitive(rng)];
    let (a, b) = (CsgTree::Leaf(0), CsgTree::Leaf(1));
    let tree = match rng.gen_range(0..3) {
        0 => CsgTree::Union(vec![a, b]),
        1 => CsgTree::Intersection(vec![a, b]),
        _ => CsgTree::Difference(Box::new(a), vec![b]),
    };
    let solid = Arc::new(CsgSolid { primitives, tree: Some(tree) });
    let at = Vec3::new(rng.gen_range(-2.5..2.5), rng.gen_range(0.3..2.0), rng.gen_range(-2.5..2.5));
    let body = Body::Solid { solid, materials: Arc::from([1, 1]) };
    Object { name, body, transform: Affine3A::from_translation(at), material: 1, casts_shadows: true, ghost: false }
}

/// A floor, and 3–8 cubes, spheres and CSG solids above it at random, under
/// a spot or a directional light from a random direction, seen from above at
/// an angle.
fn random_scene(rng: &mut StdRng) -> Scene {
    let camera = looking_at_origin(Vec3::new(rng.gen_range(-3.0..3.0), 6.0, 6.0), 50.0);
    let mut scene = common::scene_with(shapes::plane(), camera, 160, 120, false);
    scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(12.0));
    scene.materials.push(Material::default());
    for k in 0..rng.gen_range(3..9) {
        if rng.gen_bool(0.3) {
            let solid = random_solid(rng, format!("o{k}"));
            scene.objects.push(solid);
            continue;
        }
        let mesh: Mesh = if rng.gen_bool(0.5) { shapes::cube() } else { shapes::sphere(rng.gen_range(6..24)) };
        let s = Vec3::new(rng.gen_range(0.2..1.0), rng.gen_range(0.2..1.0), rng.gen_range(0.2..1.0));
        let r = Quat::from_euler(glam::EulerRot::XYZ, rng.gen_range(0.0..3.0), rng.gen_range(0.0..3.0), 0.0);
        let t = Vec3::new(rng.gen_range(-2.5..2.5), rng.gen_range(0.3..2.0), rng.gen_range(-2.5..2.5));
        let transform = Affine3A::from_scale_rotation_translation(s, r, t);
        scene.objects.push(Object::mesh(format!("o{k}"), Arc::new(mesh), transform, 1));
    }
    let from = Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(0.6..1.5), rng.gen_range(-1.0..1.0)).normalize();
    let kind = if rng.gen_bool(0.5) {
        LightKind::Directional { direction: -from }
    } else {
        let position = from * 8.0;
        LightKind::Spot { position, direction: -from, inner: 0.5, outer: 0.6 }
    };
    scene.lights = vec![Light { kind, ..Light::default() }];
    scene
}

/// On random scenes of meshes and solids (cubes, spheres and CSG solids of
/// two primitives, which may pierce the floor and each other) the SLB's
/// decisions equal shadow rays on at least 99.9% of the visible points the
/// light faces, at scale 1 and with the virtual projection space 16 and 64
/// times wider, where a texel holds a whole caster and its contact with the
/// floor. The points on solids are also counted on their own, held to 1%:
/// where a solid shadows itself (a union's inner corner, a cut's walls) no
/// line records the step, and a ray through the solid decides.
#[test]
fn slb_decisions_equal_shadow_rays_on_random_scenes_at_scales_1_16_and_64() {
    let mut rng = StdRng::seed_from_u64(36);
    for scale in [1.0, 16.0, 64.0] {
        let (mut wrong, mut total, mut solid_wrong, mut solid_total) = (0, 0, 0, 0);
        for _ in 0..6 {
            let mut scene = with_method(random_scene(&mut rng), ShadowMethod::Slb);
            scene.lights[0].shadow.scale = scale;
            let terms = ShadowTerm::build_all(&scene);
            let on_solid = |o: u32| scene.objects[o as usize].solid().is_some();
            let judge = |solids_only: bool| {
                common::decisions_vs_rays(&scene, |light, at| {
                    let receiver = at.receiver();
                    (!solids_only || on_solid(at.object))
                        .then(|| terms[light].lit(at.surface.position, at.cos_theta, &receiver))
                })
            };
            let ((w, t), (sw, st)) = (judge(false), judge(true));
            (wrong, total, solid_wrong, solid_total) = (wrong + w, total + t, solid_wrong + sw, solid_total + st);
        }
        eprintln!("scale {scale}: {wrong} of {total} disagree; on solids {solid_wrong} of {solid_total}");
        assert!(total > 30_000, "scale {scale}: only {total} tests");
        assert!((wrong as f64) <= 0.001 * total as f64, "scale {scale}: {wrong} of {total} disagree with shadow rays");
        assert!(solid_wrong * 100 <= solid_total, "scale {scale}: {solid_wrong} of {solid_total} on solids");
    }
}

/// A closed mesh leaves no shared lines: every texel the buffer keeps for a
/// lone sphere lies on its outline as the light sees it, none inside.
#[test]
fn a_closed_mesh_keeps_only_its_outline() {
    let (res, radius_texels) = (256u32, 80.0f32);
    let camera = Camera {
        eye: Vec3::new(0.0, 10.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::Z,
        near: 0.1,
        far: 20.0,
        projection: Projection::Orthographic { height: 2.0 * res as f32 / (2.0 * radius_texels) },
        shift: Vec2::ZERO,
    };
    let mut scene = common::scene_with(shapes::sphere(32), camera, 64, 64, false);
    scene.objects[0].transform = Affine3A::IDENTITY;
    let map = kage::shadows::SlbMap::render(
        &scene,
        &camera,
        res,
        &[true],
        kage::visibility::Workers::All,
        kage::visibility::VisibilityBuffer::depth_only(0, 0),
        &kage::scene::ShadowSettings::SLB,
    );
    let slb = map.buffer();
    let stats = slb.stats();
    assert!(slb.edge_texels() > 400, "{} edge texels", slb.edge_texels());
    assert!(stats.shared > 5 * slb.line_count(), "{stats:?}: most edges are shared");
    let centre = res as f32 / 2.0;
    for y in 0..res {
        for x in 0..res {
            if slb.is_edge(x, y) {
                let r = Vec2::new(x as f32 + 0.5 - centre, y as f32 + 0.5 - centre).length();
                // The polygon's outline lies between the inscribed and the
                // circumscribed circles of its 64-gon.
                assert!((r - radius_texels).abs() < 2.0, "edge texel ({x}, {y}) at radius {r}");
            }
        }
    }
}

/// One mesh of `parts`, each placed by its transform.
fn joined(parts: Vec<(Mesh, Affine3A)>) -> Mesh {
    let mut out = Mesh::default();
    for (part, at) in parts {
        let base = out.positions.len() as u32;
        out.positions.extend(part.positions.iter().map(|p| at.transform_point3(*p)));
        out.normals.extend(part.normals.iter().map(|n| at.transform_vector3(*n).normalize()));
        out.uvs.extend(part.uvs);
        out.triangles.extend(part.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    out
}

/// An object shadows itself: a bent plate (one mesh, an L whose upright
/// shades its foot) under a low light, as shadow rays say.
#[test]
fn a_bent_plate_shadows_itself_as_rays_say() {
    let stand = Affine3A::from_rotation_translation(
        Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
        Vec3::new(0.0, 0.5, -0.5),
    );
    let mesh = joined(vec![(shapes::plane(), Affine3A::IDENTITY), (shapes::plane(), stand)]);
    let camera = Camera {
        eye: Vec3::new(0.0, 2.0, 2.5),
        target: Vec3::new(0.0, 0.2, 0.0),
        up: Vec3::Y,
        near: 0.1,
        far: 20.0,
        projection: Projection::Perspective { fov_y_deg: 40.0 },
        shift: Vec2::ZERO,
    };
    let mut scene = common::scene_with(mesh, camera, 320, 240, true);
    scene.lights = vec![Light {
        kind: LightKind::Directional { direction: Vec3::new(0.3, -0.6, 1.0).normalize() },
        ..Light::default()
    }];
    let scene = with_method(scene, ShadowMethod::Slb);
    let terms = ShadowTerm::build_all(&scene);
    // Points on the foot behind the upright are in its shadow.
    let shade = terms[0].lit(Vec3::new(0.0, 0.0, -0.35), 1.0, &kage::shadows::Receiver::of_object(0));
    assert_eq!(shade, 0.0, "the foot behind the upright is lit");
    let (share, wrong, total) = disagreement(&scene);
    assert!(total > 5000 && share < 0.002, "{wrong} of {total} disagree with shadow rays");
}

/// An object shadows itself as closely as shadow rays say: Keenan Crane's
/// cow (a closed mesh of 5,856 triangles, `kage render`'s set-up for a lone
/// model) under its key light. Told which way the receiver's triangle faces,
/// the SLB holds the receiver's own surfaces that face the light the other
/// way to the small bias of other objects' surfaces (they cannot be the
/// sheet the receiver lies on): fewer of its decisions differ from shadow
/// rays than when only the receiver's object is known.
#[test]
fn an_object_shadows_itself_as_closely_as_rays_say() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/spot_triangulated.obj");
    let mut scene = kage::scene::model::scene_for_model(&path, 640, 360).expect("the cow loads");
    scene.lights.iter_mut().for_each(|l| l.size = 0.0);
    let scene = with_method(scene, ShadowMethod::Slb);
    let terms = ShadowTerm::build_all(&scene);
    let judged = |plane_known: bool| {
        common::decisions_vs_rays(&scene, |light, at| {
            let receiver = if plane_known { at.receiver() } else { kage::shadows::Receiver::of_object(at.object) };
            terms[light].casts().then(|| terms[light].lit(at.surface.position, at.cos_theta, &receiver))
        })
    };
    let ((facing, total), (object_only, _)) = (judged(true), judged(false));
    eprintln!("cow: {facing} of {total} disagree with shadow rays; {object_only} with the receiver's object alone");
    assert!(total > 50_000, "only {total} tests");
    assert!(facing * 10 <= object_only * 7, "{facing} disagree, against {object_only} by the object alone");
    assert!(facing as f64 <= 3e-4 * total as f64, "{facing} of {total} disagree");
}

/// The antialiased SLB term against 16 × 16 shadow rays per pixel, on the
/// pixels along shadow boundaries (where the 0/1 term changes within a
/// pixel's 3 × 3 neighbourhood, on one object): its RMSE is at most a third
/// of the 0/1 term's.
#[test]
fn the_antialiased_boundary_is_a_third_as_far_from_the_ray_traced_coverage() {
    let mut scenes: Vec<Scene> = common::shadow_example_scenes()
        .into_iter()
        .filter(|(name, _)| ["spotlights", "cad-ortho"].contains(name))
        .map(|(_, s)| s)
        .collect();
    let mut rng = StdRng::seed_from_u64(7);
    scenes.extend((0..2).map(|_| random_scene(&mut rng)));
    let (mut sharp_total, mut smooth_total, mut count) = (0.0, 0.0, 0);
    for scene in scenes {
        let scene = with_method(scene, ShadowMethod::Slb);
        let options = kage::RenderOptions { shadow_images: true, ..kage::RenderOptions::default() };
        let images = |antialias: bool| {
            let mut s = scene.clone();
            s.lights.iter_mut().for_each(|l| l.shadow.antialias = antialias);
            kage::render(&s, &options).unwrap()
        };
        let (sharp, smooth) = (images(false), images(true));
        let rays = shadow_truth::ShadowRays::new(&scene);
        for light in 0..scene.lights.len() {
            let (hard, soft) = (sharp.shadows[light].pixels(), smooth.shadows[light].pixels());
            let pixels = shadow_truth::boundary_pixels(&sharp.visibility, hard);
            let truth = rays.covered_share(light, &pixels, 16);
            let (a, n) = shadow_truth::rmse_at(hard, scene.width, &pixels, &truth);
            let (b, _) = shadow_truth::rmse_at(soft, scene.width, &pixels, &truth);
            eprintln!("light {light}: {n} boundary pixels, RMSE 0/1 {a:.4}, antialiased {b:.4}");
            (sharp_total, smooth_total, count) =
                (sharp_total + a * a * n as f64, smooth_total + b * b * n as f64, count + n);
        }
    }
    let (sharp, smooth) = ((sharp_total / count as f64).sqrt(), (smooth_total / count as f64).sqrt());
    eprintln!("all: {count} pixels, RMSE 0/1 {sharp:.4}, antialiased {smooth:.4} ({:.2}x)", smooth / sharp);
    assert!(count > 2000, "only {count} boundary pixels");
    assert!(smooth <= sharp / 3.0, "antialiased RMSE {smooth:.4} vs 0/1 {sharp:.4}");
}

/// A scene file's `shadow` table sets the SLB's keys, each to what it says.
#[test]
fn a_scene_file_sets_the_slb_keys() {
    let text = "[[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\n\
                shadow = { method = \"slb\", bits = 12, scale = 4, antialias = false }\n\
                [[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nshadow = { method = \"slb\" }\n\
                [[object]]\nshape = \"cube\"\n";
    let fs = kage::scene::load::FileSystem { base: std::env::temp_dir() };
    let scene =
        kage::scene::file::SceneFile::parse(text, std::path::Path::new("slb.toml")).unwrap().build(&fs).unwrap();
    let (set, default) = (scene.lights[0].shadow, scene.lights[1].shadow);
    assert_eq!((set.method, set.bits, set.scale, set.antialias), (ShadowMethod::Slb, 12, 4.0, false));
    assert_eq!((default.bits, default.scale, default.antialias, default.resolution), (8, 1.0, true, 1024));
}

/// The examples that show the method — a heat sink whose fins shadow each
/// other (one mesh), an atrium under a pergola of slats — agree with shadow
/// rays more closely with the SLB their files ask for than with maps.
#[test]
fn the_slb_examples_agree_with_shadow_rays_better_than_maps() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes");
    for name in ["heatsink", "atrium"] {
        let mut scene = kage::scene::file::load_scene(&dir.join(format!("{name}.toml"))).unwrap();
        (scene.width, scene.height) = (320, 200);
        assert!(scene.lights.iter().all(|l| l.shadow.method == ShadowMethod::Slb), "{name} asks for the SLB");
        let (slb, slb_wrong, total) = disagreement(&scene);
        let (map, map_wrong, _) = disagreement(&with_method(scene, ShadowMethod::Map));
        eprintln!("{name}: map {:.3}%, slb {:.3}% of {total}", 100.0 * map, 100.0 * slb);
        assert!(total > 10_000 && slb < 0.0005, "{name}: the SLB disagrees with shadow rays on {slb_wrong} of {total}");
        assert!(slb_wrong < map_wrong, "{name}: SLB {slb_wrong} ≥ map {map_wrong}");
    }
}

/// Boxes under a sun 12° above the floor, the view 16 times wider: a box's
/// whole shadow lies within the floor's own slope bias (about 8 texels at
/// that angle), so the texels no outline crosses must hold the box to the
/// box's bias, not the floor's (the map keeps each texel's object).
#[test]
fn long_grazing_shadows_stay_with_the_view_16_times_wider() {
    let camera = looking_at_origin(Vec3::new(0.0, 7.0, 9.0), 60.0);
    let mut scene = common::scene_with(shapes::plane(), camera, 320, 200, false);
    scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(30.0));
    let cube = Arc::new(shapes::cube());
    for k in 0..9 {
        let at = Vec3::new(-3.0 + 3.0 * (k % 3) as f32, 0.4, -3.0 + 3.0 * (k / 3) as f32);
        let transform =
            Affine3A::from_scale_rotation_translation(Vec3::splat(0.8), Quat::from_rotation_y(0.4 * k as f32), at);
        scene.objects.push(Object::mesh(format!("box {k}"), cube.clone(), transform, 0));
    }
    let sun = 12f32.to_radians();
    let direction = -Vec3::new(0.8 * sun.cos(), sun.sin(), 0.6 * sun.cos()).normalize();
    scene.lights = vec![Light { kind: LightKind::Directional { direction }, ..Light::default() }];
    let mut scene = with_method(scene, ShadowMethod::Slb);
    scene.lights[0].shadow.scale = 16.0;
    let (share, wrong, total) = disagreement(&scene);
    assert!(total > 20_000 && share < 0.001, "{wrong} of {total} disagree with shadow rays");
}
