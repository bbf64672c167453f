//! `kage-bench view`: the preview window orbiting a scene beside f3d, the
//! minimal viewer users reach for, on the same machine with no GPU (f3d on
//! Mesa's software OpenGL, offscreen through EGL).
//!
//! kage runs as a user runs it — `kage view FILE --script orbit --timings`
//! under a virtual X server (Xvfb): 120 drags of 3° each, one a frame,
//! each arriving while the frame before it renders (the rate is the time
//! between two frames shown, presentation included),
//! then rest; 16 passes into the refinement an input (a zoom of no steps)
//! gives up the pass rendering, and the refinement starts over and runs to
//! its 64-pass image. f3d 4.0 (`pip install f3d`;
//! the bench looks for it in the Python given by `--python`) loads the same
//! model, turns its camera 3° per frame and renders each to an image. The
//! two alternate, scene by scene, in one run.

use std::path::{Path, PathBuf};
use std::process::Command;

use miette::{miette, IntoDiagnostic, Result};

use crate::Common;

/// Options of `kage-bench view`.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    #[command(flatten)]
    common: Common,
    /// The `kage` binary to run (default: the release build beside this one).
    #[arg(long)]
    kage: Option<PathBuf>,
    /// A Python with the `f3d` package (f3d's rows are left empty without it).
    #[arg(long, default_value = "python3")]
    python: PathBuf,
    /// Frames of the orbit.
    #[arg(long, default_value_t = 120)]
    orbit: u32,
    /// Only scenes whose name contains this (`scad`: only the saved `.scad`).
    #[arg(long)]
    only: Option<String>,
}

/// What a viewer did on one scene.
#[derive(Debug, Default, Clone, Copy)]
struct Run {
    /// Launch to the first image, ms.
    first_ms: f64,
    /// Median ms between two frames shown while orbiting.
    frame_ms: f64,
    /// From the last input to the fully refined image, ms (kage only).
    refined_ms: Option<f64>,
    /// From an input (a file saved) to the next image, ms (kage only).
    new_image_ms: Option<f64>,
    /// From an input to the refinement step it made stale given up, ms
    /// (kage only).
    given_up_ms: Option<f64>,
}

/// The scenes: a name, kage's file, and the file f3d opens (none for
/// kage's own scene files).
fn scenes(c: &Common) -> Vec<(String, PathBuf, Option<PathBuf>)> {
    let repo = crate::repository();
    let assets = c.assets();
    let mut out = vec![
        ("demo".to_string(), PathBuf::new(), None),
        ("showroom.toml".to_string(), repo.join("examples/scenes/showroom.toml"), None),
    ];
    for model in ["meshes/stanford-bunny/stanford-bunny.obj", "gltf/CesiumMilkTruck/CesiumMilkTruck.glb"] {
        let path = assets.join(model);
        if path.exists() {
            let name = path.file_name().unwrap_or_default().to_string_lossy().into_owned();
            out.push((name, path.clone(), Some(path)));
        } else {
            eprintln!("skipped {} (not found)", path.display());
        }
    }
    match crate::share::median_csg(&assets.join("csg"), (c.width, c.height), 3) {
        Ok(Some(csg)) => {
            let name = format!("{} (median .csg)", csg.file_name().unwrap_or_default().to_string_lossy());
            let stl = csg.with_extension("stl");
            out.push((name, csg, stl.exists().then_some(stl)));
        }
        Ok(None) => eprintln!("skipped the median .csg (no corpus)"),
        Err(e) => eprintln!("skipped the median .csg: {e}"),
    }
    out
}

/// Runs kage's window on `file` (the demo when empty) through the orbit.
fn kage_run(kage: &Path, file: &Path, c: &Common, orbit: u32) -> Result<Run> {
    let mut text = String::from("wait\n");
    text += &"drag left 7.5 0\n".repeat(orbit as usize);
    text += "wait 16\nwheel 0\nwait\nquit\n";
    kage_scripted(kage, file, c, &text)
}

/// Runs kage's window on `file` (the demo when empty) with the script
/// `text` (paths in it relative to `file`'s folder): its timings.
fn kage_scripted(kage: &Path, file: &Path, c: &Common, text: &str) -> Result<Run> {
    let dir = match file.parent() {
        Some(p) if !p.as_os_str().is_empty() && !file.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::env::temp_dir(),
    };
    let script = dir.join(format!("kage-bench-view-{}.script", std::process::id()));
    std::fs::write(&script, text).into_diagnostic()?;
    let mut cmd = Command::new("xvfb-run");
    cmd.args(["-a", "-s", "-screen 0 1920x1080x24"]).arg(kage).arg("view");
    if !file.as_os_str().is_empty() {
        cmd.arg(file);
    }
    cmd.args(["--width", &c.width.to_string(), "--height", &c.height.to_string(), "--timings", "--script"]);
    let out = cmd.arg(&script).output().into_diagnostic()?;
    std::fs::remove_file(&script).ok();
    let said = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(miette!("kage view {}: {}{}", file.display(), said, String::from_utf8_lossy(&out.stderr)));
    }
    let line = said.lines().find(|l| l.starts_with("first image")).ok_or_else(|| miette!("no timings: {said}"))?;
    Ok(Run {
        first_ms: number_after(line, "first image", "").unwrap_or(f64::NAN),
        frame_ms: number_after(line, "quick frames", "shown every").unwrap_or(f64::NAN),
        refined_ms: number_after(line, "refined", "median"),
        new_image_ms: number_after(line, "new image", "median"),
        given_up_ms: number_after(line, "given up", "median"),
    })
}

/// The number after `key` (and then after `then`, when not empty) in `line`.
fn number_after(line: &str, key: &str, then: &str) -> Option<f64> {
    let mut rest = &line[line.find(key)? + key.len()..];
    if !then.is_empty() {
        rest = &rest[rest.find(then)? + then.len()..];
    }
    rest.trim_start().split(|c: char| !(c.is_ascii_digit() || c == '.')).next()?.parse().ok()
}

/// The median corpus model's `.scad` saved again while `kage view` shows it:
/// milliseconds from the change reaching the window to the new image
/// (`openscad -o` to `.csg`, the load, the first frame), beside OpenSCAD's
/// own preview of the model (the peers' TIMINGS.md).
fn saved_scad(kage: &Path, c: &Common) -> Result<()> {
    let Ok(Some(csg)) = crate::share::median_csg(&c.assets().join("csg"), (c.width, c.height), 3) else {
        return Ok(());
    };
    let scad = csg.with_extension("scad");
    if !scad.exists() || Command::new("openscad").arg("--version").output().is_err() {
        eprintln!("skipped the .scad row (no {} or no openscad)", scad.display());
        return Ok(());
    }
    let dir = std::env::temp_dir().join(format!("kage-bench-scad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).into_diagnostic()?;
    let model = dir.join("model.scad");
    std::fs::copy(&scad, &model).into_diagnostic()?;
    std::fs::copy(&scad, dir.join("saved.scad")).into_diagnostic()?;
    let run = kage_scripted(kage, &model, c, "wait\ncopy saved.scad model.scad\nsleep 2\nwait\nquit\n")?;
    let name = scad.file_stem().unwrap_or_default().to_string_lossy().into_owned();
    let theirs = crate::csg::openscad_preview_seconds(&c.peers()).get(&name).copied();
    println!("\n| model | kage: .scad saved → new image, ms | OpenSCAD 2021.01 preview, ms |");
    println!("|---|---:|---:|");
    println!(
        "| {name}.scad | {} | {} |",
        run.new_image_ms.map_or("–".to_string(), |v| format!("{v:.0}")),
        theirs.map_or("–".to_string(), |s| format!("{:.0}", s * 1e3))
    );
    println!(
        "\nkage: from the file watcher's event to the next image shown — `openscad -o model.csg model.scad`, the \
         load, the first (quick) frame. OpenSCAD: `openscad --preview` of the same model to a 640×480 PNG, start-up \
         included (../shared/peers/openscad/TIMINGS.md, the same kind of machine)."
    );
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}

/// f3d's script: launch to first image, then the orbit's median frame.
const F3D_SCRIPT: &str = r#"
import sys, time
t0 = time.perf_counter()
import f3d
engine = f3d.Engine.create_egl()
engine.window.size = (int(sys.argv[2]), int(sys.argv[3]))
engine.scene.add(sys.argv[1])
engine.window.render_to_image()
first = time.perf_counter() - t0
frames = []
for i in range(int(sys.argv[4])):
    engine.window.camera.azimuth(3.0)
    t = time.perf_counter()
    engine.window.render_to_image()
    frames.append(time.perf_counter() - t)
frames.sort()
print(f"{first * 1e3:.1f} {frames[len(frames) // 2] * 1e3:.2f}")
"#;

/// Runs f3d on `file` through the orbit; `None` when f3d is not there.
fn f3d_run(python: &Path, file: &Path, c: &Common, orbit: u32) -> Option<Run> {
    let out = Command::new(python)
        .args(["-c", F3D_SCRIPT])
        .arg(file)
        .args([c.width.to_string(), c.height.to_string(), orbit.to_string()])
        .output()
        .ok()?;
    if !out.status.success() {
        eprintln!("f3d on {}: {}", file.display(), String::from_utf8_lossy(&out.stderr).lines().last().unwrap_or(""));
        return None;
    }
    let said = String::from_utf8_lossy(&out.stdout);
    let mut v = said.split_whitespace().filter_map(|n| n.parse::<f64>().ok());
    Some(Run { first_ms: v.next()?, frame_ms: v.next()?, refined_ms: None, new_image_ms: None, given_up_ms: None })
}

/// Prints the table.
///
/// # Errors
///
/// When kage's window cannot run (no `xvfb-run`, no release binary).
pub fn run(args: &ViewArgs) -> Result<()> {
    let c = &args.common;
    let kage = args.kage.clone().unwrap_or_else(|| {
        std::env::current_exe().ok().and_then(|p| p.parent().map(|d| d.join("kage"))).unwrap_or_else(|| "kage".into())
    });
    println!(
        "| scene | kage first image ms | kage ms per orbit frame | kage fps | kage 64 passes done, ms after the last \
         input | kage pass given up, ms after an input | f3d first image ms | f3d ms per frame | f3d fps | kage fps \
         / f3d fps |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (name, file, f3d_file) in scenes(c) {
        if args.only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        let ours = kage_run(&kage, &file, c, args.orbit)?;
        let theirs = f3d_file.as_deref().and_then(|f| f3d_run(&args.python, f, c, args.orbit));
        let cell = |v: Option<f64>, digits: usize| v.map_or("–".to_string(), |v| format!("{v:.digits$}"));
        println!(
            "| {name} | {:.0} | {:.1} | {:.1} | {} | {} | {} | {} | {} | {} |",
            ours.first_ms,
            ours.frame_ms,
            1e3 / ours.frame_ms,
            cell(ours.refined_ms, 0),
            cell(ours.given_up_ms, 1),
            cell(theirs.map(|t| t.first_ms), 0),
            cell(theirs.map(|t| t.frame_ms), 1),
            cell(theirs.map(|t| 1e3 / t.frame_ms), 1),
            cell(theirs.map(|t| t.frame_ms / ours.frame_ms), 1),
        );
    }
    if args.only.as_ref().is_none_or(|o| o.contains("scad")) {
        saved_scad(&kage, c)?;
    }
    println!(
        "\n{0}×{1}, 2 threads. kage: `kage view FILE --script` under Xvfb, {2} drags of 3° (one a frame, arriving while the \
         frame before renders; ms per frame: median time between two frames shown, presenting included; a quick \
         frame — no edge pass, plain maps for costlier shadows), then left to rest; after 16 jittered passes an \
         input (a zoom of no steps) gives up the pass rendering, and the refinement runs again until 64 passes are \
         averaged; first image from the window's start (scene loaded, window open, first frame shown). f3d 4.0: \
         `f3d.Engine.create_egl()` offscreen on Mesa llvmpipe, the model added, `camera.azimuth(3)` and \
         `render_to_image()` per frame; first image from the interpreter's start. Medians over the orbit.",
        c.width, c.height, args.orbit
    );
    Ok(())
}
