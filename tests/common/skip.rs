//! A test that cannot run here (a shared asset, a system program or a
//! display is missing) says so: on stderr, and as a line of the file
//! `$KAGE_SKIP_LOG` names, which `.ci/run` prints with a count at the end, so
//! a fresh clone's run says what it did not check.

use std::io::Write;

/// Records that the running test skipped (all or part of) its check, and why.
#[allow(dead_code, reason = "each test crate includes this file; not all of them skip")]
pub fn skipped(why: &str) {
    let test = std::thread::current().name().unwrap_or("a test").to_string();
    eprintln!("skipped: {why}");
    if let Some(log) = std::env::var_os("KAGE_SKIP_LOG") {
        if let Ok(mut file) = std::fs::OpenOptions::new().create(true).append(true).open(log) {
            let _ = writeln!(file, "{test}: {why}");
        }
    }
}

/// A real model by its path in the shared corpus (`gltf/Box/Box.glb`):
/// from `../shared/assets` where present, else from the copies the
/// repository keeps of the small ones (`tests/data/assets`; `tests/data/csg`
/// holds two OpenSCAD models), else `None`, the skip recorded.
#[allow(dead_code, reason = "each test crate includes this file; not all of them read models")]
pub fn asset(rel: &str) -> Option<std::path::PathBuf> {
    // The repository's root, from the library's tests or a member crate's.
    let here = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let root = here.ancestors().find(|d| d.join("tests/data/assets").is_dir()).unwrap_or(here);
    let found = ["../shared/assets", "tests/data/assets", "tests/data"]
        .iter()
        .map(|dir| root.join(dir).join(rel))
        .find(|p| p.exists());
    if found.is_none() {
        skipped(&format!("{rel} is neither in ../shared/assets nor kept in tests/data"));
    }
    found
}
