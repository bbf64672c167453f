//! OpenSCAD `.csg` input (issue 6): every file of the shared corpus parses.

use std::path::Path;
use std::sync::Arc;

use kage::scene::load::openscad::{parse_csg, CsgNode};

fn count(nodes: &[CsgNode]) -> usize {
    nodes.iter().map(|n| 1 + count(&n.children)).sum()
}

#[test]
fn every_corpus_file_parses() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/csg");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        eprintln!("skipped: {} not found", dir.display());
        return;
    };
    let mut files: Vec<_> =
        entries.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "csg")).collect();
    files.sort();
    assert!(!files.is_empty(), "no .csg files in {}", dir.display());
    for path in &files {
        let text: Arc<str> = Arc::from(std::fs::read_to_string(path).unwrap());
        let nodes = parse_csg(path, Arc::clone(&text)).unwrap_or_else(|e| panic!("{e}"));
        // Every node of the file is read: as many nodes as lines that open one.
        let opening = text.lines().filter(|l| l.trim_end().ends_with(';') || l.trim_end().ends_with('{')).count();
        assert_eq!(count(&nodes), opening, "{}", path.display());
    }
    eprintln!("{} corpus files parsed", files.len());
}
