//! Bad input gives clear errors — file, line and column for scene files, the path
//! for missing files — and never a panic or a silent black image.

use std::path::{Path, PathBuf};

use kage::scene::file::{load_scene, SceneFile};
use kage::scene::load::FileSystem;
use kage::scene::model::scene_for_model;
use kage::{render, Error, RenderOptions};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kage-bad-input-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn parse_err(text: &str) -> String {
    let fs = FileSystem { base: scratch("parse") };
    match SceneFile::parse(text, Path::new("bad.toml")).and_then(|f| f.build(&fs)) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

const OK_OBJECT: &str = "[[object]]\nshape = \"cube\"\n";

#[test]
fn malformed_toml_names_file_line_and_column() {
    let e = parse_err("[image]\nwidth = 640\nheight = = 3\n");
    assert!(e.starts_with("bad.toml:3:10"), "{e}");
}

#[test]
fn wrong_types_and_unknown_keys_point_at_the_value() {
    let e = parse_err(&format!("[image]\nwidth = \"wide\"\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:2:9") && e.contains("expected i64"), "{e}");
    let e = parse_err(&format!("{OK_OBJECT}colour = [1, 0, 0]\n"));
    assert!(e.starts_with("bad.toml:3:1") && e.contains("unknown field `colour`"), "{e}");
    let e = parse_err(&format!("[[light]]\ntype = \"laser\"\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:2:8") && e.contains("unknown variant `laser`"), "{e}");
}

/// A shadow key the light's method does not read is a located warning that
/// names it and what the method reads; the example scenes give none.
#[test]
fn shadow_keys_a_method_does_not_read_are_warned_with_their_line() {
    let fs = FileSystem { base: scratch("shadow-keys") };
    let text = format!(
        "[[light]]\ntype = \"point\"\nposition = [0, 5, 0]\n[light.shadow]\nmethod = \"map\"\nbits = 12\npcf = 3\n{OK_OBJECT}"
    );
    let scene = SceneFile::parse(&text, Path::new("keys.toml")).and_then(|f| f.build(&fs)).unwrap();
    let said: Vec<&String> = scene.warnings.iter().filter(|w| w.contains("does not read")).collect();
    assert_eq!(said.len(), 1, "{:?}", scene.warnings);
    assert!(
        said[0].starts_with("keys.toml:4:") && said[0].contains("`bits`") && !said[0].contains("`pcf` (ignored)"),
        "{}",
        said[0]
    );
    assert!(said[0].contains("it reads `resolution`, `bias`, `slope`, `pcf`, `samples`"), "{}", said[0]);
    // A soft shadow with silhouette-line hard shadows reads the SLB's keys.
    let soft = text.replace("method = \"map\"", "method = \"soft\"\nhard = \"slb\"");
    let scene = SceneFile::parse(&soft, Path::new("keys.toml")).and_then(|f| f.build(&fs)).unwrap();
    assert!(scene.warnings.iter().any(|w| w.contains("`soft` does not read `pcf` (ignored)")), "{:?}", scene.warnings);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes");
    for entry in
        std::fs::read_dir(&dir).unwrap().flatten().filter(|e| e.path().extension().is_some_and(|x| x == "toml"))
    {
        let scene = kage::scene::file::load_scene(&entry.path()).unwrap();
        assert!(!scene.warnings.iter().any(|w| w.contains("does not read")), "{:?}", scene.warnings);
    }
}

#[test]
fn semantic_errors_point_at_the_value() {
    let e = parse_err("[[object]]\nshape = \"cube\"\nmaterial = \"gold\"\n");
    assert!(e.starts_with("bad.toml:3:12") && e.contains("no material named 'gold'"), "{e}");
    let e = parse_err(&format!("[image]\nwidth = 0\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:2:9") && e.contains("between 1 and 16384"), "{e}");
    let e = parse_err(&format!("[image]\nheight = 100000\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:2:10"), "{e}");
    let e = parse_err(&format!("[camera]\neye = [0, 0, 0]\ntarget = [0, 0, 0]\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:1:1") && e.contains("eye and target coincide"), "{e}");
    let e = parse_err(&format!("[[light]]\ntype = \"point\"\n{OK_OBJECT}"));
    assert!(e.contains("needs `position`"), "{e}");
    let e = parse_err("[image]\nwidth = 8\n");
    assert!(e.contains("no [[object]]"), "{e}");
    let e = parse_err(&format!("[fog]\nmode = \"linear\"\ndensity = 0.1\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:1:1") && e.contains("linear fog needs `end`"), "{e}");
    let e =
        parse_err(&format!("[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nshadow = {{ pcf = 0 }}\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:4:18") && e.contains("pcf must be between 1 and 15"), "{e}");
    let light = "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nsize = 0.2\n";
    let e = parse_err(&format!("{light}shadow = {{ method = \"soft\", search = 100 }}\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:5:38") && e.contains("shadow search must be between 0 and 64"), "{e}");
    let e = parse_err(&format!("{light}shadow = {{ method = \"soft\", falloff = \"cubic\" }}\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:5") && e.contains("unknown variant `cubic`"), "{e}");
    let e = parse_err(&format!("{light}shadow = {{ method = \"pcss\", filter = 0 }}\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:5:38") && e.contains("shadow filter must be between 1 and 256"), "{e}");
    let e = parse_err(&format!("[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\nonly = [\"teapot\"]\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:4:9") && e.contains("no [[object]] named 'teapot'"), "{e}");
    let e = parse_err(&format!("[image]\nantialias = {{ method = \"blur\" }}\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:2:24") && e.contains("unknown antialiasing method 'blur'"), "{e}");
    let e = parse_err(&format!("[image]\nantialias = {{ method = \"jitter\", samples = 0 }}\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:2:44") && e.contains("between 1 and 1024"), "{e}");
    let e = parse_err(&format!("[image]\nantialias = {{ method = \"edge\", edges = \"some\" }}\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:2:40") && e.contains("unknown edges 'some'"), "{e}");
    let e = parse_err(&format!(
        "[image]\nantialias = {{ method = \"jitter\", samples = 4, edges = \"all\" }}\n{OK_OBJECT}"
    ));
    assert!(e.starts_with("bad.toml:2:55") && e.contains("`edges` and `filter` belong to method \"edge\""), "{e}");
    let e = parse_err(&format!("[image]\nantialias = {{ method = \"edge\", samples = 4 }}\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:2:42") && e.contains("takes no samples"), "{e}");
    let e = parse_err(&format!("[image]\nantialias = {{ method = \"edge\", filter = \"box\" }}\n{OK_OBJECT}"));
    assert!(e.starts_with("bad.toml:2:41") && e.contains("unknown filter 'box'"), "{e}");
}

#[test]
fn missing_mesh_and_texture_name_the_path() {
    let e = parse_err("[[object]]\nmesh = \"nowhere/teapot.obj\"\n");
    assert!(e.contains("nowhere/teapot.obj") && e.contains("cannot read"), "{e}");
    let e = parse_err("[[material]]\nname = \"m\"\nkd_map = \"missing.png\"\n[[object]]\nshape = \"cube\"\n");
    assert!(e.contains("missing.png"), "{e}");
    let e = load_scene(Path::new("no/such/scene.toml")).unwrap_err().to_string();
    assert!(e.contains("no/such/scene.toml"), "{e}");
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn bad_meshes_are_errors_or_warned_repairs() {
    let dir = scratch("meshes");
    let nan = write(&dir, "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
    let e = scene_for_model(&nan, 64, 64).unwrap_err().to_string();
    assert!(e.contains("nan.obj") && e.contains("non-finite"), "{e}");
    let inf = write(&dir, "inf.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex inf 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n");
    let e = scene_for_model(&inf, 64, 64).unwrap_err().to_string();
    assert!(e.contains("inf.stl") && e.contains("non-finite"), "{e}");
    let empty = write(&dir, "empty.obj", "# nothing\n");
    let e = scene_for_model(&empty, 64, 64).unwrap_err().to_string();
    assert!(e.contains("empty.obj") && e.contains("no triangles"), "{e}");
    let flat = write(&dir, "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    let e = scene_for_model(&flat, 64, 64).unwrap_err().to_string();
    assert!(e.contains("zero area"), "{e}");
    let some = write(&dir, "some.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n");
    let scene = scene_for_model(&some, 64, 64).unwrap();
    assert!(scene.warnings.iter().any(|w| w.contains("dropped 1 zero-area")), "{:?}", scene.warnings);
    // Three objects with a zero-area triangle each: one warning, counting 3.
    let objects =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\no a\nf 1 2 3\nf 1 2 4\no b\nf 1 2 3\nf 1 2 4\no c\nf 1 2 3\nf 1 2 4\n";
    let scene = scene_for_model(&write(&dir, "objects.obj", objects), 64, 64).unwrap();
    let dropped: Vec<&String> = scene.warnings.iter().filter(|w| w.contains("zero-area")).collect();
    assert!(dropped.len() == 1 && dropped[0].contains("dropped 3 zero-area"), "{dropped:?}");
    let garbage = write(&dir, "garbage.glb", "not a gltf");
    let e = scene_for_model(&garbage, 64, 64).unwrap_err().to_string();
    assert!(e.contains("garbage.glb"), "{e}");
    let unknown = write(&dir, "model.ply", "ply");
    let e = scene_for_model(&unknown, 64, 64).unwrap_err().to_string();
    assert!(e.contains("model.ply") && e.contains("not a model kage reads") && e.contains(".off"), "{e}");
    // An OFF file, as OpenSCAD writes them, is a model of its own too.
    let step = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/openscad/parts/step.off");
    let scene = scene_for_model(&step, 64, 64).unwrap();
    assert_eq!(scene.objects.len(), 2, "the step and the ground");
}

#[test]
fn absurd_image_sizes_are_refused_before_allocating() {
    let mut scene = kage::scene::demo::demo_scene().unwrap();
    for (w, h, want) in
        [(0, 10, "at least 1"), (100_000, 100_000, "at most 16384"), (16_384, 16_384, "at most 134,217,728")]
    {
        scene.width = w;
        scene.height = h;
        match render(&scene, &RenderOptions::default()) {
            Err(Error::ImageSize { reason, .. }) => assert!(reason.contains(want), "{reason}"),
            other => panic!("{w}x{h}: expected a size error, got {:?}", other.map(|_| ())),
        }
    }
}

#[test]
fn an_impossible_thread_count_is_refused_as_such_not_as_a_bad_scene() {
    for threads in [kage::frame::MAX_THREADS + 1, usize::MAX] {
        let options = RenderOptions { threads: Some(threads), ..RenderOptions::default() };
        let e = kage::Renderer::new(&options).expect_err("refused");
        assert!(matches!(e, Error::Threads { requested, .. } if requested == threads), "{e:?}");
        let message = e.to_string();
        assert!(message.contains("threads requested") && !message.contains("invalid scene"), "{message}");
    }
}

#[test]
fn a_scene_whose_only_object_is_empty_is_a_located_error_not_a_panic() {
    let dir = scratch("empty-solid");
    // A difference whose positive part has no volume: an empty solid.
    write(
        &dir,
        "nothing.csg",
        "difference() {\n\tcube(size = [0, 1, 1], center = false);\n\tcube(size = [1, 1, 1], center = false);\n}\n",
    );
    let scene = write(&dir, "scene.toml", "[image]\nwidth = 32\nheight = 32\n\n[[object]]\nmesh = \"nothing.csg\"\n");
    let e = load_scene(&scene).unwrap_err().to_string();
    assert!(e.contains("scene.toml:5:1") && e.contains("nothing to draw"), "{e}");
}
