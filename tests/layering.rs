//! The frame's layering, kept by a test: a top-level module of the library may
//! use only the modules below it in the frame's order, and within any folder
//! no two files use each other, however indirectly. Paths are read from the
//! source (`use` trees and `crate::`/`super::` paths in code; comments and
//! doc links are not imports).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The library's top-level modules, the ground floor first: each may use the
/// ones before it only.
const FRAME_ORDER: &[&str] = &[
    "limits",
    "error",
    "sampling",
    "idle",
    "image",
    "camera",
    "triangle",
    "polygon",
    "bvh",
    "csg",
    "scene",
    "visibility",
    "shadows",
    "shading",
    "raytrace",
    "resolve",
    "frame",
    "output",
    "compare",
];

/// A module's path from the crate root (`[]` is the root).
type ModPath = Vec<String>;

/// Every module's source with comments removed, by module path.
fn read_tree(src: &Path) -> BTreeMap<ModPath, String> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("src is readable").flatten() {
            let path = entry.path();
            if path.is_dir() {
                // Binaries are crates of their own.
                if path.file_name().is_some_and(|n| n != "bin") {
                    stack.push(path);
                }
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path.strip_prefix(src).expect("under src").with_extension("");
                let mut module: ModPath = rel.iter().map(|s| s.to_string_lossy().into_owned()).collect();
                if matches!(module.last().map(String::as_str), Some("mod" | "lib")) {
                    module.pop();
                }
                let text = std::fs::read_to_string(&path).expect("source is UTF-8");
                out.insert(module, without_comments(&text));
            }
        }
    }
    out
}

/// `text` without `//` comments (doc comments included), `/* */` blocks and
/// what string and character literals hold (a word in a message is not a
/// path); line breaks are kept.
fn without_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    let (mut in_string, mut depth) = (false, 0usize);
    while let Some(c) = chars.next() {
        match c {
            '\n' => out.push(c),
            _ if depth > 0 => match (c, chars.peek()) {
                ('*', Some('/')) => {
                    chars.next();
                    depth -= 1;
                }
                ('/', Some('*')) => {
                    chars.next();
                    depth += 1;
                }
                _ => {}
            },
            '\\' if in_string => {
                chars.next();
            }
            '"' => {
                in_string = !in_string;
                out.push(c);
            }
            _ if in_string => {}
            '\'' => {
                // A character literal ('x', '\n', '"'), or a lifetime ('a).
                let mut ahead = chars.clone();
                let literal = match ahead.next() {
                    Some('\\') => true,
                    Some(_) => ahead.next() == Some('\''),
                    None => false,
                };
                if literal {
                    while let Some(c) = chars.next() {
                        if c == '\\' {
                            chars.next();
                        } else if c == '\'' {
                            break;
                        }
                    }
                }
                out.push(' ');
            }
            '/' if chars.peek() == Some(&'/') => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            '/' if chars.peek() == Some(&'*') => {
                chars.next();
                depth = 1;
            }
            _ => out.push(c),
        }
    }
    out
}

/// The paths a `use` tree names (`a::{b, c::{d, self}}` → `a::b`, `a::c::d`,
/// `a::c`), as lists of segments.
fn expand_use_tree(tree: &str) -> Vec<Vec<String>> {
    let tree: String = without_renames(tree).chars().filter(|c| !c.is_whitespace()).collect();
    let Some(open) = tree.find('{') else {
        return vec![tree.split("::").filter(|s| !s.is_empty()).map(str::to_string).collect()];
    };
    let prefix: Vec<String> = tree[..open].split("::").filter(|s| !s.is_empty()).map(str::to_string).collect();
    let close = tree.rfind('}').filter(|&c| c > open).unwrap_or(tree.len());
    let inner = &tree[open + 1..close];
    let (mut parts, mut depth, mut start) = (Vec::new(), 0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    let mut out = Vec::new();
    for part in parts.into_iter().filter(|p| !p.is_empty()) {
        for tail in expand_use_tree(part) {
            let mut path = prefix.clone();
            path.extend(tail.into_iter().filter(|s| s != "self"));
            out.push(path);
        }
    }
    out
}

/// `tree` without its renames (`a::b as c` → `a::b`): the word `as` and the
/// name after it, whatever the spacing; names that merely hold the letters
/// "as" (`passes`, `aa`) stay whole.
fn without_renames(tree: &str) -> String {
    let is_name = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = String::with_capacity(tree.len());
    let mut rest = tree;
    while let Some(at) = find_word(rest, "as") {
        out.push_str(&rest[..at]);
        let after = rest[at + 2..].trim_start();
        rest = after.trim_start_matches(is_name);
    }
    out.push_str(rest);
    out
}

/// Every path `source` names: its `use` trees, and the `crate::`, `super::`
/// and `self::` paths written in its code.
fn named_paths(source: &str) -> Vec<Vec<String>> {
    let mut paths = Vec::new();
    let mut rest = source;
    while let Some(at) = find_word(rest, "use") {
        let tail = &rest[at + 3..];
        let end = tail.find(';').unwrap_or(tail.len());
        if tail.starts_with(char::is_whitespace) {
            paths.extend(expand_use_tree(&tail[..end]));
        }
        rest = &tail[end.min(tail.len())..];
    }
    for root in ["crate", "super", "self"] {
        let mut rest = source;
        while let Some(at) = find_word(rest, root) {
            let tail = &rest[at..];
            let len = tail.find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')).unwrap_or(tail.len());
            let path: Vec<String> = tail[..len].split("::").filter(|s| !s.is_empty()).map(str::to_string).collect();
            if path.len() > 1 {
                paths.push(path);
            }
            rest = &tail[len.max(1)..];
        }
    }
    paths
}

/// Where `word` stands alone in `text` (not part of a longer name).
fn find_word(text: &str, word: &str) -> Option<usize> {
    let is_name = |c: char| c.is_alphanumeric() || c == '_';
    let mut from = 0;
    while let Some(i) = text[from..].find(word).map(|i| i + from) {
        let before = text[..i].chars().next_back();
        let after = text[i + word.len()..].chars().next();
        if !before.is_some_and(is_name) && !after.is_some_and(is_name) {
            return Some(i);
        }
        from = i + word.len();
    }
    None
}

/// The module a path written in `module` leads to: the longest prefix of it
/// that is a module of the tree (`None` for paths into other crates).
fn target(tree: &BTreeMap<ModPath, String>, module: &ModPath, path: &[String]) -> Option<ModPath> {
    let (mut base, mut segs): (ModPath, &[String]) = match path.first().map(String::as_str) {
        Some("crate") => (Vec::new(), &path[1..]),
        Some("self") => (module.clone(), &path[1..]),
        Some("super") => (module[..module.len().saturating_sub(1)].to_vec(), &path[1..]),
        Some(first) => {
            let mut child = module.clone();
            child.push(first.to_string());
            if !tree.contains_key(&child) {
                return None; // another crate, or an item of this module
            }
            (module.clone(), path)
        }
        None => return None,
    };
    while segs.first().is_some_and(|s| s == "super") {
        base.pop();
        segs = &segs[1..];
    }
    base.extend(segs.iter().cloned());
    (0..=base.len()).rev().map(|k| base[..k].to_vec()).find(|m| tree.contains_key(m))
}

/// The items the crate root re-exports (`pub use frame::render;` at the
/// root), by name → the module they come from.
fn root_exports(tree: &BTreeMap<ModPath, String>) -> BTreeMap<String, ModPath> {
    let Some(root) = tree.get(&Vec::new()) else { return BTreeMap::new() };
    let mut out = BTreeMap::new();
    let mut rest = root.as_str();
    while let Some(at) = find_word(rest, "pub") {
        let tail = rest[at + 3..].trim_start();
        let end = tail.find(';').unwrap_or(tail.len());
        if let Some(tree_text) = tail.strip_prefix("use").filter(|t| t.starts_with(char::is_whitespace)) {
            for path in expand_use_tree(&tree_text[..end - 3]) {
                let (Some(name), Some(from)) = (path.last(), target(tree, &Vec::new(), &path)) else { continue };
                if !from.is_empty() {
                    out.insert(name.clone(), from);
                }
            }
        }
        rest = &tail[end.min(tail.len())..];
    }
    out
}

/// The module a path written in `module` leads to, a crate-root re-export
/// followed to the module it comes from.
fn resolved(
    tree: &BTreeMap<ModPath, String>,
    exports: &BTreeMap<String, ModPath>,
    module: &ModPath,
    path: &[String],
) -> Option<ModPath> {
    let found = target(tree, module, path)?;
    if !found.is_empty() {
        return Some(found);
    }
    // At the root: the segment after the modules walked is an item there.
    let item = path.iter().find(|s| !matches!(s.as_str(), "crate" | "super" | "self"))?;
    Some(exports.get(item).cloned().unwrap_or(found))
}

/// Every module → the modules it uses.
fn uses(tree: &BTreeMap<ModPath, String>) -> BTreeMap<ModPath, BTreeSet<ModPath>> {
    let exports = root_exports(tree);
    tree.iter()
        .map(|(module, source)| {
            let targets = named_paths(source)
                .iter()
                .filter_map(|p| resolved(tree, &exports, module, p))
                .filter(|t| t != module)
                .collect();
            (module.clone(), targets)
        })
        .collect()
}

/// `module → target` pairs where a top-level module uses one later in
/// `order` (or one `order` does not name).
fn upward(uses: &BTreeMap<ModPath, BTreeSet<ModPath>>, order: &[&str]) -> Vec<String> {
    let rank = |m: &ModPath| m.first().map(|top| order.iter().position(|o| o == top));
    let mut out = Vec::new();
    for (module, targets) in uses {
        for t in targets {
            let (Some(a), Some(b)) = (rank(module), rank(t)) else { continue };
            if a.is_none() || b.is_none() || (a != b && b > a) {
                out.push(format!("{} uses {}", module.join("::"), t.join("::")));
            }
        }
    }
    out
}

/// Groups of sibling modules (children of one folder) that use each other in
/// a circle, found through their descendants' uses; a folder's own module
/// (`mod.rs`), which its children may read, is not a sibling.
fn sibling_circles(uses: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Vec<String> {
    let parents: BTreeSet<ModPath> = uses.keys().filter(|m| !m.is_empty()).map(|m| m[..m.len() - 1].to_vec()).collect();
    let mut out = Vec::new();
    for parent in parents {
        let child =
            |m: &ModPath| (m.len() > parent.len() && m[..parent.len()] == parent[..]).then(|| m[parent.len()].clone());
        let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (module, targets) in uses {
            let Some(a) = child(module) else { continue };
            for b in targets.iter().filter_map(child).filter(|b| *b != a) {
                graph.entry(a.clone()).or_default().insert(b);
            }
        }
        for circle in circles(&graph) {
            let at = if parent.is_empty() { "the crate root".to_string() } else { parent.join("::") };
            out.push(format!("in {at}: {} use each other", circle.join(", ")));
        }
    }
    out
}

/// The strongly connected groups of more than one node (Tarjan).
fn circles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct Walk<'g> {
        graph: &'g BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'g str, (usize, usize)>,
        stack: Vec<&'g str>,
        out: Vec<Vec<String>>,
    }
    impl<'g> Walk<'g> {
        fn visit(&mut self, v: &'g str) -> usize {
            let n = self.index.len();
            self.index.insert(v, (n, n));
            self.stack.push(v);
            let mut low = n;
            for w in self.graph.get(v).into_iter().flatten() {
                low = low.min(match self.index.get(w.as_str()) {
                    None => self.visit(w),
                    Some(&(i, _)) if self.stack.contains(&w.as_str()) => i,
                    Some(_) => usize::MAX,
                });
            }
            self.index.insert(v, (n, low));
            if low == n {
                let at = self.stack.iter().position(|&s| s == v).expect("on the stack");
                let group: Vec<String> = self.stack.split_off(at).into_iter().map(str::to_string).collect();
                if group.len() > 1 {
                    self.out.push(group);
                }
            }
            low
        }
    }
    let mut walk = Walk { graph, index: BTreeMap::new(), stack: Vec::new(), out: Vec::new() };
    for v in graph.keys() {
        if !walk.index.contains_key(v.as_str()) {
            walk.visit(v);
        }
    }
    walk.out
}

fn library() -> BTreeMap<ModPath, String> {
    read_tree(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"))
}

/// The library's front door for the command line and the viewer: the items
/// the crate root re-exports (render, the reference, frame statistics, the
/// component list, ...) and these modules, which describe a scene and its
/// images. The stages (visibility, shadows, shading, ray tracing, resolve,
/// the frame's internals) stay behind it.
const FRONT_DOOR_MODULES: &[&[&str]] =
    &[&["scene"], &["camera"], &["image"], &["output"], &["compare"], &["error"], &["limits"], &["csg", "openscad"]];

/// Every `kage::` path `source` names: in its `use` trees and in its code.
fn kage_paths(source: &str) -> Vec<Vec<String>> {
    let mut paths: Vec<Vec<String>> =
        named_paths(source).into_iter().filter(|p| p.first().is_some_and(|s| s == "kage")).collect();
    let mut rest = source;
    while let Some(at) = find_word(rest, "kage") {
        let tail = &rest[at..];
        let len = tail.find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')).unwrap_or(tail.len());
        let path: Vec<String> = tail[..len].split("::").filter(|s| !s.is_empty()).map(str::to_string).collect();
        if path.len() > 1 && tail[..len].contains("::") {
            paths.push(path);
        }
        rest = &tail[len.max(1)..];
    }
    paths
}

/// Where the crate in `tree` (a binary using the library) goes round the
/// front door: an item the crate root re-exports from a stage named by its
/// module path, and (unless `stages` is set) any path into a module that is
/// not in [`FRONT_DOOR_MODULES`]. A module of the binary that uses an item of the
/// binary's root (`main.rs`) is reported too: the root dispatches, the
/// modules do the work.
fn front_door_breaches(tree: &BTreeMap<ModPath, String>, lib: &BTreeMap<ModPath, String>, stages: bool) -> Vec<String> {
    let exports = root_exports(lib);
    let mut out = BTreeSet::new();
    for (module, source) in tree {
        let at = if module.is_empty() { "main".to_string() } else { module.join("::") };
        for path in kage_paths(source) {
            let rest = &path[1..];
            let Some(m) = target(lib, &Vec::new(), rest).filter(|m| !m.is_empty()) else { continue };
            let written = path.join("::");
            let front = FRONT_DOOR_MODULES.iter().any(|f| m.len() >= f.len() && m[..f.len()] == **f);
            if let Some(item) = rest.get(m.len()).filter(|i| !front && exports.get(*i) == Some(&m)) {
                out.insert(format!("{at} names {written}: use kage::{item}"));
            } else if !stages && !front {
                out.insert(format!("{at} reaches into kage::{} (a stage behind the front door)", m.join("::")));
            }
        }
        if module.is_empty() {
            continue;
        }
        for path in named_paths(source) {
            let Some(t) = target(tree, module, &path) else { continue };
            if t.is_empty() && path.iter().any(|s| !matches!(s.as_str(), "crate" | "super" | "self")) {
                out.insert(format!("{at} uses {} from the binary's root", path.join("::")));
            }
        }
    }
    out.into_iter().collect()
}

#[test]
fn the_command_line_and_the_viewer_use_the_library_through_its_front_door() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let found = front_door_breaches(&read_tree(&root.join("cli/src")), &library(), false);
    assert!(found.is_empty(), "round the front door:\n{}", found.join("\n"));
}

/// The benchmarks measure stages one by one, so they may reach them; what
/// the front door offers they take from it.
#[test]
fn the_benchmarks_take_what_the_front_door_offers_from_it() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let found = front_door_breaches(&read_tree(&root.join("bench/src")), &library(), true);
    assert!(found.is_empty(), "round the front door:\n{}", found.join("\n"));
}

#[test]
fn every_top_level_module_has_its_place_in_the_frame() {
    let tree = library();
    let tops: BTreeSet<&str> = tree.keys().filter_map(|m| m.first().map(String::as_str)).collect();
    let unplaced: Vec<&str> = tops.iter().copied().filter(|t| !FRAME_ORDER.contains(t)).collect();
    assert!(unplaced.is_empty(), "modules missing from FRAME_ORDER: {unplaced:?}");
}

#[test]
fn top_level_modules_use_only_modules_below_them() {
    let found = upward(&uses(&library()), FRAME_ORDER);
    assert!(found.is_empty(), "imports against the frame's order:\n{}", found.join("\n"));
}

#[test]
fn no_two_files_of_a_folder_use_each_other() {
    let found = sibling_circles(&uses(&library()));
    assert!(found.is_empty(), "import circles:\n{}", found.join("\n"));
}

/// The checks find what they look for: a scene that reads shading, and two
/// files of one folder that read each other through a grouped `use`, are
/// reported; the same names in comments and in other crates' paths are not.
#[test]
fn the_checks_catch_an_upward_import_and_a_circle() {
    let file = |path: &[&str], text: &str| (path.iter().map(|s| s.to_string()).collect(), without_comments(text));
    let tree: BTreeMap<ModPath, String> = [
        file(&[], "mod scene; mod shading; mod resolve;"),
        file(&["scene"], "use crate::shading::Fog; // crate::resolve::x\n/* use crate::resolve::y; */"),
        file(&["shading"], "use glam::Vec3; use image::Rgb;"),
        file(&["resolve"], "mod edges; mod parts;"),
        file(&["resolve", "edges"], "use super::{parts::Plan, PixelSet};"),
        file(&["resolve", "parts"], "fn f() -> super::edges::Blend { todo() }"),
    ]
    .into_iter()
    .collect();
    let order = ["scene", "shading", "resolve"];
    let uses = uses(&tree);
    assert_eq!(upward(&uses, &order), vec!["scene uses shading".to_string()]);
    assert_eq!(sibling_circles(&uses), vec!["in resolve: edges, parts use each other".to_string()]);
    let clean = BTreeMap::from([(vec!["scene".to_string()], String::new())]);
    assert!(upward(&crate::uses(&clean), &order).is_empty());
    // A rename is not part of the path; a name holding "as" is whole.
    assert_eq!(expand_use_tree("super::passes::x as y"), vec![vec!["super", "passes", "x"]]);
    assert_eq!(expand_use_tree("a::{b as c, aas}"), vec![vec!["a", "b"], vec!["a", "aas"]]);
    // Through a crate-root re-export, a scene reading shading is still seen.
    let tree: BTreeMap<ModPath, String> = [
        file(&[], "mod scene; mod shading; pub use shading::Fog;"),
        file(&["scene"], "fn f(_: crate::Fog) {}"),
        file(&["shading"], ""),
    ]
    .into_iter()
    .collect();
    assert_eq!(upward(&crate::uses(&tree), &order), vec!["scene uses shading".to_string()]);
    // A binary naming a stage, or a re-exported item by its module, and a
    // module of it calling into its root, are reported.
    let lib: BTreeMap<ModPath, String> = [
        file(&[], "mod scene; mod shading; pub use shading::Component;"),
        file(&["scene"], ""),
        file(&["shading"], "pub fn screen_surfaces() {}"),
    ]
    .into_iter()
    .collect();
    let bin: BTreeMap<ModPath, String> = [
        file(&[], "mod batch; fn render_command() {} use kage::scene::Scene;"),
        file(
            &["batch"],
            "use super::render_command; fn f() { kage::shading::screen_surfaces(); }\nuse kage::shading::Component;",
        ),
    ]
    .into_iter()
    .collect();
    assert_eq!(
        front_door_breaches(&bin, &lib, false),
        vec![
            "batch names kage::shading::Component: use kage::Component".to_string(),
            "batch reaches into kage::shading (a stage behind the front door)".to_string(),
            "batch uses super::render_command from the binary's root".to_string(),
        ]
    );
}
