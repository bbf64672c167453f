//! `kage bench --csg`: seed 003's scanline visibility of CSG solids against the
//! paper's baseline, a ray per pixel cast at every primitive, on the OpenSCAD
//! corpus (`../shared/assets/csg`, each model with its own camera);
//! `--csg-random`: the paper's Tables 1 and 2 on random spheres;
//! `--csg-preview`: time to image beside OpenSCAD's preview, and frames per
//! second when only the camera moves.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use glam::Vec2;
use kage::camera::{Camera, Ray};
use kage::csg::openscad::{load_csg, CsgOptions, Geometry};
use kage::csg::{Crossing, CsgCaster, CsgSolid};
use kage::visibility::solids::paper::pattern::PatternMatrix;
use kage::visibility::solids::SurfaceFrame;
use kage::visibility::solids::{CsgMethod, PreparedSolid};
use miette::{miette, Result};
use rayon::prelude::*;

use crate::{median, Common};

/// Which corpus models a CSG table takes.
#[derive(clap::Args, Debug)]
pub struct Models {
    /// Only these corpus models (comma-separated names; default all).
    #[arg(long)]
    models: Option<String>,
}

/// Options of `kage-bench csg`.
#[derive(clap::Args, Debug)]
pub struct CsgArgs {
    #[command(flatten)]
    common: Common,
    #[command(flatten)]
    models: Models,
}

/// Options of `kage-bench csg-random`.
#[derive(clap::Args, Debug)]
pub struct RandomArgs {
    #[command(flatten)]
    common: Common,
}

/// Options of `kage-bench csg-preview`.
#[derive(clap::Args, Debug)]
pub struct PreviewArgs {
    #[command(flatten)]
    common: Common,
    #[command(flatten)]
    models: Models,
    /// The `kage` command timed to its first image (default: the one built
    /// beside this program, `cargo build --release` makes both).
    #[arg(long)]
    kage: Option<PathBuf>,
}

/// Runs the table.
pub fn run(csg: &CsgArgs) -> Result<()> {
    let args = &csg.common;
    let dir = args.assets().join("csg");
    let files = corpus(&dir, &csg.models)?;
    let (w, h) = (args.width, args.height);
    println!(
        "| model | primitives | scanline ms | covered pixels | naive rays ms | ratio | BVH rays ms | ratio | \
         reuse (§5.2.2) ms | pattern matrix: segments, ms |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|");
    let (mut ratios, mut bvh_ratios) = (Vec::new(), Vec::new());
    for path in &files {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        let text: Arc<str> = Arc::from(std::fs::read_to_string(path).map_err(|e| miette!("{e}"))?);
        let options = CsgOptions { geometry: Geometry::Exact, skip_unsupported: true };
        let solid = load_csg(path, text, &options, &Default::default()).map_err(|e| miette!("{e}"))?.solid;
        let Some(camera) = corpus_camera(&dir, name) else {
            eprintln!("skipped {name}: no camera sidecar");
            continue;
        };
        let (mut times, covered) = scan_times(&solid, &camera, (w, h), CsgMethod::Segments, args.frames.max(1));
        let scan_ms = median(&mut times);
        let (mut coherent, _) = scan_times(&solid, &camera, (w, h), CsgMethod::SegmentsCoherent, args.frames.max(1));
        let pattern = pattern_cell(&solid, &camera, w, h, args.frames.max(1));
        let caster = CsgCaster::new(&solid);
        let near = |ray: &Ray| camera.distance_at_depth(ray, 1.0);
        let (naive_ms, naive_covered) = cast(&camera, w, h, |ray| caster.first_hit_every_primitive(ray, near(ray)));
        let (bvh_ms, bvh_covered) = cast(&camera, w, h, |ray| caster.first_hit(ray, near(ray), f32::INFINITY));
        if naive_covered != covered || bvh_covered != covered {
            eprintln!("{name}: scanline, naive and BVH rays cover {covered}, {naive_covered}, {bvh_covered} pixels");
        }
        ratios.push(naive_ms / scan_ms);
        bvh_ratios.push(bvh_ms / scan_ms);
        println!(
            "| {name} | {} | {scan_ms:.1} | {covered} | {naive_ms:.0} | {:.1} | {bvh_ms:.0} | {:.1} | {:.1} | {pattern} |",
            solid.primitives.len(),
            naive_ms / scan_ms,
            bvh_ms / scan_ms,
            median(&mut coherent)
        );
    }
    println!(
        "\n{w}x{h}, exact quadrics, each model with its corpus camera; scanline: the solid prepared once (as the \
         rays' caster is), median of {} frames (the default walk: an eight-pixel block's answer found at its first pixel and spread where it provably holds, seed 003 \
         §5.2.2 by blocks); rays: one frame each. Every method writes the same frame: each pixel's visible \
         surface with its normal, into a buffer allocated beforehand. Naive rays: the paper's baseline, every \
         primitive's interval at every pixel, then combined along the tree. BVH rays: only the primitives whose boxes the ray crosses (a BVH from {} primitives up), combined \
         along the tree with early exits. Reuse: the walk keeping a pixel's answer at the next while its occupants \
         and the depth order of all their ends stay (§5.2.2 pixel by pixel, as the paper has it; the same surfaces \
         to the bit). {} threads. \
         Median ratios: naive/scanline {:.1}, BVH/scanline {:.1}.",
        args.frames.max(1),
        CsgCaster::BVH_PRIMITIVES,
        rayon::current_num_threads(),
        median(&mut ratios),
        median(&mut bvh_ratios)
    );
    Ok(())
}

/// The corpus's `.csg` files (those `--models` names, if given), sorted.
fn corpus(dir: &Path, models: &Models) -> Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| miette!("cannot read {}: {e}", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "csg"))
        .filter(|p| {
            let name = p.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
            models.models.as_ref().is_none_or(|m| m.split(',').any(|k| k.trim() == name))
        })
        .collect();
    files.sort();
    Ok(files)
}

/// Most segments the pattern-matrix column expands (OpenSCAD's own limit).
const PATTERN_LIMIT: usize = 100_000;

/// The pattern-matrix walk's cell: its number of segments and median time, or
/// where the expansion stopped.
fn pattern_cell(solid: &CsgSolid, camera: &Camera, w: u32, h: u32, frames: usize) -> String {
    let Some(tree) = &solid.tree else { return "empty".into() };
    let matrix = match PatternMatrix::expand(tree, solid.primitives.len(), PATTERN_LIMIT) {
        Ok(m) => m,
        Err(e) => return format!("> {} segments", e.limit),
    };
    let method = CsgMethod::PatternMatrix { limit: PATTERN_LIMIT };
    let (mut times, _) = scan_times(solid, camera, (w, h), method, frames);
    format!("{}, {:.1}", matrix.segments.len(), median(&mut times))
}

/// Milliseconds of `frames` scans of `solid` by `method` into one output
/// buffer (allocated by a first, untimed scan, as a renderer keeps its
/// visibility buffer), and the pixels covered.
fn scan_times(
    solid: &CsgSolid,
    camera: &Camera,
    size: (u32, u32),
    method: CsgMethod,
    frames: usize,
) -> (Vec<f64>, usize) {
    // Prepared once, as the rays' caster is: a viewer keeps both while only
    // the camera moves.
    let prepared = PreparedSolid::new(solid, method).expect("expanded before");
    let mut out = SurfaceFrame::new();
    let scan = |out: &mut SurfaceFrame| prepared.scan_into(camera, size, out);
    scan(&mut out);
    let times = (0..frames).map(|_| timed(|| scan(&mut out)).0).collect();
    (times, out.pixels().iter().filter(|p| p.is_some()).count())
}

/// Milliseconds `f` takes, and what it returns.
fn timed<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let t = Instant::now();
    let out = f();
    (t.elapsed().as_secs_f64() * 1e3, out)
}

/// Milliseconds to cast every pixel's centre ray (rows in parallel, four to
/// a task, so that the rays are shared out as evenly as the walk's bands), each
/// pixel's visible surface `first` (with its normal) written into a frame
/// allocated before the clock starts, as the scanline walk writes its own;
/// and the pixels covered.
fn cast(camera: &Camera, w: u32, h: u32, first: impl Fn(&Ray) -> Option<Crossing> + Sync) -> (f64, usize) {
    let rays = camera.pixel_rays(Vec2::new(w as f32, h as f32));
    let mut frame: Vec<Option<Crossing>> = vec![None; w as usize * h as usize];
    let (ms, ()) = timed(|| {
        frame.par_chunks_mut(w as usize).enumerate().with_max_len(4).for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                *px = first(&rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)));
            }
        });
    });
    (ms, frame.iter().filter(|p| p.is_some()).count())
}

/// The camera of the corpus sidecar `NAME.camera.txt`.
fn corpus_camera(dir: &Path, name: &str) -> Option<Camera> {
    let text = std::fs::read_to_string(dir.join(format!("{name}.camera.txt"))).ok()?;
    kage::csg::openscad::sidecar_camera(&text).map(|(camera, _, _)| camera)
}

/// A union of `segments` intersections of `per` spheres each: spheres of radius
/// 0.25–0.45 scattered in the cube [−2, 2]³, each segment's spheres within 0.2
/// of a common centre so that their intersection is not empty.
fn random_spheres(seed: u64, segments: usize, per: usize) -> CsgSolid {
    use kage::csg::{CsgTree, Primitive, Shape};
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut unit = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut primitives = Vec::new();
    let mut kids = Vec::new();
    for _ in 0..segments {
        let centre = glam::Vec3::new(unit(), unit(), unit()) * 4.0 - 2.0;
        let members = (0..per)
            .map(|_| {
                let jitter = (glam::Vec3::new(unit(), unit(), unit()) - 0.5) * 0.4;
                let r = 0.25 + 0.2 * unit();
                let transform = glam::Affine3A::from_scale_rotation_translation(
                    glam::Vec3::splat(r),
                    glam::Quat::IDENTITY,
                    centre + jitter,
                );
                primitives.push(Primitive { shape: Shape::Sphere, transform, color: None, source: 0..0 });
                CsgTree::Leaf(primitives.len() - 1)
            })
            .collect::<Vec<_>>();
        kids.push(if per == 1 { members.into_iter().next().expect("one") } else { CsgTree::Intersection(members) });
    }
    CsgSolid { primitives, tree: Some(CsgTree::Union(kids)) }
}

/// The paper's Tables 1 (random spheres) and 2 (120 spheres in fewer, larger
/// segments): scanline and naive ray casting, at the paper's 160x100 and at
/// 1920x1080.
pub fn run_random(args: &RandomArgs) -> Result<()> {
    let args = &args.common;
    let camera = Camera {
        eye: glam::Vec3::new(0.0, 0.0, 9.0),
        target: glam::Vec3::ZERO,
        up: glam::Vec3::Y,
        near: 0.1,
        far: 100.0,
        projection: kage::camera::Projection::Perspective { fov_y_deg: 40.0 },
        shift: Vec2::ZERO,
    };
    let tables = [
        ("Table 1: random spheres", vec![(50, 1), (100, 1), (200, 1), (300, 1)]),
        ("Table 2: 120 spheres in segments", vec![(120, 1), (60, 2), (40, 3), (30, 4)]),
    ];
    for (title, rows) in tables {
        println!("\n{title}\n");
        println!("| spheres | segments | size | scanline ms | naive rays ms | ratio | pattern matrix ms |");
        println!("|---:|---:|---|---:|---:|---:|---:|");
        for (segments, per) in rows {
            let solid = random_spheres(segments as u64 * 31 + per as u64, segments, per);
            for (w, h) in [(160, 100), (1920, 1080)] {
                let best = |method| {
                    let (times, _) = scan_times(&solid, &camera, (w, h), method, args.frames.max(1));
                    times.into_iter().fold(f64::INFINITY, f64::min)
                };
                let scan_ms = best(CsgMethod::Segments);
                let pattern_ms = best(CsgMethod::PatternMatrix { limit: PATTERN_LIMIT });
                let caster = CsgCaster::new(&solid);
                let (naive_ms, _) = cast(&camera, w, h, |ray| caster.first_hit_every_primitive(ray, 0.0));
                println!(
                    "| {} | {segments} | {w}x{h} | {scan_ms:.1} | {naive_ms:.0} | {:.0} | {pattern_ms:.1} |",
                    segments * per,
                    naive_ms / scan_ms
                );
            }
        }
    }
    println!(
        "\nScanline: best of {} frames; naive rays: one frame, every sphere's interval at every pixel, then the \
         booleans; both write each pixel's surface and normal into a frame. {} threads. The paper (160x100, \
         i80286): 50 spheres 73x, 300 spheres 108x; 120 spheres in 30 segments 225x.",
        args.frames.max(1),
        rayon::current_num_threads()
    );
    Ok(())
}

/// OpenSCAD's preview seconds per model, from the peers' TIMINGS.md table.
pub(crate) fn openscad_preview_seconds(peers: &Path) -> std::collections::HashMap<String, f64> {
    let text = std::fs::read_to_string(peers.join("openscad/TIMINGS.md")).unwrap_or_default();
    text.lines()
        .filter_map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            // | model | set | prims | normalized | preview s | ...
            Some((cells.get(1)?.to_string(), cells.get(5)?.parse().ok()?))
        })
        .collect()
}

/// Time to image of `kage render NAME.csg` (a fresh process, 640x480, median of
/// three) beside OpenSCAD's preview, and frames per second of a viewer whose
/// camera orbits the model, with and without shadows.
pub fn run_preview(preview: &PreviewArgs) -> Result<()> {
    let args = &preview.common;
    let dir = args.assets().join("csg");
    let openscad = openscad_preview_seconds(&args.peers());
    let exe = match &preview.kage {
        Some(exe) => exe.clone(),
        None => std::env::current_exe().map_err(|e| miette!("{e}"))?.with_file_name("kage"),
    };
    if !exe.exists() {
        return Err(miette!("{} is not built: `cargo build --release` builds it beside kage-bench", exe.display()));
    }
    let out = std::env::temp_dir().join(format!("kage-bench-{}.png", std::process::id()));
    let (w, h) = (args.width, args.height);
    println!(
        "| model | kage s (640x480, process) | OpenSCAD preview s | OpenSCAD / kage | fps {w}x{h} | fps, no shadows | fps, aliased |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    let (mut ratios, mut fps_shadowed, mut fps_plain_all) = (Vec::new(), Vec::new(), Vec::new());
    let mut fps_aliased_all = Vec::new();
    for path in corpus(&dir, &preview.models)? {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default().to_string();
        let mut runs: Vec<f64> = (0..3)
            .map(|_| {
                let t = Instant::now();
                let status = std::process::Command::new(&exe)
                    .args(["render", "--width", "640", "--height", "480", "-o"])
                    .arg(&out)
                    .arg(&path)
                    .arg("--skip-unsupported")
                    .stderr(std::process::Stdio::null())
                    .status();
                status.is_ok_and(|s| s.success()).then(|| t.elapsed().as_secs_f64())
            })
            .collect::<Option<_>>()
            .ok_or_else(|| miette!("kage render {} failed", path.display()))?;
        let kage_s = median(&mut runs);
        let theirs = openscad.get(&name).copied();
        let options = CsgOptions { geometry: Geometry::Exact, skip_unsupported: true };
        let options = kage::scene::model::ModelOptions { csg: options, file_camera: true, ..Default::default() };
        let scene = kage::scene::model::scene_for_model_with(&path, w, h, &options).map_err(|e| miette!("{e}"))?;
        let fps = orbit_fps(&scene, args.frames.max(3))?;
        let mut plain = scene.clone();
        plain.lights.iter_mut().for_each(|l| l.shadow = kage::scene::ShadowSettings::NONE);
        let fps_plain = orbit_fps(&plain, args.frames.max(3))?;
        // As a viewer would draw while the camera moves: no edge pass.
        let aliased = kage::Scene { antialias: kage::scene::Antialias::None, ..scene.clone() };
        let fps_aliased = orbit_fps(&aliased, args.frames.max(3))?;
        fps_shadowed.push(fps);
        fps_plain_all.push(fps_plain);
        fps_aliased_all.push(fps_aliased);
        let ratio = theirs.map(|t| t / kage_s);
        ratios.extend(ratio);
        println!(
            "| {name} | {kage_s:.2} | {} | {} | {fps:.1} | {fps_plain:.1} | {fps_aliased:.1} |",
            theirs.map_or("-".into(), |t| format!("{t:.2}")),
            ratio.map_or("-".into(), |r| format!("{r:.1}"))
        );
    }
    std::fs::remove_file(&out).ok();
    println!(
        "\nkage: `kage render NAME.csg --width 640 --height 480` (exact quadrics, lit, shadowed, on a ground), wall \
         clock of the whole process, median of 3. OpenSCAD 2021.01: its preview PNG at 640x480 (no shadows), from \
         peers/openscad/TIMINGS.md (taken on the workplace's standard machine). Orbit: the camera turns 3° about \
         the model per \
         frame, median of {} frames of a reused renderer ({} threads), as `kage render` sets the model up (the \
         edge pass on); aliased: shadows on, no edge pass. Medians: OpenSCAD / kage {:.1}, fps with shadows \
         {:.1}, without {:.1}, aliased {:.1}.",
        args.frames.max(3),
        rayon::current_num_threads(),
        median(&mut ratios),
        median(&mut fps_shadowed),
        median(&mut fps_plain_all),
        median(&mut fps_aliased_all)
    );
    Ok(())
}

/// Frames per second of a renderer re-rendering `scene` as its camera orbits
/// the target (3° per frame about the z axis): the median frame.
fn orbit_fps(scene: &kage::scene::Scene, frames: usize) -> Result<f64> {
    let mut renderer = kage::Renderer::new(&kage::RenderOptions::default()).map_err(|e| miette!("{e}"))?;
    let mut scene = scene.clone();
    let turn = glam::Affine3A::from_translation(scene.camera.target)
        * glam::Affine3A::from_rotation_z(3f32.to_radians())
        * glam::Affine3A::from_translation(-scene.camera.target);
    let mut times = Vec::new();
    for _ in 0..frames {
        scene.camera.eye = turn.transform_point3(scene.camera.eye);
        let t = Instant::now();
        renderer.render(&scene).map_err(|e| miette!("{e}"))?;
        times.push(t.elapsed().as_secs_f64());
    }
    Ok(1.0 / median(&mut times))
}
