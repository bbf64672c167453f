//! A model file dropped in as it is: it stands up as its format means (STL and
//! OpenSCAD z-up, OBJ and glTF y-up), on a ground that catches its shadow,
//! seen by a camera that frames it.

#[path = "common/skip.rs"]
mod skip;
use std::path::{Path, PathBuf};

use glam::Vec3;
use kage::scene::model::{scene_for_model, scene_for_model_with, ModelOptions};
use kage::scene::Up;
use kage::shading::{Component, ComponentSet};
use kage::{render, RenderOptions, Scene};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kage-models-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The twelve triangles of the box `lo..hi`, outward and counter-clockwise.
fn box_triangles(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let c = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    quads.iter().flat_map(|q| [[c(q[0]), c(q[1]), c(q[2])], [c(q[0]), c(q[2]), c(q[3])]]).collect()
}

fn write_stl(path: &Path, triangles: &[[Vec3; 3]]) {
    let mut text = String::from("solid box\n");
    for t in triangles {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        text += &format!("facet normal {} {} {}\nouter loop\n", n.x, n.y, n.z);
        t.iter().for_each(|v| text += &format!("vertex {} {} {}\n", v.x, v.y, v.z));
        text += "endloop\nendfacet\n";
    }
    text += "endsolid box\n";
    std::fs::write(path, text).unwrap();
}

fn write_obj(path: &Path, triangles: &[[Vec3; 3]]) {
    let mut text = String::new();
    for t in triangles {
        t.iter().for_each(|v| text += &format!("v {} {} {}\n", v.x, v.y, v.z));
    }
    (0..triangles.len()).for_each(|k| text += &format!("f {} {} {}\n", 3 * k + 1, 3 * k + 2, 3 * k + 3));
    std::fs::write(path, text).unwrap();
}

/// Width and height in pixels of what `scene` shows of objects other than
/// its ground.
fn shown_size(scene: &Scene) -> (u32, u32) {
    let frame = render(scene, &RenderOptions::default()).unwrap();
    let (mut lo, mut hi) = ((u32::MAX, u32::MAX), (0, 0));
    for y in 0..scene.height {
        for x in 0..scene.width {
            let item = frame.visibility.item(x, y);
            if !item.is_none() && scene.objects[item.object as usize].name != "ground" {
                (lo, hi) = ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)));
            }
        }
    }
    assert!(hi.0 >= lo.0, "the model shows");
    (hi.0 - lo.0 + 1, hi.1 - lo.1 + 1)
}

#[test]
fn a_tall_box_stands_up_from_a_z_up_stl_and_from_a_y_up_obj() {
    let dir = scratch("tall");
    let (stl, obj) = (dir.join("tall.stl"), dir.join("tall.obj"));
    write_stl(&stl, &box_triangles(Vec3::ZERO, Vec3::new(1.0, 1.0, 3.0)));
    write_obj(&obj, &box_triangles(Vec3::ZERO, Vec3::new(1.0, 3.0, 1.0)));
    let bare = ModelOptions { ground: false, ..ModelOptions::default() };
    let mut standing = f32::INFINITY;
    for path in [&stl, &obj] {
        let (w, h) = shown_size(&scene_for_model_with(path, 160, 160, &bare).unwrap());
        assert!(h as f32 > 1.5 * w as f32, "{}: {w} x {h} pixels, not standing", path.display());
        standing = standing.min(h as f32 / w as f32);
    }
    // Told the STL is y-up, the box lies on its side, its long side towards
    // the camera: far less tall for its width.
    let lying = ModelOptions { up: Some(Up::Y), ..bare };
    let (w, h) = shown_size(&scene_for_model_with(&stl, 160, 160, &lying).unwrap());
    assert!((h as f32 / w as f32) < 0.75 * standing, "lying {w} x {h}, standing {standing} high for wide");
}

#[test]
fn a_lone_model_stands_on_a_ground_that_catches_its_shadow() {
    let dir = scratch("ground");
    let stl = dir.join("cube.stl");
    write_stl(&stl, &box_triangles(Vec3::ZERO, Vec3::splat(1.0)));
    let scene = scene_for_model(&stl, 160, 120).unwrap();
    let ground = scene.objects.iter().position(|o| o.name == "ground").expect("a ground");
    assert!(!scene.objects[ground].casts_shadows, "the ground takes no share of the shadow map");
    let options = RenderOptions { aovs: ComponentSet::only(Component::Diffuse), ..RenderOptions::default() };
    let frame = render(&scene, &options).unwrap();
    let diffuse = &frame.aovs[0].1;
    let mut on_ground: Vec<f32> = (0..scene.height)
        .flat_map(|y| (0..scene.width).map(move |x| (x, y)))
        .filter(|&(x, y)| frame.visibility.item(x, y).object as usize == ground)
        .map(|(x, y)| diffuse.get(x, y).max_element())
        .collect();
    assert!(on_ground.len() > 1000, "the ground shows: {} pixels", on_ground.len());
    on_ground.sort_by(f32::total_cmp);
    let lit = on_ground[on_ground.len() * 9 / 10];
    let shadowed = on_ground.iter().filter(|&&d| d < 0.5 * lit).count();
    assert!(shadowed * 100 >= on_ground.len(), "{shadowed} of {} ground pixels in shadow", on_ground.len());
    // Without a ground, none.
    let bare =
        scene_for_model_with(&stl, 160, 120, &ModelOptions { ground: false, ..ModelOptions::default() }).unwrap();
    assert!(bare.objects.iter().all(|o| o.name != "ground"));
}

/// A lone flat card (one quad) is framed face-on from the side its face
/// faces, and a ground under it never takes its pixels.
#[test]
fn a_flat_card_is_seen_face_on_and_not_hidden_by_its_ground() {
    let dir = scratch("card");
    let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| vec![[a, b, c], [a, c, d]];
    let (p, q) = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0));
    let up = quad(p, Vec3::new(p.x, 0.0, q.z), q, Vec3::new(q.x, 0.0, p.z));
    let down: Vec<[Vec3; 3]> = up.iter().map(|t| [t[0], t[2], t[1]]).collect();
    for (name, triangles) in [("up", up), ("down", down)] {
        let obj = dir.join(format!("card-{name}.obj"));
        write_obj(&obj, &triangles);
        let scene = scene_for_model(&obj, 160, 120).unwrap();
        let (w, h) = shown_size(&scene);
        assert!(w > 60 && h > 60, "card facing {name}: {w}x{h} pixels of the card");
        let toward = (scene.camera.eye - scene.camera.target).normalize();
        let facing = (triangles[0][1] - triangles[0][0]).cross(triangles[0][2] - triangles[0][0]).normalize();
        assert!(toward.dot(facing) > 0.99, "card facing {name} is seen from {toward}");
    }
}

/// Round a turntable, a model's light rig turns with the camera: every
/// frame shows the model lit alike (its mean brightness within 20%), where a
/// rig fixed in the world would leave the frames behind it in shade.
#[test]
fn a_turntable_lights_every_side_of_a_model_alike() {
    let dir = scratch("turntable");
    let stl = dir.join("box.stl");
    write_stl(&stl, &box_triangles(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0)));
    let mut scene = scene_for_model(&stl, 96, 72).unwrap();
    assert!(scene.lights_follow_camera);
    let (camera, rig) = (scene.camera, scene.lights.clone());
    let mut means = Vec::new();
    for frame in 0..8 {
        scene.camera = kage::scene::camera_path::turntable(&camera, frame, 8);
        scene.lights = kage::scene::camera_path::turntable_lights(&rig, camera.target, frame, 8);
        let out = render(&scene, &RenderOptions::default()).unwrap();
        let (mut sum, mut n) = (0.0, 0);
        for y in 0..scene.height {
            for x in 0..scene.width {
                let item = out.visibility.item(x, y);
                if !item.is_none() && scene.objects[item.object as usize].name != "ground" {
                    sum += out.image.get(x, y).dot(Vec3::splat(1.0 / 3.0));
                    n += 1;
                }
            }
        }
        means.push(sum / n as f32);
    }
    let (lo, hi) = means.iter().fold((f32::MAX, 0.0f32), |(a, b), &m| (a.min(m), b.max(m)));
    assert!(hi <= 1.2 * lo, "the frames' mean brightness: {means:?}");
}

/// An open box (five walls facing inwards, no wall towards +x) with a glowing
/// panel under its top, as a Cornell box is modelled: it is seen through its
/// open side, with no ground, lit from the panel.
#[test]
fn an_open_box_is_seen_through_its_open_side_and_lit_from_within() {
    let dir = scratch("open-box");
    let v = Vec3::new;
    // Inward-facing quads (counter-clockwise seen from inside).
    let walls = [
        [v(0., 0., 0.), v(0., 0., 1.), v(1., 0., 1.), v(1., 0., 0.)], // floor, up
        [v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)], // top, down
        [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)], // z = 0, towards +z
        [v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)], // z = 1, towards −z
        [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)], // x = 0, towards +x
    ];
    let panel = [v(0.4, 0.98, 0.4), v(0.6, 0.98, 0.4), v(0.6, 0.98, 0.6), v(0.4, 0.98, 0.6)]; // facing down
    let mut obj = String::from("mtllib box.mtl\nusemtl white\n");
    let mut n = 1;
    for (k, q) in walls.iter().chain([&panel]).enumerate() {
        if k == walls.len() {
            obj += "usemtl glow\n";
        }
        q.iter().for_each(|p| obj += &format!("v {} {} {}\n", p.x, p.y, p.z));
        obj += &format!("f {} {} {} {}\n", n, n + 1, n + 2, n + 3);
        n += 4;
    }
    std::fs::write(dir.join("box.obj"), obj).unwrap();
    std::fs::write(dir.join("box.mtl"), "newmtl white\nKd 0.7 0.7 0.7\nnewmtl glow\nKd 0.8 0.8 0.8\nKe 10 10 10\n")
        .unwrap();
    let scene = scene_for_model(&dir.join("box.obj"), 160, 120).unwrap();
    let cam = scene.camera;
    assert!(cam.eye.x > 1.0 && (cam.eye.y - 0.5).abs() < 0.05 && (cam.eye.z - 0.5).abs() < 0.05, "eye {}", cam.eye);
    assert!(scene.objects.iter().all(|o| o.name != "ground"), "a box has its own floor");
    let inside = |p: Vec3| p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::ONE).all();
    let light = scene.lights.iter().find_map(|l| match l.kind {
        kage::scene::LightKind::Point { position } if inside(position) => Some((position, l.size)),
        _ => None,
    });
    // A sphere as wide as the panel (0.2 × 0.2 at y = 0.98), just under it.
    let at_panel =
        |(p, r): (Vec3, f32)| (p.y + r - 0.98).abs() < 0.01 && (r - 0.2 / std::f32::consts::PI.sqrt()).abs() < 1e-3;
    assert!(light.is_some_and(at_panel), "a light at the panel: {light:?}");
    // The back wall (x = 0) shows through the opening, lit.
    let options = RenderOptions { aovs: ComponentSet::only(Component::Diffuse), ..RenderOptions::default() };
    let frame = render(&scene, &options).unwrap();
    let (x, y) = (scene.width / 2, scene.height / 2);
    assert!(!frame.visibility.item(x, y).is_none(), "the centre sees into the box");
    assert!(frame.aovs[0].1.get(x, y).max_element() > 0.1, "the back wall is lit: {}", frame.aovs[0].1.get(x, y));
}

/// An OBJ of inward-facing quads (counter-clockwise seen from inside) on the
/// faces of the box `lo..hi` that `sides` picks (−x, +x, −y, +y, −z, +z).
fn write_room(path: &Path, lo: Vec3, hi: Vec3, sides: [bool; 6]) {
    let inside: Vec<[Vec3; 3]> = box_triangles(lo, hi).iter().map(|t| [t[0], t[2], t[1]]).collect();
    // box_triangles lists −z, +z, −y, +y, −x, +x, two triangles each.
    let order = [4, 5, 2, 3, 0, 1];
    let kept: Vec<[Vec3; 3]> =
        (0..6).filter(|&k| sides[order[k]]).flat_map(|k| [inside[2 * k], inside[2 * k + 1]]).collect();
    write_obj(path, &kept);
}

/// A closed room (a courtyard building, a town under a sky dome) encloses
/// the point the usual camera looks at: it is framed from inside, and kage
/// says so; an open tray, which the usual camera sees into, is not.
#[test]
fn a_model_that_encloses_its_centre_is_framed_from_inside_and_says_so() {
    let dir = scratch("enclosed");
    let (lo, hi) = (Vec3::ZERO, Vec3::new(4.0, 2.0, 2.0));
    write_room(&dir.join("room.obj"), lo, hi, [true; 6]);
    let scene = scene_for_model(&dir.join("room.obj"), 160, 90).unwrap();
    let eye = scene.camera.eye;
    assert!(eye.cmpgt(lo).all() && eye.cmplt(hi).all(), "the eye is inside the room: {eye}");
    assert!(
        scene.warnings.iter().any(|w| w.contains("framed from inside")),
        "kage says where it put the camera: {:?}",
        scene.warnings
    );
    assert!(scene.objects.iter().all(|o| o.name != "ground"), "a room has its own floor");
    let options = RenderOptions { aovs: ComponentSet::only(Component::Diffuse), ..RenderOptions::default() };
    let frame = render(&scene, &options).unwrap();
    let (x, y) = (scene.width / 2, scene.height / 2);
    assert!(frame.aovs[0].1.get(x, y).max_element() > 0.1, "the far wall is lit: {}", frame.aovs[0].1.get(x, y));

    // A tray (no top) is seen into from above, as any part.
    write_room(&dir.join("tray.obj"), Vec3::ZERO, Vec3::new(1.0, 0.3, 1.0), [true, true, true, false, true, true]);
    let scene = scene_for_model(&dir.join("tray.obj"), 160, 90).unwrap();
    assert!(scene.camera.eye.y > 0.3 && scene.warnings.is_empty(), "{} {:?}", scene.camera.eye, scene.warnings);
    // A closed part holds its centre in its material: seen from outside.
    write_obj(&dir.join("part.obj"), &box_triangles(lo, hi));
    let scene = scene_for_model(&dir.join("part.obj"), 160, 90).unwrap();
    assert!(
        !scene.camera.eye.cmplt(hi).all() && scene.warnings.is_empty(),
        "{} {:?}",
        scene.camera.eye,
        scene.warnings
    );
}

/// The Cornell box of the shared corpus, dropped in: seen through its open
/// front (+z), lit by its ceiling light (material `light`, `Ke 17 12 4`).
#[test]
fn the_cornell_box_is_seen_through_its_open_front() {
    let Some(path) = skip::asset("scenes/cornell-box/CornellBox-Original.obj") else { return };
    let scene = scene_for_model(&path, 160, 120).unwrap();
    let (lo, hi) = scene.bounds().unwrap();
    let cam = scene.camera;
    assert!(cam.eye.z > hi.z && (cam.eye.x - (lo.x + hi.x) * 0.5).abs() < 0.05 * (hi.x - lo.x), "eye {}", cam.eye);
    // The light's sphere lies just under the ceiling's lamp.
    let lit_from_ceiling = scene.lights.iter().any(|l| match l.kind {
        kage::scene::LightKind::Point { position } => {
            let top = position.y + l.size;
            top > lo.y + 0.95 * (hi.y - lo.y) && top < hi.y
        }
        _ => false,
    });
    assert!(
        lit_from_ceiling,
        "a light under the ceiling: {:?}",
        scene.lights.iter().map(|l| l.kind).collect::<Vec<_>>()
    );
}
