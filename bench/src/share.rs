//! The shadow maps' share of a frame on what a user drops in first: the demo,
//! a glTF truck, a scanned mesh and the median corpus OpenSCAD model, as
//! `kage render FILE` sets each up (framed, on a ground, lit by the default
//! rig, the edge pass on). Every frame renders its shadow maps again, as a
//! one-shot render does.

use std::path::{Path, PathBuf};

use kage::Scene;
use miette::{miette, Result};

use crate::{frame_times, Common};

/// `kage-bench shadow-share`.
#[derive(clap::Args, Debug)]
pub struct ShareArgs {
    #[command(flatten)]
    common: Common,
}

fn model(path: &Path, (w, h): (u32, u32)) -> Result<Scene> {
    kage::scene::model::scene_for_model(path, w, h).map_err(|e| miette!("{}: {e}", path.display()))
}

/// The corpus `.csg` model whose frame takes the median time at `size`.
pub(crate) fn median_csg(dir: &Path, size: (u32, u32), frames: usize) -> Result<Option<PathBuf>> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Ok(None) };
    let mut files: Vec<PathBuf> =
        entries.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "csg")).collect();
    files.sort();
    let mut times = Vec::new();
    for f in files {
        // Models with nodes kage does not render are not the median user's.
        let Ok(scene) = model(&f, size) else { continue };
        times.push((frame_times(&scene, frames)?.frame, f));
    }
    times.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(times.get(times.len() / 2).map(|(_, f)| f.clone()))
}

/// Prints the table.
///
/// # Errors
///
/// When a scene does not load or render.
pub fn run(args: &ShareArgs) -> Result<()> {
    let c = &args.common;
    let assets = c.assets();
    println!(
        "| scene | size | frame ms | shadow maps ms | shadow share | shadow stage serial | frame serial | frame at 16 \
         threads (Amdahl) ms |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|");
    for size in [(960, 540), (1920, 1080)] {
        let mut rows: Vec<(String, Scene)> = Vec::new();
        let mut demo = kage::scene::demo::demo_scene().map_err(|e| miette!("{e}"))?;
        (demo.width, demo.height) = size;
        rows.push(("demo".into(), demo));
        for rel in ["gltf/CesiumMilkTruck/CesiumMilkTruck.glb", "meshes/stanford-bunny/stanford-bunny.obj"] {
            let path = assets.join(rel);
            if path.exists() {
                rows.push((path.file_name().unwrap_or_default().to_string_lossy().into_owned(), model(&path, size)?));
            }
        }
        if let Some(csg) = median_csg(&assets.join("csg"), size, 3)? {
            let name = format!("{} (median .csg)", csg.file_name().unwrap_or_default().to_string_lossy());
            rows.push((name, model(&csg, size)?));
        }
        for (name, scene) in rows {
            let t = frame_times(&scene, c.frames)?;
            println!(
                "| {name} | {}x{} | {:.1} | {:.1} | {:.0}% | {:.0}% | {:.0}% | {:.1} |",
                size.0,
                size.1,
                t.frame,
                t.shadows,
                100.0 * t.shadows / t.frame.max(1e-9),
                100.0 * t.shadow_serial,
                100.0 * t.frame_serial,
                t.frame_16
            );
        }
    }
    println!(
        "\nEach scene as `kage render FILE` sets it up (the edge pass on); every frame renders its shadow maps again; \
         median of {} frames after a warm-up frame; the median .csg is the corpus model whose frame takes the median \
         time (3 frames each); 2 threads. Serial: the share of a stage's wall time during which a worker had no \
         work, from the kernel's per-thread run and run-queue times (`kage::idle`); Amdahl: the frame's serial part \
         as it is, the rest of its work over 16 threads.",
        c.frames
    );
    Ok(())
}
