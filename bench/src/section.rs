//! `kage-bench section`: kage's section plane through each part of the
//! OpenSCAD corpus beside OpenSCAD's own `intersection()` of the part with a
//! large cube, rendered by OpenSCAD 2021.01 to an exact mesh (CGAL).
//!
//! Each part is cut at the middle of its height (the file's z, from the
//! lowest to the highest point of the solid that vertical rays through it
//! find: a tree's box also holds what it subtracts), the lower half kept, its spheres and cylinders faceted as OpenSCAD facets them: kage cuts its solid with the plane ([`kage::Scene::section`]);
//! OpenSCAD intersects the file's tree with a box reaching from below the
//! part to the plane. Both are drawn from one camera (framing the whole
//! part), and each pixel agrees when both show the part at the same depth
//! (within a thousandth) or both miss it.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use glam::Vec3;
use kage::csg::openscad::{CsgOptions, Geometry};
use kage::scene::model::{scene_for_model_with, ModelOptions};
use kage::scene::section::SectionPlane;
use kage::scene::{Scene, Up};
use kage::visibility::VisibilityBuffer;
use miette::{miette, Result};

/// Options of `kage-bench section`.
#[derive(clap::Args, Debug)]
pub struct SectionArgs {
    /// Only these models (file stems); default all.
    #[arg(long, value_delimiter = ',')]
    only: Vec<String>,
    /// Seconds OpenSCAD may take to mesh one intersection before it is stopped.
    #[arg(long, default_value_t = 120)]
    limit: u64,
    /// Image width.
    #[arg(long, default_value_t = 640)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 480)]
    height: u32,
}

/// The share of pixels that must agree.
const TARGET: f64 = 0.995;

/// Runs the table.
///
/// # Errors
///
/// When the corpus cannot be read or `openscad` is not installed.
pub fn run(args: &SectionArgs) -> Result<()> {
    if Command::new("openscad").arg("--version").output().is_err() {
        return Err(miette!("openscad is not installed (Debian: apt-get install openscad)"));
    }
    let models = crate::openscad::corpus_models(&args.only)?;
    println!("| model | cut at z | pixels of the part | agree | OpenSCAD intersection s | kage section ms |");
    println!("|---|---:|---:|---:|---:|---:|");
    let (mut measured, mut met, mut skipped) = (0, 0, Vec::new());
    // Parts whose imported meshes are not closed, compared without them.
    let (mut open_measured, mut open_met) = (0, 0);
    for path in &models {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default().to_string();
        match compare(path, args)? {
            Outcome::Compared { cut, part, share, openscad_s, kage_ms, open } => {
                measured += 1;
                met += usize::from(share >= TARGET);
                println!("| {name} | {cut:.2} | {part} | {:.2}% | {openscad_s:.1} | {kage_ms:.1} |", 100.0 * share);
                if !open.is_empty() {
                    if let Some(share) = without_open(path, &name, &open, args)? {
                        open_measured += 1;
                        open_met += usize::from(share >= TARGET);
                    }
                }
            }
            Outcome::Skipped(why) => {
                println!("| {name} | - | - | - | {why} | - |");
                skipped.push(name);
            }
        }
    }
    println!(
        "\n{met} of {measured} sections agree with OpenSCAD's intersection on at least {:.1}% of pixels ({}x{}); {} not measured: {}.",
        100.0 * TARGET,
        args.width,
        args.height,
        skipped.len(),
        if skipped.is_empty() { "none".to_string() } else { skipped.join(", ") }
    );
    if open_measured > 0 {
        println!(
            "Parts importing meshes that are not closed, compared again with those imports left out of both: {open_met} of {open_measured} agree on at least {:.1}%.",
            100.0 * TARGET
        );
    }
    Ok(())
}

/// One model's result.
enum Outcome {
    Compared {
        cut: f32,
        part: usize,
        share: f64,
        openscad_s: f64,
        kage_ms: f64,
        /// The imported meshes kage found not closed (as the file names them).
        open: Vec<String>,
    },
    Skipped(String),
}

/// Cuts the part in `path` both ways and compares the images.
fn compare(path: &Path, args: &SectionArgs) -> Result<Outcome> {
    let (w, h) = (args.width, args.height);
    // As written: OpenSCAD's z up, no ground; spheres and cylinders as
    // OpenSCAD's own facets ($fn, $fa, $fs), like for like with its mesh.
    let csg = CsgOptions { geometry: Geometry::Faceted, ..CsgOptions::default() };
    let as_written = ModelOptions { up: Some(Up::Y), ground: false, csg, ..ModelOptions::default() };
    let whole = match scene_for_model_with(path, w, h, &as_written) {
        Ok(s) => s,
        Err(e) => return Ok(Outcome::Skipped(format!("kage: {e}"))),
    };
    let Some((lo, hi)) = whole.bounds() else { return Ok(Outcome::Skipped("empty".into())) };
    let Some((bottom, top)) = height(&whole, (lo, hi)) else { return Ok(Outcome::Skipped("empty".into())) };
    let cut = 0.5 * (bottom + top);
    let plane = SectionPlane::through(Vec3::new(0.0, 0.0, cut), Vec3::Z).expect("a plane");
    let start = Instant::now();
    let options = ModelOptions { section: Some(plane), ..as_written };
    let sectioned = scene_for_model_with(path, w, h, &options).map_err(|e| miette!("{e}"))?;
    let kage_ms = start.elapsed().as_secs_f64() * 1e3;
    // OpenSCAD: the tree intersected with a box from below the part to the
    // plane, written beside the file (its imports are relative to it).
    let margin = (hi - lo).max_element() + 1.0;
    let (box_lo, size) = (lo - margin, Vec3::new(hi.x - lo.x, hi.y - lo.y, 0.0) + 2.0 * margin);
    let size = Vec3::new(size.x, size.y, cut - box_lo.z);
    let text = std::fs::read_to_string(path).map_err(|e| miette!("{}: {e}", path.display()))?;
    let cube = format!(
        "multmatrix([[1, 0, 0, {}], [0, 1, 0, {}], [0, 0, 1, {}], [0, 0, 0, 1]]) {{ cube(size = [{}, {}, {}], center = false); }}",
        box_lo.x, box_lo.y, box_lo.z, size.x, size.y, size.z
    );
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("part");
    let wrapper = path.with_file_name(format!(".section-{stem}-{}.csg", std::process::id()));
    let stl = std::env::temp_dir().join(format!("kage-section-{stem}-{}.stl", std::process::id()));
    std::fs::write(&wrapper, format!("intersection() {{\n group() {{\n{text}\n }}\n {cube}\n}}\n"))
        .map_err(|e| miette!("{}: {e}", wrapper.display()))?;
    let start = Instant::now();
    let meshed = openscad_mesh(&wrapper, &stl, Duration::from_secs(args.limit));
    let openscad_s = start.elapsed().as_secs_f64();
    std::fs::remove_file(&wrapper).ok();
    if let Err(why) = meshed {
        std::fs::remove_file(&stl).ok();
        return Ok(Outcome::Skipped(why));
    }
    let intersected = scene_for_model_with(&stl, w, h, &as_written);
    std::fs::remove_file(&stl).ok();
    let mut intersected = match intersected {
        Ok(s) => s,
        // An empty mesh: nothing below the plane.
        Err(e) => return Ok(Outcome::Skipped(format!("OpenSCAD's mesh: {e}"))),
    };
    intersected.camera = sectioned.camera;
    let (part, agree) = agreement(&sectioned, &intersected);
    let open =
        whole.warnings.iter().filter_map(|w| w.split_once(" is not closed")?.0.rsplit(": ").next()).map(String::from);
    let open = open.collect();
    Ok(Outcome::Compared { cut, part, share: agree as f64 / f64::from(w * h), openscad_s, kage_ms, open })
}

/// A part that imports meshes that are not closed, compared again with those
/// imports left out of both sides: OpenSCAD's render (CGAL) drops such a
/// mesh, kage draws it (inside by parity), so as written the two differ by
/// the mesh, not by the cut. Prints a second row; returns its share of
/// agreeing pixels, if compared.
fn without_open(path: &Path, name: &str, open: &[String], args: &SectionArgs) -> Result<Option<f64>> {
    let mut text = std::fs::read_to_string(path).map_err(|e| miette!("{}: {e}", path.display()))?;
    for file in open {
        let call = format!("import(file = \"{file}\"");
        while let Some(at) = text.find(&call) {
            let end = text[at..].find(");").map_or(text.len(), |e| at + e + 2);
            text.replace_range(at..end, "group();");
        }
    }
    let copy = path.with_file_name(format!(".open-left-out-{name}-{}.csg", std::process::id()));
    std::fs::write(&copy, text).map_err(|e| miette!("{}: {e}", copy.display()))?;
    let outcome = compare(&copy, args);
    std::fs::remove_file(&copy).ok();
    let row = format!("{name}, without {}", open.join(", "));
    match outcome? {
        Outcome::Compared { cut, part, share, openscad_s, kage_ms, .. } => {
            println!("| {row} | {cut:.2} | {part} | {:.2}% | {openscad_s:.1} | {kage_ms:.1} |", 100.0 * share);
            Ok(Some(share))
        }
        Outcome::Skipped(why) => {
            println!("| {row} | - | - | - | {why} | - |");
            Ok(None)
        }
    }
}

/// The lowest and highest z of the scene's solids and meshes that vertical
/// rays on a 97 × 97 grid over the box `lo..hi` find.
fn height(scene: &Scene, (lo, hi): (Vec3, Vec3)) -> Option<(f32, f32)> {
    const GRID: usize = 97;
    let mut range: Option<(f32, f32)> = None;
    for object in &scene.objects {
        let to_object = object.transform.inverse();
        let solid = match &object.body {
            kage::scene::Body::Solid { solid, .. } => kage::csg::CsgCaster::new(solid),
            kage::scene::Body::Mesh(_) => {
                // A mesh's own box is its height.
                if let Some((a, b)) = object.world_bounds() {
                    range = Some(range.map_or((a.z, b.z), |(l, h)| (l.min(a.z), h.max(b.z))));
                }
                continue;
            }
        };
        for i in 0..GRID * GRID {
            let (u, v) = ((i % GRID) as f32 + 0.5, (i / GRID) as f32 + 0.5);
            let (x, y) = (lo.x + (hi.x - lo.x) * u / GRID as f32, lo.y + (hi.y - lo.y) * v / GRID as f32);
            let origin = Vec3::new(x, y, lo.z - 1.0);
            let ray = kage::camera::Ray {
                origin: to_object.transform_point3(origin),
                dir: to_object.transform_vector3(Vec3::Z),
            };
            for span in solid.spans(&ray) {
                let (a, b) = (origin.z + span.enter.t, origin.z + span.exit.t);
                range = Some(range.map_or((a, b), |(l, h)| (l.min(a), h.max(b))));
            }
        }
    }
    range
}

/// OpenSCAD's mesh of `csg` written to `stl`, or why not (stopped after
/// `limit`).
fn openscad_mesh(csg: &Path, stl: &Path, limit: Duration) -> std::result::Result<(), String> {
    let mut child = Command::new("openscad")
        .args(["--export-format", "binstl", "-o"])
        .arg(stl)
        .arg(csg)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .map_err(|e| format!("openscad: {e}"))?;
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) if status.success() => return Ok(()),
            Ok(Some(status)) => return Err(format!("openscad failed ({status})")),
            Ok(None) if start.elapsed() > limit => {
                child.kill().ok();
                child.wait().ok();
                return Err(format!("> {} s", limit.as_secs()));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(50)),
            Err(e) => return Err(format!("openscad: {e}")),
        }
    }
}

/// The pixels where either scene shows its part, and the pixels where both
/// agree: both miss it, or both show it at the same depth.
fn agreement(a: &Scene, b: &Scene) -> (usize, usize) {
    let drawn = |s: &Scene| {
        let mut vb = VisibilityBuffer::new(s.width, s.height);
        kage::visibility::rasterize(s, &mut vb);
        vb
    };
    let (va, vb) = (drawn(a), drawn(b));
    let (ia, ib, da, db) = (va.items(), vb.items(), va.depths(), vb.depths());
    let mut part = 0;
    let agree = (0..ia.len())
        .filter(|&i| {
            let (pa, pb) = (!ia[i].is_none(), !ib[i].is_none());
            part += usize::from(pa || pb);
            pa == pb && (!pa || (da[i] - db[i]).abs() <= 1e-3 * da[i].abs().max(db[i].abs()))
        })
        .count();
    (part, agree)
}
