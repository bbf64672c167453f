//! Every limit on what an input may ask for: a request exactly at the limit
//! is served (it loads and renders), one just over it is refused with an
//! error naming the limit; the limits are set in a scene's `[limits]` table
//! and over it by the command line's settings.

use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use kage::frame::MemoryNeeded;
use kage::limits::{Limit, LimitSetting, Limits};
use kage::scene::file::SceneFile;
use kage::scene::load::{self, InMemory};
use kage::{render, RenderOptions, Scene};

/// A scene file's text built over `files` (name, bytes), with `overrides`.
fn build_with(text: &str, files: &[(&str, Vec<u8>)], overrides: &[LimitSetting]) -> kage::error::Result<Scene> {
    let files = InMemory { files: files.iter().map(|(n, b)| (PathBuf::from(n), b.clone())).collect() };
    let mut scene = SceneFile::parse(text, Path::new("s.toml"))?.build_with(&files, overrides)?;
    (scene.width, scene.height) = (32, 24);
    Ok(scene)
}

/// Builds and renders; the error's text if either fails.
fn outcome(text: &str, files: &[(&str, Vec<u8>)]) -> Result<(), String> {
    let scene = build_with(text, files, &[]).map_err(|e| e.to_string())?;
    render(&scene, &RenderOptions::default()).map(|_| ()).map_err(|e| e.to_string())
}

/// `text_at(limit)` is served at `limit` and refused at `limit - 1` with an
/// error naming `name`.
fn holds_at(name: &str, limit: u64, text_at: impl Fn(u64) -> String, files: &[(&str, Vec<u8>)]) {
    let served = outcome(&text_at(limit), files);
    assert!(served.is_ok(), "`{name}` = {limit}: {served:?}");
    let refused = outcome(&text_at(limit - 1), files).expect_err("one under the request");
    assert!(refused.contains(&format!("over the `{name}` limit of {}", limit - 1)), "{refused}");
    assert!(refused.contains(&format!("--limit {name}=")), "the error says how to raise it: {refused}");
}

const LIGHT: &str = "[[light]]\ntype = \"directional\"\ndirection = [-1, -2, -1]\nshadow = { method = \"none\" }\n";

fn object(file: &str) -> String {
    format!("{LIGHT}[[object]]\nmesh = \"{file}\"\n")
}

fn nested_unions(depth: usize) -> Vec<u8> {
    let open = "union() {\n".repeat(depth);
    let close = "}\n".repeat(depth);
    format!("{open}sphere($fn = 0, $fa = 12, $fs = 2, r = 1);\n{close}").into_bytes()
}

#[test]
fn nesting_bounds_csg_blocks() {
    for depth in [5, 6] {
        let files = [("deep.csg", nested_unions(depth))];
        let got = outcome(&format!("[limits]\nnesting = 5\n{}", object("deep.csg")), &files);
        match depth {
            5 => assert!(got.is_ok(), "{got:?}"),
            _ => assert!(got.unwrap_err().contains("over the `nesting` limit of 5")),
        }
    }
}

/// A glTF whose node `i` lists `children(i)`, the last of `nodes` holding a
/// triangle.
fn gltf(nodes: usize, children: impl Fn(usize) -> Vec<usize>) -> Vec<u8> {
    let node = |i: usize| {
        let kids = children(i);
        let mesh = if i + 1 == nodes { ", \"mesh\": 0" } else { "" };
        format!("{{\"children\": {kids:?}{mesh}}}").replace("\"children\": [], ", "")
    };
    let nodes: Vec<String> = (0..nodes).map(node).collect();
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"byteLength": 44, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}}],
 "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
 "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}}, {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}],
 "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
 "nodes": [{}], "scenes": [{{"nodes": [0]}}], "scene": 0}}"#,
        nodes.join(", ")
    )
    .into_bytes()
}

#[test]
fn nesting_bounds_gltf_node_trees() {
    let chain = gltf(6, |i| if i < 5 { vec![i + 1] } else { vec![] });
    holds_at("nesting", 6, |n| format!("[limits]\nnesting = {n}\n{}", object("c.gltf")), &[("c.gltf", chain)]);
}

#[test]
fn gltf_nodes_bounds_the_nodes_a_file_holds() {
    let chain = gltf(3, |i| if i < 2 { vec![i + 1] } else { vec![] });
    holds_at("gltf_nodes", 3, |n| format!("[limits]\ngltf_nodes = {n}\n{}", object("c.gltf")), &[("c.gltf", chain)]);
}

#[test]
fn instances_counts_a_node_once_per_parent() {
    // Node 0 lists node 1 twice, node 1 lists node 2 twice: 1 + 2 + 4 placed.
    let dag = gltf(3, |i| if i < 2 { vec![i + 1, i + 1] } else { vec![] });
    holds_at("instances", 7, |n| format!("[limits]\ninstances = {n}\n{}", object("d.gltf")), &[("d.gltf", dag)]);
}

#[test]
fn segments_bounds_a_circle() {
    let files = [("s.csg", b"sphere($fn = 64, $fa = 12, $fs = 2, r = 1);\n".to_vec())];
    holds_at("segments", 64, |n| format!("[limits]\nsegments = {n}\n{}", object("s.csg")), &files);
}

#[test]
fn facets_bounds_a_faceted_sphere_and_a_hull() {
    // 16 segments, 8 rings: 16 × 7 quads and two caps.
    let files = [("s.csg", b"sphere($fn = 16, $fa = 12, $fs = 2, r = 1);\n".to_vec())];
    let faceted = |n| format!("[limits]\nfacets = {n}\n{}geometry = \"faceted\"\n", object("s.csg"));
    holds_at("facets", 114, faceted, &files);
    let files = [("h.csg", b"hull() {\n\tcube(size = [1, 2, 3], center = false);\n}\n".to_vec())];
    holds_at("facets", 8, |n| format!("[limits]\nfacets = {n}\n{}", object("h.csg")), &files);
}

#[test]
fn triangles_bound_the_scene_at_the_object_that_passes_them() {
    let two_cubes = |n| {
        format!("[limits]\ntriangles = {n}\n{LIGHT}[[object]]\nshape = \"cube\"\n[[object]]\nshape = \"cube\"\ntranslate = [2, 0, 0]\n")
    };
    holds_at("triangles", 24, two_cubes, &[]);
    let refused = outcome(&two_cubes(23), &[]).unwrap_err();
    assert!(refused.starts_with("s.toml:9:1"), "located at the second object: {refused}");
}

#[test]
fn triangles_are_checked_from_a_binary_stl_header_before_reading_it() {
    let mut stl = vec![0u8; 84];
    stl[80..84].copy_from_slice(&1_000_000u32.to_le_bytes());
    let refused = outcome(&format!("[limits]\ntriangles = 999999\n{}", object("big.stl")), &[("big.stl", stl)]);
    assert!(refused.unwrap_err().contains("over the `triangles` limit of 999999"));
}

#[test]
fn primitives_bound_a_solid() {
    let three = b"union() {\n\tcube(size = [1, 1, 1], center = false);\n\tsphere($fn = 0, $fa = 12, $fs = 2, r = 1);\n\tcylinder($fn = 0, $fa = 12, $fs = 2, h = 1, r1 = 1, r2 = 1, center = false);\n}\n";
    let files = [("p.csg", three.to_vec())];
    holds_at("primitives", 3, |n| format!("[limits]\nprimitives = {n}\n{}", object("p.csg")), &files);
}

fn png(width: u32, height: u32) -> Vec<u8> {
    let img = image::RgbImage::from_pixel(width, height, image::Rgb([200, 100, 50]));
    let mut out = Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

#[test]
fn texture_pixels_are_checked_from_the_header() {
    let files = [("t.png", png(4, 5))];
    let textured = |n| {
        format!("[limits]\ntexture_pixels = {n}\n{LIGHT}[[material]]\nname = \"m\"\nkd_map = \"t.png\"\n[[object]]\nshape = \"cube\"\nmaterial = \"m\"\n")
    };
    holds_at("texture_pixels", 20, textured, &files);
}

#[test]
fn a_texture_named_by_many_materials_is_decoded_once() {
    let materials: String =
        (0..20).map(|i| format!("[[material]]\nname = \"m{i}\"\nkd_map = \"t.png\"\n[[object]]\nshape = \"cube\"\nmaterial = \"m{i}\"\ntranslate = [{i}, 0, 0]\n")).collect();
    let scene = build_with(&format!("{LIGHT}{materials}"), &[("t.png", png(64, 64))], &[]).unwrap();
    let first = &scene.materials[0].maps.diffuse[0];
    assert!(scene.materials.iter().all(|m| std::sync::Arc::ptr_eq(&m.maps.diffuse[0], first)));
}

/// Directional lights whose one map is 1024² four-byte depths: 4 MiB each.
fn sunlit(lights: usize, limits: &str) -> String {
    let sun = "[[light]]\ntype = \"directional\"\ndirection = [-1, -2, -1]\nshadow = { resolution = 1024 }\n";
    format!("[limits]\n{limits}\n{}[[object]]\nshape = \"cube\"\n", sun.repeat(lights))
}

#[test]
fn light_shadow_mb_bounds_one_lights_maps() {
    holds_at("light_shadow_mb", 4, |n| sunlit(1, &format!("light_shadow_mb = {n}")), &[]);
}

#[test]
fn frame_shadow_mb_bounds_every_lights_maps_together() {
    holds_at("frame_shadow_mb", 8, |n| sunlit(2, &format!("frame_shadow_mb = {n}")), &[]);
}

#[test]
fn file_mb_bounds_a_file_read_from_memory_or_disk() {
    let limits = Limits::default().with(Limit::FileMb, 1);
    let mib = 1 << 20;
    let files = InMemory { files: HashMap::from([("a".into(), vec![b' '; mib]), ("b".into(), vec![b' '; mib + 1])]) };
    assert_eq!(load::read(Path::new("a"), &files, &limits).unwrap().len(), mib);
    let refused = load::read(Path::new("b"), &files, &limits).unwrap_err().to_string();
    assert!(refused.contains("2 MiB is over the `file_mb` limit of 1 MiB"), "{refused}");
    let dir = std::env::temp_dir().join(format!("kage-limits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("b"), vec![b' '; mib + 1]).unwrap();
    let disk = load::FileSystem { base: dir };
    assert!(load::read(Path::new("b"), &disk, &limits).unwrap_err().to_string().contains("`file_mb` limit"));
    let device = load::read(Path::new("/dev/zero"), &disk, &limits).unwrap_err().to_string();
    assert!(device.contains("not a regular file"), "{device}");
}

#[test]
fn memory_mb_bounds_the_frames_estimate() {
    let text = "[image]\nwidth = 640\nheight = 480\n[[light]]\ntype = \"directional\"\ndirection = [-1, -2, -1]\nshadow = { resolution = 512 }\n[[object]]\nshape = \"sphere\"\n";
    let mut scene = build_with(text, &[], &[]).unwrap();
    (scene.width, scene.height) = (640, 480);
    let need = MemoryNeeded::estimate(&scene);
    assert_eq!(need.pixels, 640 * 480 * kage::frame::BYTES_PER_PIXEL);
    assert_eq!(need.shadow_maps, 512 * 512 * 4);
    let at = need.total().div_ceil(1 << 20);
    scene.limits = Limits::default().with(Limit::MemoryMb, at);
    assert!(render(&scene, &RenderOptions::default()).is_ok());
    scene.limits = Limits::default().with(Limit::MemoryMb, at - 1);
    let Err(refused) = render(&scene, &RenderOptions::default()) else { panic!("rendered one MiB under") };
    let refused = refused.to_string();
    assert!(refused.contains(&format!("over the `memory_mb` limit of {}", at - 1)), "{refused}");
    // A tile counts the pixels it draws: a sixteenth of the frame fits where
    // the whole does not.
    let tile = kage::image::PixelRect::tile(5, 16, 640, 480);
    let options = RenderOptions { region: Some(tile), ..RenderOptions::default() };
    let frame = render(&scene, &options).expect("a tile within the limit");
    let drawn = kage::frame::region_drawn(&scene, tile);
    assert_eq!(frame.rect(), drawn);
    assert!(u64::from(drawn.width() * drawn.height()) * 4 < 640 * 480, "{drawn:?}");
}

#[test]
fn the_command_lines_settings_win_over_the_files_table() {
    let text = format!("[limits]\ntriangles = 1000\n{LIGHT}[[object]]\nshape = \"cube\"\n");
    let lower = [LimitSetting { limit: Limit::Triangles, value: 11 }];
    let refused = build_with(&text, &[], &lower).expect_err("refused").to_string();
    assert!(refused.contains("over the `triangles` limit of 11"), "{refused}");
    assert!(build_with(&text, &[], &[]).is_ok());
}

#[test]
fn an_unknown_limit_or_a_negative_value_is_located() {
    let e = build_with(&format!("[limits]\ntriangle = 5\n{}", object("x.obj")), &[], &[]).err().unwrap().to_string();
    assert!(e.starts_with("s.toml:2:1") && e.contains("unknown limit 'triangle'") && e.contains("triangles"), "{e}");
    let e = build_with(&format!("[limits]\ntriangles = -5\n{}", object("x.obj")), &[], &[]).err().unwrap().to_string();
    assert!(e.starts_with("s.toml:2:13") && e.contains("whole number"), "{e}");
}

#[test]
fn slices_bound_an_extrusion_before_it_is_cut() {
    let twisted = b"linear_extrude(height = 10, center = false, convexity = 1, twist = 90, slices = 40, scale = [1, 1]) {\n\tsquare(size = [1, 1], center = false);\n}\n";
    let files = [("t.csg", twisted.to_vec())];
    holds_at("slices", 40, |n| format!("[limits]\nslices = {n}\n{}", object("t.csg")), &files);
    // A faceted revolution's segments ($fn = 8 stays faceted in exact
    // geometry): over half a turn, 4.
    let revolved = b"rotate_extrude(angle = 180, convexity = 2, $fn = 8, $fa = 12, $fs = 2) {\n\tmultmatrix([[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) {\n\t\tsquare(size = [1, 1], center = false);\n\t}\n}\n";
    let files = [("r.csg", revolved.to_vec())];
    holds_at("slices", 4, |n| format!("[limits]\nslices = {n}\n{}", object("r.csg")), &files);
}

#[test]
fn points_bound_a_polygon_and_a_polyhedron() {
    let polygon = b"linear_extrude(height = 1, center = false, convexity = 1, scale = [1, 1]) {\n\tpolygon(points = [[0, 0], [2, 0], [2, 2], [1, 1], [0, 2]], paths = undef, convexity = 1);\n}\n";
    let files = [("p.csg", polygon.to_vec())];
    holds_at("points", 5, |n| format!("[limits]\npoints = {n}\n{}", object("p.csg")), &files);
    let dented = b"polyhedron(points = [[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0], [2, 2, -1], [2, 2, -3]], faces = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [1, 0, 5], [2, 1, 5], [3, 2, 5], [0, 3, 5]], convexity = 1);\n";
    let files = [("d.csg", dented.to_vec())];
    holds_at("points", 6, |n| format!("[limits]\npoints = {n}\n{}", object("d.csg")), &files);
}

#[test]
fn text_length_bounds_a_label() {
    let label = b"linear_extrude(height = 1, center = false, convexity = 1, scale = [1, 1]) {\n\ttext(text = \"kage!\", size = 10, spacing = 1, font = \"\", direction = \"ltr\", language = \"en\", script = \"latin\", halign = \"left\", valign = \"baseline\", $fn = 0, $fa = 12, $fs = 2);\n}\n";
    let files = [("l.csg", label.to_vec())];
    holds_at("text_length", 5, |n| format!("[limits]\ntext_length = {n}\n{}", object("l.csg")), &files);
}
