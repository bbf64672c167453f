//! Scene TOML: parsed, built (the files it may name served from memory) and
//! rendered at a tiny size. The targets' limits are applied over the file's
//! `[limits]`, as the command line's `--limit` would be.
#![no_main]
use std::path::Path;

use kage::scene::file::SceneFile;

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else { return };
    let Ok(file) = SceneFile::parse(text, Path::new("s.toml")) else { return };
    let files = kage_fuzz::files(&[]);
    if let Ok(scene) = file.build_with(&files, &kage_fuzz::settings()) {
        kage_fuzz::render_small(scene);
    }
});
