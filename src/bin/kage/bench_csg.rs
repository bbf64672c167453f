//! `kage bench --csg`: seed 003's scanline visibility of CSG solids against the
//! paper's baseline, a ray per pixel cast at every primitive, on the OpenSCAD
//! corpus (`../shared/assets/csg`, each model with its own camera).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use glam::Vec2;
use kage::raytrace::csg::CsgCaster;
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
        .filter(|p| {
            let name = p.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
            args.models.as_ref().is_none_or(|m| m.split(',').any(|k| k.trim() == name))
        })
        .collect();
    files.sort();
    let (w, h) = (args.width, args.height);
    println!("| model | primitives | scanline ms | covered pixels | naive rays ms | ratio | BVH rays ms | ratio |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    let (mut ratios, mut bvh_ratios) = (Vec::new(), Vec::new());
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
        let caster = CsgCaster::new(&solid);
        let near = |ray: &kage::scene::Ray| camera.distance_at_depth(ray, 1.0);
        let (naive_ms, naive_covered) =
            timed(|| cast(&camera, w, h, |ray| caster.first_hit_every_primitive(ray, near(ray)).is_some()));
        let (bvh_ms, bvh_covered) =
            timed(|| cast(&camera, w, h, |ray| caster.first_hit(ray, near(ray), f32::INFINITY).is_some()));
        if naive_covered != covered || bvh_covered != covered {
            eprintln!("{name}: scanline, naive and BVH rays cover {covered}, {naive_covered}, {bvh_covered} pixels");
        }
        ratios.push(naive_ms / scan_ms);
        bvh_ratios.push(bvh_ms / scan_ms);
        println!(
            "| {name} | {} | {scan_ms:.1} | {covered} | {naive_ms:.0} | {:.1} | {bvh_ms:.0} | {:.1} |",
            solid.primitives.len(),
            naive_ms / scan_ms,
            bvh_ms / scan_ms
        );
    }
    println!(
        "\n{w}x{h}, exact quadrics, each model with its corpus camera; scanline: median of {} frames; rays: one frame \
         each. Naive rays: the paper's baseline, every primitive's interval at every pixel, then combined along the \
         tree. BVH rays: only the primitives whose boxes the ray crosses (a BVH from {} primitives up), combined \
         along the tree with early exits. {} threads. Median ratios: naive/scanline {:.1}, BVH/scanline {:.1}.",
        args.frames.max(1),
        CsgCaster::BVH_PRIMITIVES,
        rayon::current_num_threads(),
        median(&mut ratios),
        median(&mut bvh_ratios)
    );
    Ok(())
}

/// The median of `v` (0 when empty).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Milliseconds `f` takes, and what it returns.
fn timed<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let t = Instant::now();
    let out = f();
    (t.elapsed().as_secs_f64() * 1e3, out)
}

/// Pixels whose centre ray `covers`, every pixel cast in parallel rows.
fn cast(camera: &Camera, w: u32, h: u32, covers: impl Fn(&kage::scene::Ray) -> bool + Sync) -> usize {
    let rays = camera.pixel_rays(Vec2::new(w as f32, h as f32));
    (0..h)
        .into_par_iter()
        .map(|y| (0..w).filter(|&x| covers(&rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)))).count())
        .sum()
}

/// The camera of the corpus sidecar `NAME.camera.txt`.
fn corpus_camera(dir: &Path, name: &str) -> Option<Camera> {
    let text = std::fs::read_to_string(dir.join(format!("{name}.camera.txt"))).ok()?;
    kage::scene::load::openscad::sidecar_camera(&text).map(|(camera, _, _)| camera)
}
