//! Every input that ever crashed kage, replayed: each file of
//! `tests/regressions/` listed in its `expected.txt` must give what the list
//! says — a render (with the warning named), or an error naming the fault —
//! never a panic. The fuzzers' and the bad-input campaign's finds land here,
//! minimised, so CI checks them in seconds without running a fuzzer.

use std::path::{Path, PathBuf};

use kage::csg::openscad::{CsgOptions, Geometry};
use kage::scene::file::load_scene;
use kage::scene::model::{scene_for_model_with, ModelOptions};
use kage::{render, RenderOptions, Scene};

fn folder() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/regressions")
}

/// One line of `expected.txt`.
struct Case {
    file: PathBuf,
    faceted: bool,
    renders: bool,
    text: String,
}

fn cases() -> Vec<Case> {
    let list = std::fs::read_to_string(folder().join("expected.txt")).expect("tests/regressions/expected.txt");
    list.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|line| {
            let parts: Vec<&str> = line.split('|').map(str::trim).collect();
            assert_eq!(parts.len(), 3, "expected.txt: `{line}` is not FILE | renders/error | TEXT");
            let mut words = parts[0].split_whitespace();
            let file = folder().join(words.next().expect("a file"));
            let faceted = words.next() == Some("faceted");
            assert!(matches!(parts[1], "renders" | "error"), "expected.txt: `{}` is not renders or error", parts[1]);
            Case { file, faceted, renders: parts[1] == "renders", text: parts[2].to_string() }
        })
        .collect()
}

fn load(case: &Case) -> kage::error::Result<Scene> {
    if case.file.extension().is_some_and(|e| e == "toml") {
        let mut scene = load_scene(&case.file)?;
        (scene.width, scene.height) = (32, 24);
        return Ok(scene);
    }
    let geometry = if case.faceted { Geometry::Faceted } else { Geometry::Exact };
    let options = ModelOptions { csg: CsgOptions { geometry, ..CsgOptions::default() }, ..ModelOptions::default() };
    scene_for_model_with(&case.file, 32, 24, &options)
}

#[test]
fn every_input_that_once_crashed_gives_what_the_list_says() {
    let cases = cases();
    assert!(cases.len() >= 13, "expected.txt lists {} cases", cases.len());
    for case in &cases {
        assert!(case.file.exists(), "{} is listed but absent", case.file.display());
        let name = case.file.display();
        match (load(case), case.renders) {
            (Ok(scene), true) => {
                let warned = case.text.is_empty() || scene.warnings.iter().any(|w| w.contains(&case.text));
                assert!(warned, "{name}: no warning containing `{}` in {:?}", case.text, scene.warnings);
                let frame = render(&scene, &RenderOptions::default())
                    .unwrap_or_else(|e| panic!("{name}: loads but fails: {e}"));
                let bad = frame.image.pixels().iter().position(|p| !(p.is_finite() && p.min_element() >= 0.0));
                assert!(bad.is_none(), "{name}: pixel {bad:?} is not a colour");
            }
            (Ok(scene), false) => match render(&scene, &RenderOptions::default()) {
                // What a frame asks for is checked when it starts.
                Err(e) => assert!(e.to_string().contains(&case.text), "{name}: `{e}` lacks `{}`", case.text),
                Ok(_) => panic!("{name}: rendered, but an error containing `{}` was expected", case.text),
            },
            (Err(e), true) => panic!("{name}: expected to render, got: {e}"),
            (Err(e), false) => {
                let e = e.to_string();
                assert!(e.contains(&case.text), "{name}: the error `{e}` does not contain `{}`", case.text);
            }
        }
    }
}

/// Every file in the folder is listed (a find added without its expectation
/// would never be replayed).
#[test]
fn every_file_of_the_folder_is_listed() {
    let listed: Vec<PathBuf> = cases().into_iter().map(|c| c.file).collect();
    let mut stack = vec![folder()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = entry.path();
            let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
            if path.is_dir() {
                stack.push(path);
            } else if matches!(ext, "obj" | "stl" | "gltf" | "glb" | "csg" | "toml") {
                assert!(listed.contains(&path), "{} is not in expected.txt", path.display());
            }
        }
    }
}
