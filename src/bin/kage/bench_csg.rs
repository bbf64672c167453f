//! `kage bench --csg`: seed 003's scanline visibility of CSG solids against the
//! paper's baseline, a ray per pixel cast at every primitive, on the OpenSCAD
//! corpus (`../shared/assets/csg`, each model with its own camera).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use glam::Vec2;
use kage::raytrace::csg::CsgCaster;
use kage::scene::csg::CsgSolid;
use kage::scene::load::openscad::{load_csg, CsgOptions, Geometry};
use kage::scene::Camera;
use kage::visibility::csg::scan_solid;
use miette::{miette, Result};
use rayon::prelude::*;

use crate::bench::BenchArgs;

/// Runs the table.
pub fn run(args: &BenchArgs) -> Result<()> {
    let dir = args.peers.join("../assets/csg");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map_err(|e| miette!("cannot read {}: {e}", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "csg"))
        .collect();
    files.sort();
    let (w, h) = (args.width, args.height);
    println!("| model | primitives | scanline ms | covered pixels | ray per pixel, every primitive ms | ratio |");
    println!("|---|---:|---:|---:|---:|---:|");
    let mut ratios = Vec::new();
    for path in &files {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        let text: Arc<str> = Arc::from(std::fs::read_to_string(path).map_err(|e| miette!("{e}"))?);
        let options = CsgOptions { geometry: Geometry::Exact, skip_unsupported: true };
        let solid = load_csg(path, text, &options).map_err(|e| miette!("{e}"))?.solid;
        let Some(camera) = corpus_camera(&dir, name) else {
            eprintln!("skipped {name}: no camera sidecar");
            continue;
        };
        let mut times = Vec::new();
        let mut covered = 0;
        for _ in 0..args.frames.max(1) {
            let t = Instant::now();
            let pixels = scan_solid(&solid, &camera, w, h);
            times.push(t.elapsed().as_secs_f64() * 1e3);
            covered = pixels.iter().filter(|p| p.is_some()).count();
        }
        times.sort_by(f64::total_cmp);
        let scan_ms = times[times.len() / 2];
        let t = Instant::now();
        let naive_covered = naive(&solid, &camera, w, h);
        let naive_ms = t.elapsed().as_secs_f64() * 1e3;
        if naive_covered != covered {
            eprintln!("{name}: the two methods cover {covered} and {naive_covered} pixels");
        }
        ratios.push(naive_ms / scan_ms);
        println!(
            "| {name} | {} | {scan_ms:.1} | {covered} | {naive_ms:.0} | {:.1} |",
            solid.primitives.len(),
            naive_ms / scan_ms
        );
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios.get(ratios.len() / 2).copied().unwrap_or(0.0);
    println!(
        "\n{w}x{h}, exact quadrics, each model with its corpus camera; scanline: median of {} frames; ray per pixel: one \
         frame (the paper's baseline: every primitive's interval at every pixel, combined along the tree); {} threads. \
         Median ratio {median:.1}.",
        args.frames.max(1),
        rayon::current_num_threads()
    );
    Ok(())
}

/// Pixels covered when every pixel's ray is cast at every primitive.
fn naive(solid: &CsgSolid, camera: &Camera, w: u32, h: u32) -> usize {
    let caster = CsgCaster::new(solid);
    let rays = camera.pixel_rays(Vec2::new(w as f32, h as f32));
    (0..h)
        .into_par_iter()
        .map(|y| {
            (0..w)
                .filter(|&x| {
                    let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                    caster.first_hit(&ray, 0.0, f32::INFINITY).is_some()
                })
                .count()
        })
        .sum()
}

/// The camera of the corpus sidecar `NAME.camera.txt`.
fn corpus_camera(dir: &Path, name: &str) -> Option<Camera> {
    let text = std::fs::read_to_string(dir.join(format!("{name}.camera.txt"))).ok()?;
    kage::scene::load::openscad::sidecar_camera(&text).map(|(camera, _, _)| camera)
}
