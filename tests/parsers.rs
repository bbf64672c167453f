//! Every reader on random bytes and on random mutations of real files (the
//! fuzz targets' seeds) never panics: it loads, or it gives an error. The
//! stable, CI-sized cousin of `fuzz/`: 500 cases per reader and
//! kind, every model that loads rendered at 8 × 6.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use kage::csg::openscad::{load_csg, CsgOptions};
use kage::limits::{Limit, Limits};
use kage::scene::file::SceneFile;
use kage::scene::load::{self, InMemory};
use kage::scene::model::{scene_for_loaded_model, ModelOptions};
use kage::scene::Texture;
use kage::{render, RenderOptions};
use proptest::prelude::*;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Low limits, as the fuzz targets run under: every accepted case is quick.
fn limits() -> Limits {
    [(Limit::Triangles, 50_000), (Limit::Facets, 2_000), (Limit::Primitives, 100), (Limit::MemoryMb, 256)]
        .into_iter()
        .fold(Limits::default(), |l, (limit, v)| l.with(limit, v))
}

/// The small files scenes and models may name.
fn files(extra: &[(&str, &[u8])]) -> InMemory {
    let data = repo().join("tests/data/fuzz");
    let mut files: HashMap<PathBuf, Vec<u8>> = std::fs::read_dir(&data)
        .unwrap()
        .flatten()
        .map(|e| (PathBuf::from(e.file_name()), std::fs::read(e.path()).unwrap()))
        .collect();
    files.extend(extra.iter().map(|(n, b)| (PathBuf::from(n), b.to_vec())));
    InMemory { files }
}

/// The seeds of one format: every file of `dirs` ending in `ext`, those of
/// the first folder (files that load) repeated to be at least half.
fn seeds(dirs: &[&str], ext: &str) -> Vec<Vec<u8>> {
    let good = files_in(&dirs[..1], ext);
    let bad = files_in(&dirs[1..], ext);
    let copies = if good.is_empty() { 0 } else { bad.len().div_ceil(good.len()).max(1) };
    let out: Vec<Vec<u8>> = (0..copies).flat_map(|_| good.iter().cloned()).chain(bad).collect();
    assert!(!out.is_empty(), "no .{ext} seeds in {dirs:?}");
    out
}

fn files_in(dirs: &[&str], ext: &str) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    for dir in dirs {
        let mut stack = vec![repo().join(dir)];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
                let p = e.path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|e| e == ext) && e.metadata().is_ok_and(|m| m.len() < 64 * 1024) {
                    out.push(std::fs::read(&p).unwrap());
                }
            }
        }
    }
    out
}

/// One change to a file's bytes, at positions taken modulo its length.
#[derive(Debug, Clone)]
enum Edit {
    Set(usize, u8),
    Insert(usize, u8),
    Delete(usize, usize),
    Repeat(usize, usize, usize),
    Token(usize, usize),
}

/// Words the readers care about, to splice in.
const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-1e30",
    "1e38",
    "0",
    "-1",
    "{",
    "}",
    "[",
    "]",
    "(",
    ")",
    ",",
    ";",
    "=",
    "\"",
    "\n",
    "/",
    "//",
    "union() {",
    "cube(size = [1, 1, 1], center = false);",
    "$fn = ",
    "f 1 2 3\n",
    "v 0 0 0\n",
    "vt 0 -1e30\n",
    "mtllib m.mtl\n",
    "Kd 0.5\n",
    "map_Kd tex.png\n",
    "\"nodes\"",
    "\"children\": [0]",
    "\"mesh\": 0",
    "\"POSITION\": 0",
    "\"uri\": \"buf.bin\"",
    "[[object]]\nshape = \"cube\"\n",
    "[[light]]\ntype = \"spot\"\n",
    "resolution = 16384",
    "samples = 256",
    "facet normal 0 0 1\n",
    "vertex 0 0 0\n",
    "glTF",
    "\u{0}",
];

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Insert(i, b)),
        (any::<usize>(), 1..8usize).prop_map(|(i, n)| Edit::Delete(i, n)),
        (any::<usize>(), 1..32usize, 1..8usize).prop_map(|(i, n, k)| Edit::Repeat(i, n, k)),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(i, t)| Edit::Token(i, t)),
    ]
}

fn mutated(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for e in edits {
        let at = |i: usize, b: &Vec<u8>| if b.is_empty() { 0 } else { i % b.len() };
        match *e {
            Edit::Set(i, v) if !b.is_empty() => {
                let i = at(i, &b);
                b[i] = v;
            }
            Edit::Set(..) => {}
            Edit::Insert(i, v) => {
                let i = at(i, &b);
                b.insert(i, v);
            }
            Edit::Delete(i, n) => {
                let i = at(i, &b);
                b.drain(i..(i + n).min(b.len()));
            }
            Edit::Repeat(i, n, k) => {
                let i = at(i, &b);
                let part: Vec<u8> = b[i..(i + n).min(b.len())].to_vec();
                for _ in 0..k {
                    b.splice(i..i, part.iter().copied());
                }
            }
            Edit::Token(i, t) => {
                let i = at(i, &b);
                b.splice(i..i, TOKENS[t].bytes());
            }
        }
    }
    b
}

/// A model file's bytes loaded as `name` and, if they load, rendered small.
fn model(name: &str, bytes: &[u8]) {
    let files = files(&[(name, bytes)]);
    let options = ModelOptions { limits: limits(), ..ModelOptions::default() };
    let Ok(model) = load::model_with(Path::new(name), &files, &options.csg, &options.limits) else { return };
    if let Ok(mut scene) = scene_for_loaded_model(&model, Path::new(name), 8, 6, &options) {
        scene
            .lights
            .iter_mut()
            .for_each(|l| (l.shadow.resolution, l.shadow.by_need, l.shadow.samples) = (32, false, 1));
        let _ = render(&scene, &RenderOptions { threads: Some(1), ..RenderOptions::default() });
    }
}

fn scene(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else { return };
    let Ok(file) = SceneFile::parse(text, Path::new("s.toml")) else { return };
    let overrides: Vec<_> = [
        Limit::Triangles,
        Limit::Facets,
        Limit::Primitives,
        Limit::MemoryMb,
        Limit::LightShadowMb,
        Limit::FrameShadowMb,
    ]
    .into_iter()
    .map(|limit| kage::limits::LimitSetting { limit, value: limits().get(limit) })
    .collect();
    if let Ok(mut scene) = file.build_with(&files(&[]), &overrides) {
        (scene.width, scene.height) = (8, 6);
        let _ = render(&scene, &RenderOptions { threads: Some(1), ..RenderOptions::default() });
    }
}

fn csg(bytes: &[u8]) {
    if let Ok(text) = std::str::from_utf8(bytes) {
        let _ = load_csg(Path::new("m.csg"), Arc::from(text), &CsgOptions::default(), &limits());
    }
    model("m.csg", bytes);
}

fn drawing(bytes: &[u8], dxf: bool) {
    for contour in kage::csg::openscad::drawing_outlines(bytes, dxf).into_iter().flatten() {
        assert!(contour.iter().flatten().all(|v| v.is_finite()));
    }
}

fn texture(bytes: &[u8]) {
    if let Ok(t) = Texture::decode(bytes, true, &limits()) {
        assert!(t.sample(glam::Vec2::new(0.4, 0.6)).is_finite());
    }
}

/// Random bytes and mutated seeds for one reader.
macro_rules! never_panics {
    ($name:ident, $read:expr, $dirs:expr, $ext:expr) => {
        mod $name {
            use super::*;

            proptest! {
                #![proptest_config(ProptestConfig { cases: 500, failure_persistence: None, ..ProptestConfig::default() })]

                #[test]
                fn on_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
                    ($read)(&bytes);
                }

                #[test]
                fn on_mutated_seeds(pick in any::<usize>(), edits in proptest::collection::vec(edit(), 1..4)) {
                    let seeds = seeds(&$dirs, $ext);
                    ($read)(&mutated(&seeds[pick % seeds.len()], &edits));
                }
            }
        }
    };
}

// Seeds: the fuzz targets' own (files that load, naming each other), then
// the regression corpus (files that once crashed kage).
never_panics!(scene_toml, scene, ["tests/data/fuzz", "tests/regressions/scene"], "toml");
never_panics!(obj, |b: &[u8]| model("m.obj", b), ["tests/data/fuzz", "tests/regressions/obj"], "obj");
never_panics!(stl, |b: &[u8]| model("m.stl", b), ["tests/data/fuzz", "tests/data"], "stl");
never_panics!(gltf, |b: &[u8]| model("m.gltf", b), ["tests/data/fuzz", "tests/regressions/gltf"], "gltf");
never_panics!(glb, |b: &[u8]| model("m.glb", b), ["tests/data/fuzz", "tests/regressions/gltf"], "glb");
never_panics!(openscad, csg, ["tests/data", "tests/regressions/csg"], "csg");
never_panics!(dxf, |b: &[u8]| drawing(b, true), ["tests/data/openscad", "tests/regressions/csg"], "dxf");
never_panics!(svg, |b: &[u8]| drawing(b, false), ["tests/data/openscad", "tests/regressions/csg"], "svg");
never_panics!(png, texture, ["tests/data", "tests/regressions/scene", "examples/scenes"], "png");

/// The seeds of the fuzz targets load and render as they are: the mutations
/// above start from files that reach every stage, not only the first check.
#[test]
fn the_seeds_load() {
    let files = files(&[]);
    let scene_text = std::str::from_utf8(&files.files[Path::new("scene.toml")]).unwrap().to_string();
    let built = SceneFile::parse(&scene_text, Path::new("s.toml")).and_then(|f| f.build(&files));
    assert_eq!(built.map(|s| s.objects.len()).map_err(|e| e.to_string()), Ok(5));
    for name in
        ["cube.obj", "tri.stl", "part.csg", "tri.gltf", "tri.glb", "quantized.gltf", "meshopt.gltf", "draco.gltf"]
    {
        let model = load::model_with(Path::new(name), &files, &CsgOptions::default(), &limits());
        assert!(model.is_ok_and(|m| !m.parts.is_empty() || !m.solids.is_empty()), "{name}");
    }
}
