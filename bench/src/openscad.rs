//! The OpenSCAD corpus (`bench/corpus/openscad`: parts of public projects,
//! SOURCES.md there): for each model, whether kage draws it, how far its
//! image agrees with OpenSCAD's exact mesh of it, and how soon it shows,
//! beside OpenSCAD 2021.01's own preview and beside Manifold's booleans of
//! the same tree.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::time::Instant;

use kage::csg::openscad::{surface_mesh, CsgOptions, Geometry};
use kage::scene::load::FileSystem;
use miette::{miette, Result};

use crate::median;

/// Arguments of `kage-bench openscad`.
#[derive(clap::Args, Debug, Clone)]
pub struct OpenscadArgs {
    /// Only these models (file stems); default all.
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Timed runs per model and engine (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// The `kage` binary (default: the one beside kage-bench).
    #[arg(long)]
    pub kage: Option<PathBuf>,
    /// Seconds Manifold may take on one model before it is stopped.
    #[arg(long, default_value_t = 60)]
    pub manifold_limit: u64,
    /// Only time Manifold on this `.csg` and print the seconds (what the
    /// table runs in a process of its own, to stop it at the limit).
    #[arg(long, hide = true)]
    pub manifold_only: Option<PathBuf>,
    /// With `--manifold-only`: write Manifold's mesh here as binary STL.
    #[arg(long, hide = true)]
    pub manifold_stl: Option<PathBuf>,
}

/// The corpus folder.
fn corpus() -> PathBuf {
    crate::repository().join("bench/corpus/openscad")
}

/// The corpus's `.csg` models, by name; only those `only` names (file stems)
/// when it names any.
///
/// # Errors
///
/// When the corpus folder cannot be read.
pub(crate) fn corpus_models(only: &[String]) -> Result<Vec<PathBuf>> {
    let dir = corpus();
    let mut models: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map_err(|e| miette!("{}: {e}", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "csg"))
        .filter(|p| only.is_empty() || only.iter().any(|o| p.file_stem().is_some_and(|s| s == o.as_str())))
        .collect();
    models.sort();
    Ok(models)
}

/// The nodes whose presence the table names (a model "uses" them).
const CONSTRUCTS: [(&str, &str); 14] = [
    ("linear_extrude(", "linear"),
    ("rotate_extrude(", "rotate"),
    ("text(", "text"),
    ("offset(", "offset"),
    ("minkowski(", "minkowski"),
    ("hull(", "hull"),
    ("polyhedron(", "polyhedron"),
    ("polygon(", "polygon"),
    ("projection(", "projection"),
    ("resize(", "resize"),
    ("import(", "import"),
    ("surface(", "surface"),
    ("intersection(", "intersection"),
    ("difference(", "difference"),
];

/// Runs the table.
///
/// # Errors
///
/// When the `kage` binary is not built or the corpus cannot be read.
pub fn run(args: &OpenscadArgs) -> Result<()> {
    if let Some(path) = &args.manifold_only {
        let seconds = manifold_seconds(path, args.runs, args.manifold_stl.as_deref())
            .ok_or_else(|| miette!("{}: does not read", path.display()))?;
        println!("{seconds}");
        return Ok(());
    }
    let dir = corpus();
    let exe = match &args.kage {
        Some(exe) => exe.clone(),
        None => std::env::current_exe().map_err(|e| miette!("{e}"))?.with_file_name("kage"),
    };
    if !exe.exists() {
        return Err(miette!("{} is not built: `cargo build --release` builds it beside kage-bench", exe.display()));
    }
    let models = corpus_models(&args.only)?;
    let display = Xvfb::start();
    println!("| model | uses | kage | agrees with OpenSCAD's mesh | kage first image s | peak MB | OpenSCAD preview s | Manifold booleans s | Manifold way to image s | Manifold peak MB |");
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|");
    let (mut drawn, mut agree_995, mut with_mesh, mut faster) = (0, 0, 0, 0);
    let (mut faster_than_manifold, mut faster_than_manifold_way, mut manifold_20ms) = (0, 0, 0);
    for path in &models {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| miette!("{}: {e}", path.display()))?;
        let uses: Vec<&str> = CONSTRUCTS.iter().filter(|(n, _)| text.contains(n)).map(|(_, short)| *short).collect();
        let (status, kage_s, peak_mb) = kage_run(&exe, path, args.runs);
        drawn += usize::from(status != "error");
        let stl = dir.join("stl").join(format!("{name}.stl"));
        let agreement = stl.exists().then(|| coverage(path, &stl)).transpose()?;
        if let Some(a) = agreement {
            with_mesh += 1;
            agree_995 += usize::from(a >= 0.995);
        }
        let theirs = display.as_ref().and_then(|d| openscad_preview(d, path, args.runs));
        faster += usize::from(theirs.is_some_and(|t| kage_s.is_some_and(|k| k < t)));
        let meshed = std::env::temp_dir().join(format!("kage-bench-manifold-{}.stl", std::process::id()));
        let manifold = manifold_limited(path, &meshed, args);
        // The Manifold way to a first image: its booleans, then kage's image
        // of the mesh they make (the same size, lit and shadowed alike).
        let manifold_way = match manifold {
            Some(Timed::Within(s, _)) => kage_run(&exe, &meshed, args.runs).1.map(|image| s + image),
            _ => None,
        };
        std::fs::remove_file(&meshed).ok();
        if let (Some(m), Some(k)) = (manifold, kage_s) {
            let m = match m {
                Timed::Within(s, _) => s,
                Timed::Over(limit) => limit as f64,
            };
            if m >= 0.02 {
                manifold_20ms += 1;
                faster_than_manifold += usize::from(k < m);
                faster_than_manifold_way += usize::from(manifold_way.is_none_or(|w| k < w));
            }
        }
        let show = |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |v| format!("{v:.digits$}"));
        println!(
            "| {name} | {} | {status} | {} | {} | {} | {} | {} | {} | {} |",
            uses.join(" "),
            agreement.map_or("no mesh".to_string(), |a| format!("{:.2}%", a * 100.0)),
            show(kage_s, 2),
            show(peak_mb, 0),
            show(theirs, 2),
            manifold.map_or("-".to_string(), |m| match m {
                Timed::Within(s, _) => format!("{s:.3}"),
                Timed::Over(limit) => format!("> {limit}"),
            }),
            show(manifold_way, 2),
            manifold.map_or("-".to_string(), |m| match m {
                Timed::Within(_, mb) => format!("{mb:.0}"),
                Timed::Over(_) => "-".to_string(),
            }),
        );
    }
    println!(
        "\n{} models: {drawn} drawn; {agree_995} of the {with_mesh} with an exact mesh agree on ≥ 99.5% of pixels; \
         kage's first image sooner than OpenSCAD's preview on {faster}; of the {manifold_20ms} where Manifold's \
         booleans take ≥ 20 ms, sooner than the Manifold way to an image on {faster_than_manifold_way} and than \
         its booleans alone on {faster_than_manifold}.",
        models.len()
    );
    println!(
        "\nkage: `kage render NAME.csg --width 640 --height 480` (exact quadrics, lit, shadowed, edge-antialiased), \
         wall clock and peak resident memory of the whole process, median of {}. Agreement: the share of 640×480 \
         pixels where kage's scanline walk of the tree and kage's rasterizer of OpenSCAD's exact mesh (its CGAL \
         render to STL) both show the model or both miss it, from OpenSCAD's default view of the mesh. OpenSCAD \
         2021.01: `openscad --preview --imgsize=640,480 -o NAME.png NAME.csg` on one Xvfb server (Mesa llvmpipe), \
         whole process. Manifold: the same tree kage draws (its convex primitives faceted as OpenSCAD facets \
         them, each the hull of its corners, and its closed meshes), combined by Manifold's booleans (the \
         manifold-rust port of Manifold 3.5, one thread, in a process of its own stopped at {} s; its peak \
         memory the whole process's, reading the tree included). The Manifold way to an image: those booleans, \
         then `kage render` of the mesh they make at the same size (a median of as many runs), added.",
        args.runs, args.manifold_limit
    );
    Ok(())
}

/// `kage render` of `path` `runs` times: "ok", "warned" or "error", the
/// median wall seconds and the largest peak resident mebibytes.
fn kage_run(exe: &Path, path: &Path, runs: usize) -> (&'static str, Option<f64>, Option<f64>) {
    let out = std::env::temp_dir().join(format!("kage-bench-openscad-{}.png", std::process::id()));
    let (mut times, mut peak, mut status) = (Vec::new(), 0.0f64, "ok");
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let run = Command::new("/usr/bin/time")
            .args(["-f", "%M"])
            .arg(exe)
            .args(["render", "--width", "640", "--height", "480", "-o"])
            .arg(&out)
            .arg(path)
            .stdout(Stdio::null())
            .output();
        let Ok(run) = run else { return ("error", None, None) };
        if !run.status.success() {
            return ("error", None, None);
        }
        times.push(t.elapsed().as_secs_f64());
        let said = String::from_utf8_lossy(&run.stderr);
        if said.contains("warning") {
            status = "warned";
        }
        let kb: f64 = said.lines().last().and_then(|l| l.trim().parse().ok()).unwrap_or(0.0);
        peak = peak.max(kb / 1024.0);
    }
    std::fs::remove_file(&out).ok();
    (status, Some(median(&mut times)), Some(peak))
}

/// The share of pixels where the solid of `csg` and the mesh `stl` both
/// show or both miss the model, seen from OpenSCAD's default view of the mesh.
fn coverage(csg: &Path, stl: &Path) -> Result<f64> {
    let (w, h) = (640, 480);
    let files = FileSystem { base: csg.parent().unwrap_or(Path::new(".")).to_path_buf() };
    let options = CsgOptions { geometry: Geometry::Exact, skip_unsupported: true };
    let name = Path::new(csg.file_name().unwrap_or_default());
    let loaded =
        kage::scene::load::model_with(name, &files, &options, &Default::default()).map_err(|e| miette!("{e}"))?;
    let Some(part) = loaded.solids.first() else { return Ok(0.0) };
    let as_written =
        kage::scene::model::ModelOptions { up: Some(kage::scene::Up::Y), ground: false, ..Default::default() };
    let mut scene = kage::scene::model::scene_for_model_with(stl, w, h, &as_written).map_err(|e| miette!("{e}"))?;
    scene.camera = kage::csg::openscad::default_view(scene.bounds().ok_or_else(|| miette!("empty mesh"))?);
    let scanned = kage::visibility::solids::scan_solid(&part.solid, &scene.camera, w, h);
    let mut vb = kage::visibility::VisibilityBuffer::new(w, h);
    kage::visibility::rasterize(&scene, &mut vb);
    let agree = scanned.iter().zip(vb.items()).filter(|(s, item)| s.is_some() != item.is_none()).count();
    Ok(agree as f64 / scanned.len() as f64)
}

/// A time (with the process's peak resident mebibytes), or the limit it
/// passed.
#[derive(Debug, Clone, Copy)]
enum Timed {
    Within(f64, f64),
    Over(u64),
}

/// [`manifold_seconds`] in a process of its own, stopped at the limit.
fn manifold_limited(path: &Path, stl: &Path, args: &OpenscadArgs) -> Option<Timed> {
    let exe = std::env::current_exe().ok()?;
    let mut child = Command::new("/usr/bin/time")
        .args(["-f", "%M"])
        .arg(exe)
        .args(["openscad", "--runs", &args.runs.to_string(), "--manifold-stl"])
        .arg(stl)
        .arg("--manifold-only")
        .arg(path)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .ok()?;
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().ok()? {
            if !status.success() {
                return None;
            }
            let (mut out, mut err) = (String::new(), String::new());
            std::io::Read::read_to_string(&mut child.stdout.take()?, &mut out).ok()?;
            std::io::Read::read_to_string(&mut child.stderr.take()?, &mut err).ok()?;
            let kb: f64 = err.lines().last().and_then(|l| l.trim().parse().ok()).unwrap_or(0.0);
            return out.trim().parse().ok().map(|s| Timed::Within(s, kb / 1024.0));
        }
        if start.elapsed().as_secs() >= args.manifold_limit {
            child.kill().ok();
            child.wait().ok();
            return Some(Timed::Over(args.manifold_limit));
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// Seconds Manifold takes to combine the tree's faceted primitives (median
/// of `runs`), or `None` when the file does not read.
fn manifold_seconds(path: &Path, runs: usize, stl: Option<&Path>) -> Option<f64> {
    let files = FileSystem { base: path.parent()?.to_path_buf() };
    let options = CsgOptions { geometry: Geometry::Faceted, skip_unsupported: true };
    let loaded =
        kage::scene::load::model_with(Path::new(path.file_name()?), &files, &options, &Default::default()).ok()?;
    let solid: Arc<kage::csg::CsgSolid> = Arc::clone(&loaded.solids.first()?.solid);
    let mut times: Vec<f64> = (0..runs.max(1))
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(surface_mesh(&solid));
            t.elapsed().as_secs_f64()
        })
        .collect();
    if let Some(stl) = stl {
        let (positions, triangles) = surface_mesh(&solid);
        std::fs::write(stl, binary_stl(&positions, &triangles)).ok()?;
    }
    Some(median(&mut times))
}

/// A mesh as binary STL (normals left zero: readers compute them).
fn binary_stl(positions: &[glam::Vec3], triangles: &[[u32; 3]]) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend((triangles.len() as u32).to_le_bytes());
    for t in triangles {
        out.extend([0u8; 12]);
        for &i in t {
            positions[i as usize].to_array().iter().for_each(|c| out.extend(c.to_le_bytes()));
        }
        out.extend([0u8; 2]);
    }
    out
}

/// A virtual X server for OpenSCAD's preview, stopped when dropped.
struct Xvfb {
    child: std::process::Child,
    display: String,
}

impl Xvfb {
    /// Starts one on a free display, or `None` (with a note) without Xvfb.
    fn start() -> Option<Xvfb> {
        let n = (91..140).find(|n| !Path::new(&format!("/tmp/.X{n}-lock")).exists())?;
        let display = format!(":{n}");
        let child = Command::new("Xvfb")
            .args([display.as_str(), "-screen", "0", "1280x1024x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn();
        let Ok(child) = child else {
            eprintln!("Xvfb is not installed: the OpenSCAD column is left empty");
            return None;
        };
        for _ in 0..50 {
            if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
        Some(Xvfb { child, display })
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        self.child.kill().ok();
        self.child.wait().ok();
    }
}

/// Median wall seconds of OpenSCAD's preview of `path` to a 640×480 PNG, or
/// `None` when OpenSCAD is missing or fails.
fn openscad_preview(x: &Xvfb, path: &Path, runs: usize) -> Option<f64> {
    let out = std::env::temp_dir().join(format!("kage-bench-openscad-preview-{}.png", std::process::id()));
    let mut times = Vec::new();
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let ok = Command::new("openscad")
            .env("DISPLAY", &x.display)
            .args(["--preview", "--imgsize=640,480", "--csglimit=5000000", "-o"])
            .arg(&out)
            .arg(path)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .ok()?
            .success();
        if !ok {
            return None;
        }
        times.push(t.elapsed().as_secs_f64());
    }
    std::fs::remove_file(&out).ok();
    Some(median(&mut times))
}
