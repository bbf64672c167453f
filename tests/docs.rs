//! The documentation against the tree: what the README and the docs link is in
//! the repository (tracked, so a clone on any forge shows it), the layout
//! `ARCHITECTURE.md` draws names files and folders that exist, and nothing sends
//! a reader to files outside the repository.

#[path = "common/skip.rs"]
mod skip;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The Markdown files a reader of the repository opens.
fn documents() -> Vec<PathBuf> {
    let mut docs = vec![root().join("README.md"), root().join("ARCHITECTURE.md")];
    for entry in std::fs::read_dir(root().join("docs")).unwrap().flatten() {
        if entry.path().extension().is_some_and(|e| e == "md") {
            docs.push(entry.path());
        }
    }
    docs
}

/// The targets of Markdown links and images, `[text](target)`, that are not
/// web addresses or anchors.
fn local_links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(at) = rest.find("](") {
        rest = &rest[at + 2..];
        let Some(end) = rest.find(')') else { break };
        let target = rest[..end].split('#').next().unwrap_or("").trim();
        if !target.is_empty() && !target.contains("://") && !target.starts_with("mailto:") {
            out.push(target.to_string());
        }
    }
    out
}

/// The files git tracks, or `None` outside a git checkout.
fn tracked() -> Option<BTreeSet<String>> {
    let out = Command::new("git").arg("-C").arg(root()).args(["ls-files", "-z"]).output().ok()?;
    out.status
        .success()
        .then(|| out.stdout.split(|&b| b == 0).map(|p| String::from_utf8_lossy(p).into_owned()).collect())
}

#[test]
fn every_file_the_docs_link_is_in_the_repository() {
    let tracked = tracked();
    if tracked.is_none() {
        skip::skipped("the tracked-file half: not a git checkout (links are still checked to exist)");
    }
    let mut missing = Vec::new();
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        let folder = doc.parent().unwrap();
        for link in local_links(&text) {
            let path = folder.join(&link);
            let relative = path
                .canonicalize()
                .ok()
                .and_then(|p| p.strip_prefix(root().canonicalize().unwrap()).ok().map(Path::to_path_buf));
            let ok = match (&relative, &tracked) {
                (None, _) => false,
                (Some(r), Some(t)) => {
                    let r = r.to_string_lossy().into_owned();
                    // A folder is in the repository when a file under it is.
                    t.contains(&r) || t.iter().any(|f| f.starts_with(&format!("{r}/")))
                }
                (Some(_), None) => true,
            };
            if !ok {
                missing.push(format!("{}: {link}", doc.display()));
            }
        }
    }
    assert!(missing.is_empty(), "links to files that a clone lacks (untracked or absent): {missing:#?}");
}

#[test]
fn the_architecture_layout_names_what_exists() {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let layout = text.split("## Layout").nth(1).and_then(|s| s.split("```").nth(1)).expect("a layout block");
    // Every file and folder under the repository, by name.
    let mut names = BTreeSet::new();
    let mut stack = vec![root().to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') || name == "target" {
                continue;
            }
            if entry.path().is_dir() {
                names.insert(format!("{name}/"));
                stack.push(entry.path());
            } else {
                names.insert(name);
            }
        }
    }
    let mut unknown = Vec::new();
    for word in layout.split(|c: char| c.is_whitespace() || "(),;:".contains(c)) {
        let word = word.trim_matches(|c: char| c == '`' || c == '.');
        let named = word.ends_with(".rs") || (word.ends_with('/') && word.len() > 1);
        // `image/tone.rs`: check the last part; `solids/paper/`: each part.
        let parts: Vec<String> = if word.ends_with('/') {
            word.trim_end_matches('/').split('/').map(|p| format!("{p}/")).collect()
        } else {
            word.rsplit('/').next().map(String::from).into_iter().collect()
        };
        if named && parts.iter().any(|p| !names.contains(p)) {
            unknown.push(word.to_string());
        }
    }
    assert!(unknown.is_empty(), "ARCHITECTURE.md's layout names what the tree lacks: {unknown:?}");
}

#[test]
fn no_document_sends_the_reader_outside_the_repository() {
    let mut files = documents();
    let mut stack = vec![root().join("src"), root().join("cli/src"), root().join("bench/src")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            if entry.path().is_dir() {
                stack.push(entry.path());
            } else if entry.path().extension().is_some_and(|e| e == "rs") {
                files.push(entry.path());
            }
        }
    }
    let mut found = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        for (n, line) in text.lines().enumerate() {
            if line.contains("shared/seeds") || line.contains("SPEC.md") || line.contains("shared/design") {
                found.push(format!("{}:{}", file.display(), n + 1));
            }
        }
    }
    assert!(found.is_empty(), "the papers are cited in docs/papers.md, not by a path outside the clone: {found:#?}");
}

#[test]
fn the_link_reader_finds_links_and_images() {
    let md = "see [papers](docs/papers.md#seed-000), ![a](docs/gallery/a.png) and [web](https://x.org/y)";
    assert_eq!(local_links(md), ["docs/papers.md", "docs/gallery/a.png"]);
}
