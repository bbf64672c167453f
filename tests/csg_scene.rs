//! CSG solids as part of the frame: a `.csg` object in a scene file, next
//! to meshes, drawn into the same visibility buffer by the scanline walk, shaded,
//! shadowed and reflected like everything else. The oracle is the ray tracer: its
//! BVH holds the same solids as leaves and casts their rays by interval
//! arithmetic, a path that shares nothing with the scanline walk and the z-buffer
//! but the per-primitive interval routine.

use std::path::{Path, PathBuf};

use glam::Vec2;
use kage::raytrace::reference::{render_reference, ReferenceOptions};
use kage::raytrace::TraceScene;
use kage::scene::file::SceneFile;
use kage::scene::load::FileSystem;
use kage::scene::{Scene, ShadowSettings};
use kage::visibility::ItemId;
use kage::{render, RenderOptions};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/csg")
}

/// OpenSCAD's cube minus sphere (z up, 30 units), turned y-up and scaled to 1.5,
/// cut into by a mesh cube, over a polished floor, one point light.
fn scene(width: u32, height: u32) -> Scene {
    let text = format!(
        r#"
[image]
width = {width}
height = {height}

[camera]
eye = [2.2, 2.0, 3.4]
target = [0.1, 0.6, 0.0]
fov = 40

[[light]]
type = "point"
position = [-2.0, 5.0, 3.0]
intensity = 0.9
ambient = 0.15

[[material]]
name = "floor"
kd = [0.5, 0.5, 0.5]
ks = [0.0, 0.0, 0.0]
kr = [0.3, 0.3, 0.3]

[[material]]
name = "blue"
kd = [0.1, 0.2, 0.8]

[[object]]
name = "part"
mesh = "ex004_cube_minus_sphere.csg"
scale = 0.05
translate = [0.0, 0.75, 0.0]

[[object]]
name = "block"
shape = "cube"
scale = 0.8
translate = [0.7, 0.4, 0.4]
material = "blue"

[[object]]
shape = "plane"
scale = 8.0
material = "floor"
"#
    );
    let file = SceneFile::parse(&text, &data().join("scene.toml")).unwrap();
    // Aliased: compared pixel centre for pixel centre with rays.
    Scene { antialias: kage::scene::Antialias::None, ..file.build(&FileSystem { base: data() }).unwrap() }
}

fn without_shadows(mut scene: Scene) -> Scene {
    scene.lights.iter_mut().for_each(|l| l.shadow = ShadowSettings::NONE);
    scene
}

/// The solid's pixels hold its primitives, the mesh's its triangles, and each
/// pixel shows what the ray through its centre meets first.
#[test]
fn solids_and_meshes_hide_each_other_as_rays_see_them() {
    let scene = without_shadows(scene(240, 160));
    let frame = render(&scene, &RenderOptions { ray_depth: 0, ..Default::default() }).unwrap();
    let trace = TraceScene::new(&scene);
    let rays = scene.camera.pixel_rays(Vec2::new(240.0, 160.0));
    let (mut agree, mut differ, mut solid, mut block) = (0, 0, 0, 0);
    for y in 0..160 {
        for x in 0..240 {
            let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let hit = trace.intersect(&ray, f32::INFINITY);
            let item = frame.visibility.item(x, y);
            if hit.map_or(ItemId::NONE, |h| h.item) != item {
                differ += 1;
                continue;
            }
            agree += 1;
            solid += usize::from(item.primitive().is_some());
            block += usize::from(item.object == 1);
            if let Some(h) = hit {
                let t = scene.camera.distance_at_depth(&ray, frame.visibility.depth(x, y));
                assert!((t - h.t).abs() < 1e-3 * h.t, "({x}, {y}): depth {t} vs ray {}", h.t);
            }
        }
    }
    assert!(solid > 3000 && block > 1500, "both must show: {solid} solid pixels, {block} block pixels");
    assert!(differ * 500 < agree, "{differ} pixels see another item than the ray ({agree} agree)");
}

/// With one ray per pixel and no shadows, the reference and the raster pipeline
/// compute the same colour wherever they see the same item, the floor's traced
/// reflection of the solid included.
#[test]
fn a_solid_is_shaded_and_reflected_as_the_reference_sees_it() {
    let scene = without_shadows(scene(200, 130));
    let frame = render(&scene, &RenderOptions { ray_depth: 2, ..Default::default() }).unwrap();
    let opts = ReferenceOptions {
        pixel_samples: 1,
        light_samples: 1,
        shadows: false,
        max_depth: 2,
        ..ReferenceOptions::default()
    };
    let reference = render_reference(&scene, &opts, &|_| {});
    let trace = TraceScene::new(&scene);
    let rays = scene.camera.pixel_rays(Vec2::new(200.0, 130.0));
    let (mut compared, mut off, mut solid_in_floor) = (0, 0, 0);
    for y in 0..130 {
        for x in 0..200 {
            let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let item = frame.visibility.item(x, y);
            if trace.intersect(&ray, f32::INFINITY).map_or(ItemId::NONE, |h| h.item) != item {
                continue;
            }
            compared += 1;
            let (r, f) = (reference.get(x, y), frame.image.get(x, y));
            off += usize::from((r - f).abs().max_element() > 2e-3);
            if item.object == 2 {
                // The floor: does it mirror the solid here?
                let s = kage::shading::ObjectFrames::new(&scene).surface(&scene, item, &ray);
                let dir = ray.dir - 2.0 * ray.dir.dot(s.normal) * s.normal;
                let bounce = kage::camera::Ray { origin: s.position + s.normal * 1e-4, dir };
                solid_in_floor +=
                    usize::from(trace.intersect(&bounce, f32::INFINITY).is_some_and(|h| h.item.primitive().is_some()));
            }
        }
    }
    assert!(solid_in_floor > 300, "the floor must mirror the solid ({solid_in_floor} pixels)");
    // A secondary ray starts from the point the depth buffer gives (f32) rather
    // than the ray's own hit: a few pixels along reflected outlines may differ.
    assert!(off * 200 < compared, "{off} of {compared} pixels differ from the reference");
}

/// The light's depth pass runs the scanline walk too: the solid darkens the
/// floor where shadow rays say it should.
#[test]
fn a_solid_casts_shadows_where_shadow_rays_find_it() {
    let mut lit = scene(200, 130);
    lit.lights.iter_mut().for_each(|l| l.shadow = ShadowSettings { samples: 1, ..ShadowSettings::default() });
    let plain = without_shadows(lit.clone());
    let opts = RenderOptions { ray_depth: 0, ..Default::default() };
    let (shadowed, unshadowed) = (render(&lit, &opts).unwrap(), render(&plain, &opts).unwrap());
    let reference = render_reference(
        &lit,
        &ReferenceOptions {
            pixel_samples: 1,
            light_samples: 1,
            shadows: true,
            max_depth: 0,
            ..ReferenceOptions::default()
        },
        &|_| {},
    );
    let unlit = render_reference(&plain, &ReferenceOptions::CENTRES, &|_| {});
    let (mut floor, mut both, mut either) = (0, 0, 0);
    for y in 0..130 {
        for x in 0..200 {
            if shadowed.visibility.item(x, y).object != 2 {
                continue;
            }
            floor += 1;
            let dark = |a: glam::Vec3, b: glam::Vec3| (b - a).max_element() > 0.05;
            let raster = dark(shadowed.image.get(x, y), unshadowed.image.get(x, y));
            let rays = dark(reference.get(x, y), unlit.get(x, y));
            both += usize::from(raster && rays);
            either += usize::from(raster || rays);
        }
    }
    assert!(both > floor / 20, "the solid and the block must shade the floor ({both} of {floor} floor pixels)");
    // Shadow-map texels and the bias move the boundary by a pixel or so.
    assert!(both * 100 >= either * 90, "shadow masks: {both} agree of {either} shadowed by either");
}

/// A scene file's `.csg` object reads exact quadrics by default and OpenSCAD's
/// facets with `geometry = "faceted"`; a misspelt mode is a located error.
#[test]
fn scene_files_choose_the_geometry_of_csg_objects() {
    let build = |geometry: &str| {
        let text = format!("[[object]]\nmesh = \"ex004_cube_minus_sphere.csg\"\n{geometry}\n");
        SceneFile::parse(&text, &data().join("scene.toml")).and_then(|f| f.build(&FileSystem { base: data() }))
    };
    let polyhedra = |scene: &Scene| {
        let solid = scene.objects[0].solid().expect("a solid");
        solid.primitives.iter().all(|p| matches!(p.shape, kage::csg::Shape::Polyhedron(_)))
    };
    assert!(!polyhedra(&build("").unwrap()), "exact by default: the sphere is a quadric");
    assert!(polyhedra(&build("geometry = \"faceted\"").unwrap()), "faceted: every primitive a polyhedron");
    let e = build("geometry = \"facetted\"").unwrap_err().to_string();
    assert!(e.contains("scene.toml:3:12") && e.contains("faceted"), "{e}");
}

/// Under `antialias = edge`, a solid's outline pixels come out close to a
/// 64-pass supersampled truth, and pixels inside a solid's face are untouched.
#[test]
fn solid_outlines_are_antialiased_like_the_truth() {
    use kage::scene::Antialias;
    let mut scene = without_shadows(scene(200, 130));
    let opts = RenderOptions { ray_depth: 0, ..Default::default() };
    let aliased = render(&scene, &opts).unwrap();
    scene.antialias = Antialias::Edge(kage::scene::EdgeMode::default());
    let edge = render(&scene, &opts).unwrap();
    scene.antialias = Antialias::Jitter(64);
    let truth = render(&scene, &opts).unwrap();
    let vb = &aliased.visibility;
    let (mut outline, mut err_aliased, mut err_edge, mut inside) = (0, 0.0, 0.0, 0);
    for y in 1..129 {
        for x in 1..199 {
            let me = vb.item(x, y);
            let around = [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)].map(|(a, b)| vb.item(a, b));
            let on_solid_outline =
                around.iter().any(|&n| n != me && (n.primitive().is_some() || me.primitive().is_some()));
            let (a, e, t) = (aliased.image.get(x, y), edge.image.get(x, y), truth.image.get(x, y));
            if on_solid_outline {
                outline += 1;
                err_aliased += (a - t).length_squared();
                err_edge += (e - t).length_squared();
            } else if me.primitive().is_some() && around.iter().all(|&n| n == me) {
                inside += 1;
                assert_eq!(a, e, "({x}, {y}) inside a solid's face changed");
            }
        }
    }
    assert!(outline > 300 && inside > 1000, "{outline} outline and {inside} inner pixels");
    let (ra, re) = ((err_aliased / outline as f32).sqrt(), (err_edge / outline as f32).sqrt());
    assert!(re < 0.5 * ra, "outline RMSE vs 64 passes: aliased {ra:.4}, edge pass {re:.4}");
}
