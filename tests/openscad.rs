//! OpenSCAD `.csg` input: every file of the shared corpus parses and
//! loads, its primitive counts match the corpus table, and in faceted mode the
//! solid agrees with the mesh OpenSCAD's own CGAL render wrote (its STL), point by
//! point. Everything here skips cleanly when `../shared/assets` is absent.

#[path = "common/skip.rs"]
mod skip;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;
use kage::csg::openscad::syntax::{parse_csg, CsgNode};
use kage::csg::openscad::{load_csg, CsgOptions, Geometry};
use kage::scene::load::{model, FileSystem};

fn corpus() -> Option<(PathBuf, Vec<PathBuf>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/csg");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        skip::skipped(&format!("{} not found", dir.display()));
        return None;
    };
    let mut files: Vec<_> =
        entries.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "csg")).collect();
    files.sort();
    assert!(!files.is_empty(), "no .csg files in {}", dir.display());
    Some((dir, files))
}

fn read(path: &Path) -> Arc<str> {
    Arc::from(std::fs::read_to_string(path).unwrap())
}

fn count(nodes: &[CsgNode]) -> usize {
    nodes.iter().map(|n| 1 + count(&n.children)).sum()
}

/// Leaf nodes by kind (cube, sphere, cylinder, polyhedron), `%` subtrees included.
fn leaves(nodes: &[CsgNode], out: &mut [usize; 4]) {
    for n in nodes {
        if let Some(k) = ["cube", "sphere", "cylinder", "polyhedron"].iter().position(|k| *k == n.name) {
            out[k] += 1;
        }
        leaves(&n.children, out);
    }
}

#[test]
fn every_corpus_file_parses() {
    let Some((_, files)) = corpus() else { return };
    for path in &files {
        let text = read(path);
        let nodes = parse_csg(path, Arc::clone(&text), &Default::default()).unwrap_or_else(|e| panic!("{e}"));
        // Every node of the file is read: as many nodes as lines that open one.
        let opening = text.lines().filter(|l| l.trim_end().ends_with(';') || l.trim_end().ends_with('{')).count();
        assert_eq!(count(&nodes), opening, "{}", path.display());
    }
}

#[test]
fn primitive_counts_match_the_corpus_table() {
    let Some((dir, files)) = corpus() else { return };
    // SOURCES.md's table: | name | prims | cube/sphere/cyl/poly | ... (written by
    // the corpus's own tool, csgstat.py).
    let table = std::fs::read_to_string(dir.join("SOURCES.md")).unwrap();
    let mut checked = 0;
    for row in table.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| name")) {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let (name, kinds) = (cells[1], cells[3]);
        let Some(path) = files.iter().find(|p| p.file_stem().is_some_and(|s| s == name)) else { continue };
        let expected: Vec<usize> = kinds.split('/').map(|k| k.parse().unwrap()).collect();
        let mut got = [0; 4];
        leaves(&parse_csg(path, read(path), &Default::default()).unwrap(), &mut got);
        assert_eq!(got.to_vec(), expected, "{name}");
        checked += 1;
    }
    assert!(checked >= 20, "only {checked} rows of the table matched corpus files");
}

#[test]
fn every_corpus_model_loads_in_both_geometry_modes() {
    let Some((_, files)) = corpus() else { return };
    for path in &files {
        for geometry in [Geometry::Exact, Geometry::Faceted] {
            let options = CsgOptions { geometry, skip_unsupported: false };
            let loaded = load_csg(path, read(path), &options, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
            assert!(loaded.solid.tree.is_some(), "{}: empty", path.display());
        }
    }
}

/// Whether `p` is inside the closed triangle mesh `tris`: the parity of a ray's
/// crossings (Möller–Trumbore), in a direction no face of these models is
/// parallel to.
fn inside_mesh(tris: &[[Vec3; 3]], p: Vec3) -> bool {
    let dir = Vec3::new(0.5773, 0.4071, 0.6932).normalize();
    let mut crossings = 0;
    for [a, b, c] in tris {
        let (e1, e2) = (*b - *a, *c - *a);
        let pv = dir.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-12 {
            continue;
        }
        let tv = p - *a;
        let u = tv.dot(pv) / det;
        let qv = tv.cross(e1);
        let v = dir.dot(qv) / det;
        let t = e2.dot(qv) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 {
            crossings += 1;
        }
    }
    crossings % 2 == 1
}

#[test]
fn faceted_solids_agree_with_openscads_own_mesh_point_by_point() {
    // Two models kept in the repository always run; the corpus adds more.
    let local = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/csg");
    let mut models: Vec<(PathBuf, String)> =
        ["ex001_sphere_minus_cylinders", "ex004_cube_minus_sphere"].map(|n| (local.clone(), n.to_string())).to_vec();
    // Every corpus model OpenSCAD rendered to STL (lego_90498's render never
    // finished, so it has none).
    if let Some((dir, files)) = corpus() {
        for path in files.iter().filter(|p| p.with_extension("stl").exists()) {
            let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default().to_string();
            if !models.iter().any(|(_, n)| *n == name) {
                models.push((dir.clone(), name));
            }
        }
    }
    let options = CsgOptions { geometry: Geometry::Faceted, skip_unsupported: false };
    for (dir, name) in models {
        let csg = dir.join(format!("{name}.csg"));
        let solid = load_csg(&csg, read(&csg), &options, &Default::default()).unwrap().solid;
        let stl = model(Path::new(&format!("{name}.stl")), &FileSystem { base: dir.clone() }).unwrap();
        let tris: Vec<[Vec3; 3]> = stl
            .parts
            .iter()
            .flat_map(|part| {
                let m = &part.mesh;
                m.triangles.iter().map(|t| t.map(|i| part.transform.transform_point3(m.positions[i as usize])))
            })
            .collect();
        let (lo, hi) =
            tris.iter().flatten().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), &p| (a.min(p), b.max(p)));
        // Halton points in the mesh's bounds, a little beyond them.
        let (lo, hi) = (lo - (hi - lo) * 0.05, hi + (hi - lo) * 0.05);
        let halton = |mut i: u32, b: u32| {
            let (mut f, mut r) = (1.0, 0.0);
            while i > 0 {
                f /= b as f32;
                r += f * (i % b) as f32;
                i /= b;
            }
            r
        };
        let n = 6000;
        let (mut differ, mut inside) = (0, 0);
        for i in 1..=n {
            let p = lo + (hi - lo) * Vec3::new(halton(i, 2), halton(i, 3), halton(i, 5));
            let truth = inside_mesh(&tris, p);
            inside += usize::from(truth);
            differ += usize::from(truth != solid.contains(p));
        }
        eprintln!("{name}: {differ} of {n} points differ ({inside} inside)");
        assert!(inside > n as usize / 50, "{name}: the sample missed the solid");
        // Points within rounding of a face may fall either way; none did when this was
        // written (a sphere's rings a quarter ring off made 0.2%).
        assert!(differ * 1000 <= n as usize, "{name}: {differ} of {n} points differ from OpenSCAD's mesh");
    }
}

/// The corpus camera of `name` and its image size, from its `.camera.txt` sidecar.
fn sidecar_camera(dir: &Path, name: &str) -> Option<(kage::camera::Camera, u32, u32)> {
    kage::csg::openscad::sidecar_camera(&std::fs::read_to_string(dir.join(format!("{name}.camera.txt"))).ok()?)
}

/// The share of pixels where the solid of the `.csg` at `path`, read with
/// `geometry` and scanned by seed 003's walk, and OpenSCAD's mesh beside it
/// (`NAME.stl`, rasterized by kage) both show or both miss the model, seen
/// by `camera` (the sidecar's, else OpenSCAD's default view of the mesh); and
/// the share of the pixels both cover where their surfaces lie at different
/// depths (by a thousandth of the model's size).
fn coverage_agreement(path: &Path, geometry: Geometry, camera: Option<(kage::camera::Camera, u32, u32)>) -> (f64, f64) {
    let options = CsgOptions { geometry, skip_unsupported: false };
    let files = FileSystem { base: path.parent().unwrap_or(Path::new(".")).to_path_buf() };
    let name = Path::new(path.file_name().unwrap_or_default());
    let loaded = kage::scene::load::model_with(name, &files, &options, &Default::default());
    let solid = &loaded.unwrap_or_else(|e| panic!("{e}")).solids[0].solid;
    // The mesh as OpenSCAD wrote it (z up, no ground): the camera's frame.
    let as_written =
        kage::scene::model::ModelOptions { up: Some(kage::scene::Up::Y), ground: false, ..Default::default() };
    let (w, h) = camera.map_or((640, 480), |(_, w, h)| (w, h));
    let mut scene = kage::scene::model::scene_for_model_with(&path.with_extension("stl"), w, h, &as_written).unwrap();
    scene.camera = match camera {
        Some((c, ..)) => c,
        None => kage::csg::openscad::default_view(scene.bounds().expect("a mesh")),
    };
    let scanned = kage::visibility::solids::scan_solid(solid, &scene.camera, w, h);
    let mut vb = kage::visibility::VisibilityBuffer::new(w, h);
    kage::visibility::rasterize(&scene, &mut vb);
    let (mut agree, mut either, mut both, mut deeper) = (0usize, 0usize, 0usize, 0usize);
    let size = scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length());
    let rays = scene.camera.pixel_rays(glam::Vec2::new(w as f32, h as f32));
    for (i, (s, item)) in scanned.iter().zip(vb.items()).enumerate() {
        let (a, b) = (s.is_some(), !item.is_none());
        agree += usize::from(a == b);
        either += usize::from(a || b);
        if let (Some(s), true) = (s, b) {
            // The nearest surface lies as deep in both (a hole, an engraving).
            let pixel = glam::Vec2::new((i as u32 % w) as f32 + 0.5, (i as u32 / w) as f32 + 0.5);
            let ray = rays.ray(pixel);
            let t = scene.camera.distance_at_depth(&ray, vb.depths()[i]);
            both += 1;
            deeper += usize::from((t - s.t).abs() > 1e-3 * size);
        }
    }
    let share = agree as f64 / scanned.len() as f64;
    let of_covered = 1.0 - (scanned.len() - agree) as f64 / either.max(1) as f64;
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
    eprintln!(
        "{name} ({geometry:?}): coverage agrees on {:.3}% of pixels ({:.2}% of the {either} covered); depth differs at {deeper} of {both}",
        share * 100.0,
        of_covered * 100.0
    );
    (share, deeper as f64 / both.max(1) as f64)
}

#[test]
fn scanned_coverage_matches_openscads_mesh_rasterized_by_kage() {
    // The two models kept in the repository always run; the corpus adds the rest.
    let local = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/csg");
    let mut files: Vec<PathBuf> =
        ["ex001_sphere_minus_cylinders", "ex004_cube_minus_sphere"].map(|n| local.join(format!("{n}.csg"))).to_vec();
    if let Some((_, corpus_files)) = corpus() {
        let kept: Vec<_> = files.iter().filter_map(|f| f.file_name().map(ToOwned::to_owned)).collect();
        files.extend(corpus_files.into_iter().filter(|p| p.file_name().is_none_or(|n| !kept.iter().any(|k| k == n))));
    }
    let mut worst = 1.0f64;
    for path in files.iter().filter(|p| p.with_extension("stl").exists()) {
        let dir = path.parent().unwrap_or(Path::new("."));
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        let camera = sidecar_camera(dir, name).unwrap_or_else(|| panic!("{name}: no camera sidecar"));
        let (share, _) = coverage_agreement(path, Geometry::Faceted, Some(camera));
        worst = worst.min(share);
        assert!(share >= 0.995, "{name}: coverage agrees on only {:.3}% of pixels", share * 100.0);
    }
    eprintln!("worst: {:.3}%", worst * 100.0);
}

/// Every construct model of `tests/data/openscad` (extrusions, revolutions,
/// offsets, 2-D booleans, hulls and Minkowski sums of anything, projections,
/// resizes, text): the solid kage reads from OpenSCAD's `.csg` covers the
/// same pixels as the exact mesh OpenSCAD itself made of the same model
/// (`scripts/openscad-constructs.sh` wrote both), in both geometry modes, and
/// with OpenSCAD's facets its nearest surface lies as deep at 99% of them.
#[test]
fn every_construct_agrees_with_openscads_exact_mesh() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/openscad");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "csg") && p.with_extension("stl").exists())
        .collect();
    files.sort();
    assert!(files.len() >= 13, "only {} construct models", files.len());
    let mut failed = Vec::new();
    for path in &files {
        for geometry in [Geometry::Exact, Geometry::Faceted] {
            let (share, deeper) = coverage_agreement(path, geometry, None);
            // Exact quadrics lie off OpenSCAD's facets: their depths differ
            // by design; the facets' must not.
            let deeper = if geometry == Geometry::Faceted { deeper } else { 0.0 };
            if share < 0.995 || deeper > 0.01 {
                failed.push(format!(
                    "{} ({geometry:?}): {:.3}%, depth off at {:.3}%",
                    path.display(),
                    share * 100.0,
                    deeper * 100.0
                ));
            }
        }
    }
    assert!(failed.is_empty(), "coverage below 99.5%: {failed:#?}");
}

/// OpenSCAD's preview marks: a highlighted (`#`) cutter is drawn see-through
/// pink where it cut the part away, and a background (`%`) part is drawn
/// see-through grey but is no part of the model.
#[test]
fn a_highlighted_cutter_shows_where_it_cut_and_a_background_part_is_not_solid() {
    let dir = std::env::temp_dir().join(format!("kage-ghosts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cutter = "cylinder($fn = 32, $fa = 12, $fs = 2, h = 30, r1 = 5, r2 = 5, center = true);";
    let marked = format!("difference() {{\n\tcube(size = [20, 20, 20], center = true);\n#\t{cutter}\n}}\n%multmatrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, -30], [0, 0, 0, 1]]) {{\n\tcube(size = [5, 5, 5], center = true);\n}}\n");
    let plain = marked.replace("#\t", "\t");
    let options = kage::scene::model::ModelOptions {
        camera: kage::scene::framing::CameraOverride {
            view: Some(kage::scene::framing::View::TOP),
            ..Default::default()
        },
        ground: false,
        ..Default::default()
    };
    let centre = |text: &str, name: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let scene = kage::scene::model::scene_for_model_with(&path, 96, 96, &options).unwrap();
        let frame = kage::render(&scene, &kage::RenderOptions::default()).unwrap();
        let solid = scene.objects.iter().find_map(|o| o.solid()).unwrap().clone();
        (frame.image.get(48, 48), scene.objects.len(), solid)
    };
    let (pink, objects, solid) = centre(&marked, "marked.csg");
    let (through, plain_objects, _) = centre(&plain, "plain.csg");
    // The model, a ghost per mark (the plain file: the `%` one only).
    assert_eq!((objects, plain_objects), (3, 2));
    // Down the hole: the cutter's ghost tints the view red over green.
    assert!(pink.x > pink.y * 1.3, "no pink in the hole: {pink:?} (without the mark: {through:?})");
    assert!(through.x < through.y * 1.2, "the hole is pink without a mark: {through:?}");
    // The `%` cube (under the part) is drawn but not solid.
    assert!(!solid.contains(glam::Vec3::new(0.0, 0.0, -30.0)) && solid.contains(glam::Vec3::new(8.0, 8.0, 0.0)));
}

/// A `color()` with an alpha below 1 on a part of its own is drawn
/// see-through (the ground shows through it, not through the same part
/// opaque) and is no part of the solid; inside a difference it is drawn
/// opaque with a warning.
#[test]
fn a_see_through_colour_shows_what_is_behind_it() {
    let dir = std::env::temp_dir().join(format!("kage-alpha-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let part = |alpha: f32| {
        // A red slab over a small cube, both centred on the z axis.
        format!("cube(size = [2, 2, 2], center = true);\ncolor([1, 0, 0, {alpha}]) {{\n\tmultmatrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 3], [0, 0, 0, 1]]) {{\n\t\tcube(size = [10, 10, 1], center = true);\n\t}}\n}}\n")
    };
    let options = kage::scene::model::ModelOptions {
        camera: kage::scene::framing::CameraOverride {
            view: Some(kage::scene::framing::View::TOP),
            ..Default::default()
        },
        ..Default::default()
    };
    let shown = |text: &str, name: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let scene = kage::scene::model::scene_for_model_with(&path, 160, 96, &options).unwrap();
        let frame = kage::render(&scene, &kage::RenderOptions::default()).unwrap();
        let solid = scene.objects.iter().find_map(|o| o.solid()).unwrap().clone();
        (frame.image.get(80, 48), solid, scene.objects.len())
    };
    let (clear, solid, objects) = shown(&part(0.3), "clear.csg");
    let (opaque, opaque_solid, opaque_objects) = shown(&part(1.0), "opaque.csg");
    assert!(opaque.y < 0.1 * opaque.x, "the opaque slab is not red: {opaque:?}");
    // Seen through the slab: the cube's yellow (red and green, no blue), in
    // the slab's shadow (a see-through part casts a whole shadow).
    assert!(
        clear.y > 0.1 * clear.x && clear.x > 2.0 * clear.z,
        "the cube does not show through: {clear:?} (opaque: {opaque:?})"
    );
    // The see-through part is a mesh of its own, not in the solid.
    assert_eq!((objects, opaque_objects), (opaque_objects + 1, opaque_objects));
    assert!(!solid.contains(glam::Vec3::new(4.0, 4.0, 3.0)) && opaque_solid.contains(glam::Vec3::new(4.0, 4.0, 3.0)));
    // Inside a difference: opaque, said.
    let cut = "difference() {\n\tcube(size = [4, 4, 4], center = false);\n\tcolor([0, 0, 1, 0.5]) {\n\t\tsphere(r = 2);\n\t}\n}\n";
    let loaded = kage::csg::openscad::load_csg(
        std::path::Path::new("cut.csg"),
        std::sync::Arc::from(cut),
        &kage::csg::openscad::CsgOptions::default(),
        &kage::limits::Limits::default(),
    )
    .unwrap();
    assert!(
        loaded.see_through.is_empty()
            && loaded.warnings.iter().any(|w| w.contains("cut.csg:3:2") && w.contains("alpha")),
        "{:?}",
        loaded.warnings
    );
}

/// Every node OpenSCAD writes into a `.csg` (2021.01's, and later releases'
/// `roof` and `fill`), alone in a file read with `--skip-unsupported`:
/// it draws something, or a warning names it, or reading fails naming it.
/// A node kind dropped without a word fails here.
#[test]
fn no_node_is_dropped_without_a_message() {
    let samples = [
        ("group", "group() {\n\tcube(size = [1, 1, 1], center = false);\n}\n"),
        ("union", "union() {\n\tcube(size = [1, 1, 1], center = false);\n}\n"),
        ("render", "render(convexity = 2) {\n\tcube(size = [1, 1, 1], center = false);\n}\n"),
        ("difference", "difference() {\n\tcube(size = [2, 2, 2], center = false);\n\tcube(size = [1, 1, 1], center = false);\n}\n"),
        ("intersection", "intersection() {\n\tcube(size = [2, 2, 2], center = false);\n\tsphere($fn = 0, $fa = 12, $fs = 2, r = 1);\n}\n"),
        ("multmatrix", "multmatrix([[1, 0, 0, 5], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) {\n\tcube(size = [1, 1, 1], center = false);\n}\n"),
        ("color", "color([1, 0, 0, 0.5]) {\n\tcube(size = [1, 1, 1], center = false);\n}\n"),
        ("hull", "hull() {\n\tcube(size = [1, 1, 1], center = false);\n\tsphere($fn = 0, $fa = 12, $fs = 2, r = 1);\n}\n"),
        ("minkowski", "minkowski(convexity = 0) {\n\tcube(size = [1, 1, 1], center = false);\n\tsphere($fn = 0, $fa = 12, $fs = 2, r = 1);\n}\n"),
        ("resize", "resize(newsize = [3,0,0], auto = [1,1,1], convexity = 0) {\n\tcube(size = [1, 1, 1], center = false);\n}\n"),
        ("cube", "cube(size = [1, 1, 1], center = false);\n"),
        ("sphere", "sphere($fn = 0, $fa = 12, $fs = 2, r = 1);\n"),
        ("cylinder", "cylinder($fn = 0, $fa = 12, $fs = 2, h = 1, r1 = 1, r2 = 1, center = false);\n"),
        ("polyhedron", "polyhedron(points = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], faces = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]], convexity = 1);\n"),
        ("square", "square(size = [1, 1], center = false);\n"),
        ("circle", "circle($fn = 0, $fa = 12, $fs = 2, r = 1);\n"),
        ("polygon", "polygon(points = [[0, 0], [1, 0], [0, 1]], paths = undef, convexity = 1);\n"),
        ("text", "text(text = \"A\", size = 10, spacing = 1, font = \"\", direction = \"ltr\", language = \"en\", script = \"latin\", halign = \"left\", valign = \"baseline\", $fn = 0, $fa = 12, $fs = 2);\n"),
        ("linear_extrude", "linear_extrude(height = 1, center = false, convexity = 1, scale = [1, 1], $fn = 0, $fa = 12, $fs = 2) {\n\tsquare(size = [1, 1], center = false);\n}\n"),
        ("rotate_extrude", "rotate_extrude(angle = 360, convexity = 2, $fn = 0, $fa = 12, $fs = 2) {\n\tmultmatrix([[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) {\n\t\tsquare(size = [1, 1], center = false);\n\t}\n}\n"),
        ("offset", "offset(r = 1, $fn = 0, $fa = 12, $fs = 2) {\n\tsquare(size = [1, 1], center = false);\n}\n"),
        ("projection", "projection(cut = false, convexity = 0) {\n\tcube(size = [1, 1, 1], center = false);\n}\n"),
        ("import", "import(file = \"part.stl\", layer = \"\", origin = [0, 0], scale = 1, convexity = 1, $fn = 0, $fa = 12, $fs = 2, timestamp = 0);\n"),
        ("import", "import(file = \"plan.svg\", layer = \"\", origin = [0, 0], scale = 1, convexity = 1, $fn = 0, $fa = 12, $fs = 2, timestamp = 0);\n"),
        ("import", "import(file = \"plan.dxf\", layer = \"\", origin = [0, 0], scale = 1, convexity = 1, $fn = 0, $fa = 12, $fs = 2, timestamp = 0);\n"),
        ("surface", "surface(file = \"map.dat\", center = false, invert = false, timestamp = 0);\n"),
        ("roof", "roof(method = \"voronoi\", convexity = 1) {\n\tsquare(size = [1, 1], center = false);\n}\n"),
        ("fill", "fill() {\n\tsquare(size = [1, 1], center = false);\n}\n"),
        // A node of a release yet to come.
        ("measure_future", "measure_future(x = 1);\n"),
    ];
    let options = CsgOptions { geometry: Geometry::Exact, skip_unsupported: true };
    for (name, text) in samples {
        match load_csg(Path::new("t.csg"), Arc::from(text), &options, &Default::default()) {
            Ok(loaded) => {
                let drew = loaded.solid.tree.is_some() || !loaded.see_through.is_empty();
                let said = loaded.warnings.iter().any(|w| w.contains(name));
                assert!(drew || said, "`{name}()` drew nothing and no warning names it: {:?}", loaded.warnings);
            }
            Err(e) => assert!(e.to_string().contains("t.csg:1:1"), "`{name}()`: {e}"),
        }
    }
}

/// Every model of the corpus of public projects (`bench/corpus/openscad`:
/// printer parts, threaded parts, gears, knobs, labels...) reads without an
/// error, nothing skipped, and its solid shows at the centre of its own view.
#[test]
fn every_model_of_the_public_corpus_renders() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/corpus/openscad");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "csg"))
        .collect();
    files.sort();
    assert!(files.len() >= 50, "only {} corpus models", files.len());
    let options = CsgOptions { geometry: Geometry::Exact, skip_unsupported: false };
    let mut failed = Vec::new();
    for path in &files {
        let files = FileSystem { base: dir.clone() };
        let name = Path::new(path.file_name().unwrap_or_default());
        match kage::scene::load::model_with(name, &files, &options, &Default::default()) {
            Err(e) => failed.push(format!("{}: {e}", path.display())),
            Ok(model) => {
                let solid = &model.solids[0].solid;
                let Some(bounds) = solid.bounds() else {
                    failed.push(format!("{}: empty", path.display()));
                    continue;
                };
                let camera = kage::csg::openscad::default_view(bounds);
                let shown = kage::visibility::solids::scan_solid(solid, &camera, 80, 60);
                if shown.iter().all(Option::is_none) {
                    failed.push(format!("{}: nothing shows", path.display()));
                }
            }
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}
