//! `kage bench`: milliseconds per frame at 1920x1080 on the peers' procedural
//! scenes (`../shared/peers/common/gen_scene.py`), split into visibility and
//! shading, beside Mesa llvmpipe running the same scene in the same go when its
//! peer program is built. Camera, light and Phong rule follow
//! `../shared/peers/common/peer_common.h`, so the images can be compared.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{Affine3A, Vec3};
use kage::camera::{Camera, Projection};
use kage::scene::load::{self, FileSystem};
use kage::scene::{file::add_model, Falloff, Light, LightKind, Material, Scene, ShadowSettings};
use kage::{RenderOptions, Renderer};
use miette::{miette, IntoDiagnostic, Result};
use rayon::prelude::*;

/// Options of `kage bench`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Folder with sphere10k.obj, sphere100k.obj, sphere1m.obj (written there by
    /// gen_scene.py when missing).
    #[arg(long, default_value = "target/peer_meshes")]
    meshes: PathBuf,
    /// The peers folder (for gen_scene.py).
    #[arg(long, default_value = "../shared/peers")]
    pub(crate) peers: PathBuf,
    /// The llvmpipe peer program (`scripts/build-peers.sh` builds it); skipped if absent.
    #[arg(long, default_value = "target/peers/llvmpipe_bench_egl")]
    llvmpipe: PathBuf,
    /// Timed frames per row (the median is reported).
    #[arg(long, default_value_t = 10)]
    pub(crate) frames: usize,
    /// Alternating rounds of kage and llvmpipe; the best round of each is reported.
    #[arg(long, default_value_t = 5)]
    rounds: usize,
    /// `--csg`: only these corpus models (comma-separated names; default all).
    #[arg(long)]
    pub models: Option<String>,
    /// Only these scenes (comma-separated names).
    #[arg(long, default_value = "sphere10k,sphere100k,sphere1m")]
    scenes: String,
    /// The peer's modes to run, comma-separated: `phong` (no shadows), `shadow1`
    /// (a 2048² shadow map, one test per pixel), `shadow4` (2 x 2 PCF).
    #[arg(long, default_value = "phong")]
    modes: String,
    /// Benchmark the BVH (build time, primary-ray throughput) beside Embree
    /// instead of the raster frame beside llvmpipe.
    #[arg(long)]
    rays: bool,
    /// Time seed 002 §4's hybrid (item buffer + traced secondary rays) against the
    /// same image traced entirely by rays, on examples/scenes/reflections.toml with a
    /// matte floor.
    #[arg(long)]
    hybrid: bool,
    /// Antialiasing: aliased, seed 004's edge pass and jittered passes against a
    /// 256-pass supersampled truth on the example scenes and two real models.
    #[arg(long)]
    aa: bool,
    /// CSG solids: seed 003's scanline visibility against a ray per pixel cast at
    /// every primitive, on the OpenSCAD corpus (`../shared/assets/csg`).
    #[arg(long)]
    csg: bool,
    /// CSG: the paper's Tables 1 and 2 on random spheres (50-300 spheres; 120
    /// spheres in 120/60/40/30 segments) at 160x100 and 1920x1080, scanline
    /// against naive ray casting.
    #[arg(long)]
    csg_random: bool,
    /// CSG: time to image of `kage render NAME.csg` at 640x480 (a fresh process,
    /// as OpenSCAD's preview in ../shared/peers/openscad/TIMINGS.md), and frames
    /// per second at --width x --height when only the camera moves.
    #[arg(long)]
    csg_preview: bool,
    /// With --aa: write side-by-side crops (aliased | edge pass | truth) here.
    #[arg(long)]
    pub(crate) crops: Option<PathBuf>,
    /// Time frames as lights grow (1, 4, 16, 100 spot lights round the first
    /// scene), with and without shadow maps.
    #[arg(long)]
    lights: bool,
    /// The Embree peer program (`scripts/build-peers.sh` builds it); skipped if absent.
    #[arg(long, default_value = "target/peers/embree_bench")]
    embree: PathBuf,
    /// Image width.
    #[arg(long, default_value_t = 1920)]
    pub(crate) width: u32,
    /// Image height.
    #[arg(long, default_value_t = 1080)]
    pub(crate) height: u32,
}

struct Row {
    name: String,
    triangles: usize,
    visibility_ms: f64,
    shadow_ms: f64,
    shading_ms: f64,
    total_ms: f64,
    peer: Option<(f64, Option<f64>)>,
}

/// Runs the benchmark and prints the table.
pub fn run(args: &BenchArgs) -> Result<()> {
    if args.rays {
        return run_rays(args);
    }
    if args.hybrid {
        return run_hybrid(args);
    }
    if args.lights {
        return run_lights(args);
    }
    if args.aa {
        return crate::bench_aa::run(args);
    }
    if args.csg {
        return crate::bench_csg::run(args);
    }
    if args.csg_random {
        return crate::bench_csg::run_random(args);
    }
    if args.csg_preview {
        return crate::bench_csg::run_preview(args);
    }
    let lp = &args.llvmpipe;
    let mut rows = Vec::new();
    let runs = args.scenes.split(',').flat_map(|s| args.modes.split(',').map(move |m| (s.trim(), m.trim())));
    for (name, mode) in runs {
        let mesh = ensure_mesh(args, name)?;
        let scene = peer_scene(&mesh, args.width, args.height, mode)?;
        let label = format!("{name} {mode}");
        // Rounds alternate kage and the peer; each keeps its best round, so a burst
        // of load from a neighbour on a shared machine hurts neither side's number.
        let mut best: Option<Row> = None;
        for _ in 0..args.rounds.max(1) {
            let (row, image) = time_kage(&label, &scene, args.frames)?;
            let peer = lp.exists().then(|| run_llvmpipe(lp, &mesh, args, mode, &image)).transpose()?;
            best = Some(match best {
                None => Row { peer, ..row },
                Some(b) => Row {
                    peer: match (b.peer, peer) {
                        (Some(p), Some(q)) => Some(if q.0 < p.0 { q } else { p }),
                        (p, q) => p.or(q),
                    },
                    ..if row.total_ms < b.total_ms { row } else { b }
                },
            });
        }
        rows.push(best.expect("at least one round"));
        eprintln!("{label}: done");
    }
    print_table(&rows, args);
    Ok(())
}

fn ensure_mesh(args: &BenchArgs, name: &str) -> Result<PathBuf> {
    let path = args.meshes.join(format!("{name}.obj"));
    if !path.exists() {
        let script = args.peers.join("common/gen_scene.py");
        let status = Command::new("python3").arg(&script).arg("--all").arg(&args.meshes).status().into_diagnostic()?;
        if !status.success() || !path.exists() {
            return Err(miette!("{} is missing and {} could not write it", path.display(), script.display()));
        }
    }
    Ok(path)
}

/// The peers' scene convention (peer_common.h) around the loaded mesh, lit for
/// the peer's `mode`.
fn peer_scene(path: &Path, width: u32, height: u32, mode: &str) -> Result<Scene> {
    let fs = FileSystem { base: path.parent().unwrap_or(Path::new(".")).to_path_buf() };
    let model = load::model(Path::new(path.file_name().unwrap_or_default()), &fs).map_err(|e| miette!("{e}"))?;
    let albedo = Vec3::new(0.75, 0.72, 0.65);
    let material = Material {
        name: "peer".into(),
        ka: albedo,
        kd: 0.9 * albedo,
        ks: Vec3::splat(0.3),
        shininess: 32.0,
        ..Material::default()
    };
    let (lo, hi) = model.bounds();
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
    let mut scene = Scene {
        width,
        height,
        background: Vec3::new(0.1, 0.1, 0.15),
        camera: Camera {
            eye: c + 1.2 * r * Vec3::new(0.0, 0.5, 1.0).normalize(),
            target: c,
            up: Vec3::Y,
            near: 0.1 * r,
            far: 2.5 * r,
            projection: Projection::Perspective { fov_y_deg: 45.0 },
            shift: glam::Vec2::ZERO,
        },
        lights: vec![peer_light(c, r, mode)?],
        materials: vec![material],
        objects: Vec::new(),
        warnings: Vec::new(),
        exposure: Default::default(),
        antialias: Default::default(),
        fog: None,
        environment: None,
        translucency: Default::default(),
    };
    add_model(&mut scene, &model, "peer", Affine3A::IDENTITY, Some(0));
    Ok(scene)
}

/// The peers' point light at c + r·(1, 1.6, −0.6). With shadows, the peer renders
/// one perspective 2048² map aimed at the mesh's centre, its cone just holding
/// the bounding sphere: kage's equivalent is a spot light with that cone (no
/// falloff inside it, so the shading is the point light's).
fn peer_light(c: Vec3, r: f32, mode: &str) -> Result<Light> {
    let position = c + r * Vec3::new(1.0, 1.6, -0.6);
    let half = (r / (position - c).length()).min(0.99).asin() * 1.05;
    let (kind, shadow) = match mode {
        "phong" => (LightKind::Point { position }, ShadowSettings::NONE),
        "shadow1" | "shadow4" => (
            LightKind::Spot { position, direction: (c - position).normalize(), inner: half, outer: half },
            ShadowSettings {
                resolution: 2048,
                pcf: if mode == "shadow4" { 2 } else { 1 },
                ..ShadowSettings::default()
            },
        ),
        _ => return Err(miette!("unknown mode '{mode}' (expected phong, shadow1 or shadow4)")),
    };
    Ok(Light { kind, ambient: 0.1, falloff: Falloff::None, shadow, ..Light::default() })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn time_kage(name: &str, scene: &Scene, frames: usize) -> Result<(Row, kage::image::LinearImage)> {
    let mut renderer = Renderer::new(&RenderOptions::default()).map_err(|e| miette!("{e}"))?;
    renderer.render(scene).map_err(|e| miette!("{e}"))?; // warm-up
    let (mut vis, mut shadow, mut shade, mut total) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for _ in 0..frames.max(1) {
        let t = std::time::Instant::now();
        let stats = renderer.render(scene).map_err(|e| miette!("{e}"))?.stats;
        total.push(t.elapsed().as_secs_f64() * 1e3);
        vis.push(stats.visibility_ms);
        shadow.push(stats.shadow_ms);
        shade.push(stats.shading_ms);
    }
    let frame = renderer.into_frame();
    let row = Row {
        name: name.to_string(),
        triangles: scene.triangle_count(),
        visibility_ms: median(vis),
        shadow_ms: median(shadow),
        shading_ms: median(shade),
        total_ms: median(total),
        peer: None,
    };
    Ok((row, frame.image))
}

/// Runs llvmpipe on the same mesh; returns its median ms and the RMSE (0-255
/// scale) between its image and kage's.
fn run_llvmpipe(
    bin: &Path,
    mesh: &Path,
    args: &BenchArgs,
    mode: &str,
    ours: &kage::image::LinearImage,
) -> Result<(f64, Option<f64>)> {
    let prefix = std::env::temp_dir().join("kage_bench_llvmpipe");
    let out = Command::new(bin)
        .env("LP_NUM_THREADS", "2")
        .args([
            "-w",
            &args.width.to_string(),
            "-h",
            &args.height.to_string(),
            "-f",
            &args.frames.to_string(),
            "-m",
            mode,
            "-o",
        ])
        .arg(&prefix)
        .arg(mesh)
        .output()
        .into_diagnostic()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let ms = text
        .split_whitespace()
        .find_map(|w| w.strip_prefix("median_ms="))
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| miette!("llvmpipe printed no median_ms: {text}{}", String::from_utf8_lossy(&out.stderr)))?;
    let png = PathBuf::from(format!("{}_{mode}.png", prefix.display()));
    Ok((ms, rmse_against(&png, ours)))
}

fn rmse_against(png: &Path, ours: &kage::image::LinearImage) -> Option<f64> {
    let theirs = image::open(png).ok()?.into_rgb8();
    if theirs.dimensions() != (ours.width(), ours.height()) {
        return None;
    }
    let sum: f64 = theirs
        .pixels()
        .zip(ours.pixels())
        .flat_map(|(t, o)| (0..3).map(move |k| (t[k] as f64 - (o[k].clamp(0.0, 1.0) as f64 * 255.0).round()).powi(2)))
        .sum();
    Some((sum / (3.0 * ours.pixels().len() as f64)).sqrt())
}

fn print_table(rows: &[Row], args: &BenchArgs) {
    println!("| scene, mode | triangles | visibility ms | shadow map ms | shading ms | kage ms/frame | llvmpipe ms/frame | kage / llvmpipe | RMSE vs llvmpipe (0-255) |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let (peer, ratio, rmse) = match r.peer {
            Some((ms, rmse)) => (
                format!("{ms:.1}"),
                format!("{:.2}", r.total_ms / ms),
                rmse.map_or("n/a".into(), |e| format!("{e:.2}")),
            ),
            None => ("not built".into(), "n/a".into(), "n/a".into()),
        };
        println!(
            "| {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {peer} | {ratio} | {rmse} |",
            r.name, r.triangles, r.visibility_ms, r.shadow_ms, r.shading_ms, r.total_ms
        );
    }
    println!(
        "\n{}x{}, median of {} frames, best of {} alternating rounds, {} threads.",
        args.width,
        args.height,
        args.frames,
        args.rounds.max(1),
        rayon::current_num_threads()
    );
}

/// One row of the ray benchmark: (build ms, Mrays/s) for kage and Embree.
struct RayRow {
    name: String,
    triangles: usize,
    build_ms: f64,
    mrays: f64,
    peer: Option<(f64, f64)>,
}

fn run_rays(args: &BenchArgs) -> Result<()> {
    let mut rows = Vec::new();
    for name in args.scenes.split(',').map(str::trim) {
        let mesh = ensure_mesh(args, name)?;
        let scene = peer_scene(&mesh, args.width, args.height, "phong")?;
        let mut best: Option<RayRow> = None;
        for _ in 0..args.rounds.max(1) {
            let (build_ms, mrays) = time_rays(&scene, args.frames);
            let peer = args.embree.exists().then(|| run_embree(&args.embree, &mesh, args)).transpose()?;
            let row = RayRow { name: name.to_string(), triangles: scene.triangle_count(), build_ms, mrays, peer };
            best = Some(match best {
                None => row,
                Some(b) => RayRow {
                    build_ms: b.build_ms.min(row.build_ms),
                    mrays: b.mrays.max(row.mrays),
                    peer: match (b.peer, row.peer) {
                        (Some(p), Some(q)) => Some((p.0.min(q.0), p.1.max(q.1))),
                        (p, q) => p.or(q),
                    },
                    ..row
                },
            });
        }
        rows.push(best.expect("one round"));
        eprintln!("{name}: done");
    }
    println!("| scene | triangles | kage build ms | Embree build ms | build ratio | kage Mrays/s | Embree Mrays/s | rate ratio |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        let (pb, pr, bratio, rratio) = match r.peer {
            Some((b, m)) => {
                (format!("{b:.1}"), format!("{m:.2}"), format!("{:.2}", r.build_ms / b), format!("{:.2}", r.mrays / m))
            }
            None => ("not built".into(), "not built".into(), "n/a".into(), "n/a".into()),
        };
        println!(
            "| {} | {} | {:.1} | {pb} | {bratio} | {:.2} | {pr} | {rratio} |",
            r.name, r.triangles, r.build_ms, r.mrays
        );
    }
    println!(
        "\n{}x{} primary rays (one per pixel centre, nearest hit, no shading), median of {} frames; build median of 5; best of {} rounds; {} threads.",
        args.width,
        args.height,
        args.frames,
        args.rounds.max(1),
        rayon::current_num_threads()
    );
    Ok(())
}

/// Median BVH build time (ms) and primary-ray throughput (Mrays/s).
fn time_rays(scene: &Scene, frames: usize) -> (f64, f64) {
    use kage::raytrace::TraceScene;
    let mut builds = Vec::new();
    let mut trace = TraceScene::new(scene);
    for _ in 0..5 {
        let t = std::time::Instant::now();
        trace = TraceScene::new(scene);
        builds.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let rays = scene.camera.pixel_rays(glam::Vec2::new(scene.width as f32, scene.height as f32));
    let (w, h) = (scene.width, scene.height);
    let mut times = Vec::new();
    for _ in 0..frames.max(1) + 1 {
        let t = std::time::Instant::now();
        let hits: usize = (0..h)
            .into_par_iter()
            .map(|y| {
                (0..w)
                    .filter(|&x| {
                        let ray = rays.ray(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                        trace.intersect(&ray, f32::INFINITY).is_some()
                    })
                    .count()
            })
            .sum();
        std::hint::black_box(hits);
        times.push(t.elapsed().as_secs_f64());
    }
    times.remove(0); // warm-up
    (median(builds), (w * h) as f64 / median(times) / 1e6)
}

/// Runs Embree's primary-ray benchmark (rtcIntersect1, no shading) on the same mesh.
fn run_embree(bin: &Path, mesh: &Path, args: &BenchArgs) -> Result<(f64, f64)> {
    let out = Command::new(bin)
        .args(["-t", "2", "-n", "-m", "primary", "-a", "1", "-f", &args.frames.to_string()])
        .args(["-w", &args.width.to_string(), "-h", &args.height.to_string()])
        .arg(mesh)
        .output()
        .into_diagnostic()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let field = |line: &str, key: &str| -> Option<f64> {
        line.split_whitespace().find_map(|w| w.strip_prefix(key)).and_then(|v| v.parse().ok())
    };
    let build = text.lines().find(|l| l.contains("what=build")).and_then(|l| field(l, "median_ms="));
    let rate = text.lines().find(|l| l.contains("mode=primary")).and_then(|l| field(l, "mrays_s="));
    match (build, rate) {
        (Some(b), Some(r)) => Ok((b, r)),
        _ => Err(miette!("Embree printed no build/primary results: {text}{}", String::from_utf8_lossy(&out.stderr))),
    }
}

/// Item-buffer hybrid vs full ray tracing of the same image (two ray levels).
fn run_hybrid(args: &BenchArgs) -> Result<()> {
    let load = |name: &str| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes").join(name);
        let mut scene = kage::scene::file::load_scene(&path).map_err(|e| miette!("{e}"))?;
        (scene.width, scene.height) = (args.width, args.height);
        Ok::<Scene, miette::Report>(scene)
    };
    let showroom = load("showroom.toml")?;
    let mut balls = load("reflections.toml")?;
    // A matte floor leaves the curved chrome and glass balls as the only reflecting
    // and refracting pixels.
    balls.materials.iter_mut().filter(|m| m.name == "floor").for_each(|m| m.kr = glam::Vec3::ZERO);
    let mut closer = balls.clone();
    let cam = &mut closer.camera;
    cam.eye = cam.target + (cam.eye - cam.target) * 0.8; // the balls fill about a fifth
    println!(
        "| scene | triangles | pixels traced | hybrid ms/frame | of which visibility / shadow maps / shading / traced | full trace ms/frame | speed-up | BVH build ms (once) | RMSE between them | pixels over 0.01 |"
    );
    println!("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|");
    let rows = [
        ("showroom.toml (polished stage, chrome ball)", &showroom),
        ("reflections.toml, matte floor (chrome and glass balls)", &balls),
        ("the same, eye at 0.8x", &closer),
    ];
    for (label, scene) in rows {
        hybrid_row(args, scene, label)?;
    }
    println!(
        "\nTwo ray levels (primary + one bounce); primary shadows from shadow maps (hybrid) or shadow rays (full trace); \
         shadow rays at the surfaces secondary rays reach in both; one BVH, built before timing; median of {} frames; {} threads.",
        args.frames.max(1),
        rayon::current_num_threads()
    );
    Ok(())
}

/// One row of the hybrid table: the item-buffer frame and the fully traced image of
/// `scene`, timed alternately.
fn hybrid_row(args: &BenchArgs, scene: &Scene, label: &str) -> Result<()> {
    // "Traced up to the second ray" (seed 002 §4): primary + one bounce.
    let depth = 1;
    let mut renderer =
        Renderer::new(&RenderOptions { ray_depth: depth, ..RenderOptions::default() }).map_err(|e| miette!("{e}"))?;
    let (mut hybrid, mut full) = (Vec::new(), Vec::new());
    let mut parts = Vec::new();
    let mut full_image = None;
    // Both sides trace through one BVH, built once (an interactive preview keeps it
    // while only the view changes); the build is reported on its own.
    let t = std::time::Instant::now();
    let trace = kage::raytrace::TraceScene::new(scene);
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    renderer.render(scene).map_err(|e| miette!("{e}"))?; // builds the renderer's copy
    for _ in 0..args.frames.max(1) {
        let t = std::time::Instant::now();
        parts.push(renderer.render(scene).map_err(|e| miette!("{e}"))?.stats);
        hybrid.push(t.elapsed().as_secs_f64() * 1e3);
        let t = std::time::Instant::now();
        full_image = Some(trace_everything(scene, &trace, depth));
        full.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let frame = renderer.into_frame();
    let c = kage::compare::compare(&frame.image, &full_image.expect("one frame"), 0.01).map_err(|e| miette!("{e}"))?;
    let (h, f) = (median(hybrid), median(full));
    let traced = parts.last().map_or(0, |s| s.traced_pixels);
    let share = 100.0 * traced as f64 / (scene.width as f64 * scene.height as f64);
    let part = |get: fn(&kage::frame::FrameStats) -> f64| median(parts.iter().map(get).collect());
    println!(
        "| {label} {}x{} | {} | {share:.1}% | {h:.1} | {:.0} / {:.0} / {:.0} / {:.0} | {f:.1} | {:.2}x | {build_ms:.1} | {:.5} | {:.3}% |",
        scene.width,
        scene.height,
        trace.len(),
        part(|s| s.visibility_ms),
        part(|s| s.shadow_ms),
        part(|s| s.shading_ms),
        part(|s| s.traced_ms),
        f / h,
        c.rmse,
        100.0 * c.share_over
    );
    Ok(())
}

/// The hybrid's image computed entirely by rays, as a plain ray tracer would:
/// primary hits from the BVH, shadow rays at them (where the hybrid reads shadow
/// maps), the same bounces.
fn trace_everything(scene: &Scene, trace: &kage::raytrace::TraceScene, depth: u32) -> kage::image::LinearImage {
    use kage::raytrace::tracer::{ShadowRay, Tracer};
    use kage::shading::ObjectFrames;
    let frames = ObjectFrames::new(scene);
    let tracer = Tracer::new(scene, trace, &frames, ShadowRay);
    let rays = scene.camera.pixel_rays(glam::Vec2::new(scene.width as f32, scene.height as f32));
    let mut image = kage::image::LinearImage::new(scene.width, scene.height);
    image.pixels_mut().par_chunks_mut(scene.width as usize).enumerate().for_each(|(y, row)| {
        for (x, px) in row.iter_mut().enumerate() {
            *px = tracer.radiance(&rays.ray(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5)), depth);
        }
    });
    image
}

/// Milliseconds per frame as the number of lights grows, with and without shadow
/// maps: seed 002's "a light is only more passes" says the cost is linear.
fn run_lights(args: &BenchArgs) -> Result<()> {
    let name = args.scenes.split(',').next().unwrap_or("sphere100k").trim();
    let mesh = ensure_mesh(args, name)?;
    let base = peer_scene(&mesh, args.width, args.height, "shadow1")?;
    let (lo, hi) = base.bounds().ok_or_else(|| miette!("empty scene"))?;
    let c = (lo + hi) * 0.5;
    println!(
        "| lights | shadows | visibility ms | shadow map ms | shading ms | ms/frame | ms per light | shading passes |"
    );
    println!("|---:|---|---:|---:|---:|---:|---:|---:|");
    for n in [1usize, 4, 16, 100] {
        for shadows in [false, true] {
            let mut scene = base.clone();
            scene.lights = (0..n).map(|i| ring_light(&base.lights[0], c, i, n, shadows)).collect();
            let (row, _) = time_kage(name, &scene, args.frames)?;
            let mut renderer = Renderer::new(&RenderOptions::default()).map_err(|e| miette!("{e}"))?;
            let passes = renderer.render(&scene).map_err(|e| miette!("{e}"))?.stats.shading_passes;
            println!(
                "| {n} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {passes} |",
                if shadows { "2048² map each" } else { "none" },
                row.visibility_ms,
                row.shadow_ms,
                row.shading_ms,
                row.total_ms,
                row.total_ms / n as f64
            );
        }
    }
    println!(
        "\n{name}, {}x{}, spot lights on a ring above the mesh (intensity 1/n each), median of {} frames, {} threads.",
        args.width,
        args.height,
        args.frames,
        rayon::current_num_threads()
    );
    Ok(())
}

/// Light `i` of `n` on a ring above the scene: the peer light turned about the
/// vertical through the centre.
fn ring_light(peer: &Light, c: Vec3, i: usize, n: usize, shadows: bool) -> Light {
    let LightKind::Spot { position, inner, outer, .. } = peer.kind else { return peer.clone() };
    let turn = glam::Quat::from_rotation_y(i as f32 * std::f32::consts::TAU / n as f32);
    let position = c + turn * (position - c);
    Light {
        kind: LightKind::Spot { position, direction: (c - position).normalize(), inner, outer },
        intensity: 1.0 / n as f32,
        ambient: 0.1 / n as f32,
        shadow: if shadows { peer.shadow } else { ShadowSettings::NONE },
        ..peer.clone()
    }
}
