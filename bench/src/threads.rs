//! Where a frame leaves workers idle: each stage's wall time and the share
//! of it during which a worker had no work ([`kage::idle`]), on the scenes a
//! user meets first, and Amdahl's frame at 16 threads from it.
//!
//! The whole render call is measured too (an [`IdleClock`] around it), so
//! work outside the stages (scene checks, the translucent fragments' list,
//! buffers made ready) counts: the "outside stages" column is the call's
//! wall time less its stages', the "frame serial" column the call's.

use kage::idle::{IdleClock, IdleTime};
use kage::Scene;
use miette::{miette, Result};

use crate::{median, repository, Common};

/// `kage-bench threads`.
#[derive(clap::Args, Debug)]
pub struct ThreadsArgs {
    #[command(flatten)]
    common: Common,
}

/// The stages a row reports, in frame order, by the name of their column.
const STAGES: [&str; 5] = ["visibility", "shadows", "shading", "traced", "edges"];

fn stages(s: &kage::FrameStats) -> [IdleTime; 5] {
    let i = &s.idle;
    [i.visibility, i.shadows, i.shading, i.traced, i.edges]
}

/// One scene's medians: each stage's (ms, serial share), what lies outside
/// the stages, and the whole call's serial share and 16-thread prediction.
struct Row {
    frame: f64,
    stages: [(f64, f64); 5],
    outside: f64,
    serial: f64,
    at_16: f64,
}

fn row(scene: &Scene, frames: usize) -> Result<Row> {
    let options = kage::RenderOptions { keep_shadow_maps: false, measure_idle: true, ..Default::default() };
    let mut renderer = kage::Renderer::new(&options).map_err(|e| miette!("{e}"))?;
    renderer.render(scene).map_err(|e| miette!("{e}"))?;
    let mut samples: Vec<[f64; 14]> = Vec::new();
    for _ in 0..frames.max(1) {
        let clock = IdleClock::start();
        let stats = renderer.render(scene).map_err(|e| miette!("{e}"))?.stats;
        let call = clock.stop();
        let parts = stages(&stats);
        let staged: f64 = parts.iter().map(|p| p.wall_ms).sum();
        let mut v = [0.0; 14];
        v[0] = call.wall_ms;
        for (k, p) in parts.iter().enumerate() {
            (v[1 + 2 * k], v[2 + 2 * k]) = (p.wall_ms, p.serial_share());
        }
        (v[11], v[12], v[13]) = ((call.wall_ms - staged).max(0.0), call.serial_share(), call.predicted(16));
        samples.push(v);
    }
    let m = |k: usize| median(&mut samples.iter().map(|s| s[k]).collect::<Vec<_>>());
    Ok(Row {
        frame: m(0),
        stages: std::array::from_fn(|k| (m(1 + 2 * k), m(2 + 2 * k))),
        outside: m(11),
        serial: m(12),
        at_16: m(13),
    })
}

/// Prints the table.
///
/// # Errors
///
/// When a scene does not load or render.
pub fn run(args: &ThreadsArgs) -> Result<()> {
    let c = &args.common;
    let size = (c.width, c.height);
    let mut scenes: Vec<(String, Scene)> = Vec::new();
    let mut demo = kage::scene::demo::demo_scene().map_err(|e| miette!("{e}"))?;
    (demo.width, demo.height) = size;
    scenes.push(("demo".into(), demo));
    let mut showroom = kage::scene::file::load_scene(&repository().join("examples/scenes/showroom.toml"))
        .map_err(|e| miette!("{e}"))?;
    (showroom.width, showroom.height) = size;
    scenes.push(("showroom.toml".into(), showroom));
    let assets = c.assets();
    for rel in [
        "gltf/CesiumMilkTruck/CesiumMilkTruck.glb",
        "meshes/stanford-bunny/stanford-bunny.obj",
        "csg/ex004_cube_minus_sphere.csg",
    ] {
        let path = assets.join(rel);
        if path.exists() {
            let scene = kage::scene::model::scene_for_model(&path, size.0, size.1)
                .map_err(|e| miette!("{}: {e}", path.display()))?;
            scenes.push((path.file_name().unwrap_or_default().to_string_lossy().into_owned(), scene));
        } else {
            eprintln!("kage-bench threads: {} is absent, its row left out", path.display());
        }
    }
    let stage_columns: String = STAGES.iter().map(|s| format!(" {s} ms (serial) |")).collect();
    println!(
        "| scene | frame ms |{stage_columns} outside stages ms | frame serial | frame at 16 threads (Amdahl) ms |"
    );
    println!("|---|---:|{}---:|---:|---:|", "---:|".repeat(STAGES.len()));
    for (name, scene) in &scenes {
        let r = row(scene, c.frames)?;
        // A stage that did not run (under 0.05 ms) has no share to speak of.
        let cell = |&(ms, s): &(f64, f64)| {
            if ms < 0.05 {
                format!(" {ms:.1} (–) |")
            } else {
                format!(" {ms:.1} ({:.0}%) |", 100.0 * s)
            }
        };
        let cells: String = r.stages.iter().map(cell).collect();
        println!("| {name} | {:.1} |{cells} {:.1} | {:.0}% | {:.1} |", r.frame, r.outside, 100.0 * r.serial, r.at_16);
    }
    println!(
        "\n{}x{}, each scene as `kage render FILE` sets it up (the edge pass on); every frame renders its shadow maps \
         again; median of {} frames after a warm-up frame; {} threads. Serial: the share of the wall time during which \
         a worker had no work, from the kernel's per-thread run and run-queue times (`kage::idle`); frame serial and \
         Amdahl over the whole render call, the work outside the stages included.",
        size.0,
        size.1,
        c.frames,
        rayon::current_num_threads()
    );
    Ok(())
}
