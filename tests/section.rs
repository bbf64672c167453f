//! Section planes: a ball cut at its centre shows a disc of the cap colour of
//! the ball's radius, as a mesh and as a CSG solid; a section of an OpenSCAD
//! part equals the part intersected with a cube in the file.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Vec3};
use kage::camera::{Camera, Projection};
use kage::csg::{CsgSolid, CsgTree, Primitive, Shape};
use kage::scene::mesh::shapes;
use kage::scene::section::{SectionPlane, CAP_MATERIAL};
use kage::scene::{Antialias, Body, Object, Scene};
use kage::{render, RenderOptions};
use rand::rngs::StdRng;
use rand::SeedableRng;

/// Pixels across the view's height, which spans 3 units: 1 unit = 60 pixels.
const SIZE: u32 = 180;

/// A unit ball (a mesh, or a CSG sphere) at the origin seen straight down the
/// z axis in parallel projection.
fn ball(solid: bool) -> Scene {
    let mut rng = StdRng::seed_from_u64(3);
    let mut scene = common::scene_with(shapes::sphere(64), common::random_camera(&mut rng, false), SIZE, SIZE, false);
    scene.camera = Camera {
        eye: Vec3::new(0.0, 0.0, 5.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        near: 0.1,
        far: 20.0,
        projection: Projection::Orthographic { height: 3.0 },
        ..scene.camera
    };
    scene.antialias = Antialias::None;
    if solid {
        let sphere = Primitive { shape: Shape::Sphere, transform: Affine3A::IDENTITY, color: None, source: 0..0 };
        let solid = CsgSolid { primitives: vec![sphere], tree: Some(CsgTree::Leaf(0)) };
        scene.objects[0] = Object {
            body: Body::Solid { solid: Arc::new(solid), materials: Arc::from([0]) },
            ..scene.objects[0].clone()
        };
    }
    scene
}

/// Pixels whose surface is in the cap material.
fn cap_pixels(scene: &Scene) -> usize {
    let frame = render(scene, &RenderOptions::default()).expect("render");
    let cap = scene.materials.iter().position(|m| m.name == CAP_MATERIAL).expect("a cap material");
    frame.visibility.items().iter().filter(|i| !i.is_none() && i.material(scene) == cap).count()
}

#[test]
fn a_ball_cut_at_its_centre_shows_a_disc_of_the_cap_colour_of_its_radius() {
    for solid in [false, true] {
        for (depth, radius) in [(0.0f32, 1.0f32), (0.6, 0.8)] {
            // Keep z ≤ depth: the eye on +z sees the cut face first.
            let mut scene = ball(solid);
            let report = scene.section(SectionPlane::through(Vec3::Z * depth, Vec3::Z).expect("a plane"));
            assert_eq!(report.capped, 1, "solid {solid}: the ball is capped");
            let disc = std::f32::consts::PI * (radius * 60.0).powi(2);
            let seen = cap_pixels(&scene) as f32;
            assert!(
                (seen - disc).abs() < 0.02 * disc,
                "solid {solid}, cut at {depth}: {seen} pixels, a disc of {disc}"
            );
        }
        // From the other side the cap faces away: the ball's own surface shows.
        let mut scene = ball(solid);
        scene.section(SectionPlane::through(Vec3::ZERO, -Vec3::Z).expect("a plane"));
        assert_eq!(cap_pixels(&scene), 0, "solid {solid}: the cap is behind the half ball");
    }
}

#[test]
fn a_plane_beyond_everything_removes_it_and_one_behind_keeps_it() {
    let mut gone = ball(false);
    let report = gone.section(SectionPlane::through(Vec3::Z * -2.0, Vec3::Z).expect("a plane"));
    assert_eq!((report.removed, gone.objects.len()), (1, 0));
    assert!(gone.warnings.iter().any(|w| w.contains("nothing is left")), "{:?}", gone.warnings);
    let mut kept = ball(true);
    let report = kept.section(SectionPlane::through(Vec3::Z * 2.0, Vec3::Z).expect("a plane"));
    assert_eq!((report.removed, report.capped, kept.objects.len()), (0, 0, 1));
}

#[test]
fn a_plane_on_a_solids_face_with_the_solid_beyond_leaves_nothing_from_any_side() {
    // A box standing on z = 0 (turned about z, so its faces are not the
    // plane's to the bit), cut keeping z ≤ 0: the regularized answer is
    // empty, not a sheet of spans of no length seen from some sides.
    let turned = Affine3A::from_rotation_z(0.7) * Affine3A::from_scale(Vec3::new(1.3, 0.9, 1.1));
    let cube = Primitive {
        shape: Shape::Polyhedron(kage::csg::ConvexPolyhedron::unit_cube()),
        transform: turned * Affine3A::from_translation(Vec3::new(-0.5, -0.5, 0.0)),
        color: None,
        source: 0..0,
    };
    let mut rng = StdRng::seed_from_u64(11);
    let mut seen = Vec::new();
    for view in 0..24 {
        let mut scene = ball(true);
        let solid = CsgSolid { primitives: vec![cube.clone()], tree: Some(CsgTree::Leaf(0)) };
        scene.objects[0].body = Body::Solid { solid: Arc::new(solid), materials: Arc::from([0]) };
        scene.camera = common::random_camera(&mut rng, view % 2 == 0);
        let report = scene.section(SectionPlane::through(Vec3::ZERO, Vec3::Z).expect("a plane"));
        assert_eq!(report.capped, 1, "the plane crosses the solid's box");
        let mut vb = kage::visibility::VisibilityBuffer::new(SIZE, SIZE);
        kage::visibility::rasterize(&scene, &mut vb);
        seen.push(vb.items().iter().filter(|i| !i.is_none()).count());
    }
    assert!(seen.iter().all(|&n| n == 0), "pixels drawn per view: {seen:?}");
}

#[test]
fn an_open_mesh_cut_shows_its_inside_and_says_so() {
    let mut scene = ball(false);
    scene.objects[0].body = Body::Mesh(Arc::new(shapes::plane()));
    scene.objects[0].transform = Affine3A::from_rotation_x(std::f32::consts::FRAC_PI_2);
    let report = scene.section(SectionPlane::through(Vec3::X * 0.1, Vec3::X).expect("a plane"));
    assert_eq!(report.open.len(), 1);
    assert!(scene.warnings.iter().any(|w| w.contains("not closed")), "{:?}", scene.warnings);
    assert!(scene.materials[scene.objects[0].material].two_sided, "its inside shows");
}

#[test]
fn a_scene_files_section_cuts_its_objects_and_a_bad_one_says_where() {
    use kage::scene::file::SceneFile;
    use kage::scene::load::FileSystem;
    let fs = FileSystem { base: std::env::temp_dir() };
    let text = "[[object]]\nshape = \"sphere\"\n\n[section]\npoint = [0, 0.2, 0]\nnormal = [0, 1, 0]\n";
    let scene = SceneFile::parse(text, std::path::Path::new("cut.toml")).and_then(|f| f.build(&fs)).expect("loads");
    assert_eq!(scene.objects.len(), 2, "the ball and its cap");
    let (_, hi) = scene.bounds().expect("bounds");
    assert!((hi.y - 0.2).abs() < 1e-5, "nothing above the plane: top at {}", hi.y);
    let bad = "[[object]]\nshape = \"sphere\"\n\n[section]\npoint = [0, 0, 0]\nnormal = [0, 0, 0]\n";
    let e = SceneFile::parse(bad, std::path::Path::new("bad.toml")).and_then(|f| f.build(&fs)).expect_err("refused");
    assert!(e.to_string().starts_with("bad.toml:4:") && e.to_string().contains("normal"), "{e}");
}

#[test]
fn a_section_of_an_openscad_part_is_the_part_intersected_with_a_cube() {
    use kage::scene::model::{scene_for_model_with, ModelOptions};
    let knob = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/openscad/knob.csg");
    let text = std::fs::read_to_string(&knob).expect("the example");
    // The same cut written in OpenSCAD: keep z ≤ 12 of the file's z-up
    // coordinates (the part stands 0 to 21 high).
    let cube = "multmatrix([[1, 0, 0, -100], [0, 1, 0, -100], [0, 0, 1, -88], [0, 0, 0, 1]]) { cube(size = [200, 200, 100], center = false); }";
    let wrapped = format!("intersection() {{\n group() {{\n{text}\n }}\n {cube}\n}}\n");
    let path = std::env::temp_dir().join(format!("kage-section-{}.csg", std::process::id()));
    std::fs::write(&path, wrapped).expect("a scratch file");
    let plane = SectionPlane::through(Vec3::Z * 12.0, Vec3::Z);
    let options = ModelOptions { section: plane, ..ModelOptions::default() };
    let mut cut = scene_for_model_with(&knob, 240, 180, &options).expect("the section loads");
    let mut intersected =
        scene_for_model_with(&path, 240, 180, &ModelOptions::default()).expect("the intersection loads");
    std::fs::remove_file(&path).ok();
    cut.antialias = Antialias::None;
    (intersected.camera, intersected.antialias) = (cut.camera, Antialias::None);
    let (a, b) =
        (render(&cut, &RenderOptions::default()).unwrap(), render(&intersected, &RenderOptions::default()).unwrap());
    let solid = |s: &Scene, o: u32| s.objects.get(o as usize).is_some_and(|o| o.solid().is_some());
    let (ia, ib) = (a.visibility.items(), b.visibility.items());
    let (da, db) = (a.visibility.depths(), b.visibility.depths());
    let mut part = 0;
    let agree = (0..ia.len())
        .filter(|&i| {
            let (pa, pb) =
                (!ia[i].is_none() && solid(&cut, ia[i].object), !ib[i].is_none() && solid(&intersected, ib[i].object));
            part += usize::from(pa || pb);
            pa == pb && (!pa || (da[i] - db[i]).abs() <= 1e-3 * da[i].abs().max(1.0))
        })
        .count();
    let share = agree as f64 / ia.len() as f64;
    assert!(part > 5000, "the part covers {part} pixels");
    assert!(share >= 0.995, "section and intersection agree on {:.3}% of pixels", 100.0 * share);
}
