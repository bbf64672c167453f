//! `kage-bench raster`: milliseconds per frame on the peers' procedural meshes
//! (`peers/common/gen_scene.py`), split into visibility, shadow maps and
//! shading, beside Mesa llvmpipe running the same scene in the same go when its
//! peer program is built. Camera, light and Phong rule follow
//! `peers/common/peer_common.h`, so the images can be compared.
//!
//! Like for like: llvmpipe renders its shadow map every frame, so the rows
//! compared with it render kage's every frame too; the kept-map rows (a viewer
//! whose camera moves re-renders no spot light's map) stand on their own.
//!
//! `kage-bench lights`: the same scene as the lights grow.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{Affine3A, Vec3};
use kage::camera::{Camera, Projection};
use kage::image::LinearImage;
use kage::scene::load::{self, FileSystem};
use kage::scene::{file::add_model, Falloff, Light, LightKind, Material, Scene, ShadowSettings};
use kage::{RenderOptions, Renderer};
use miette::{miette, IntoDiagnostic, Result};

use crate::{median, Common};

/// Where the peers' meshes are, and which to run.
#[derive(clap::Args, Debug, Clone)]
pub struct Meshes {
    /// Folder with sphere10k.obj, sphere100k.obj, sphere1m.obj (written there by
    /// the peers' gen_scene.py when missing).
    #[arg(long, default_value = "target/peer_meshes")]
    pub meshes: PathBuf,
    /// Only these meshes (comma-separated names).
    #[arg(long, default_value = "sphere10k,sphere100k,sphere1m")]
    pub scenes: String,
}

/// Options of `kage-bench raster`.
#[derive(clap::Args, Debug)]
pub struct RasterArgs {
    #[command(flatten)]
    common: Common,
    #[command(flatten)]
    meshes: Meshes,
    /// The llvmpipe peer program (`scripts/build-peers.sh` builds it); its
    /// columns stay empty if it is absent.
    #[arg(long, default_value = "target/peers/llvmpipe_bench_egl")]
    llvmpipe: PathBuf,
    /// Alternating rounds of kage and llvmpipe; the best round of each is reported.
    #[arg(long, default_value_t = 5)]
    rounds: usize,
    /// The peer's modes, comma-separated: `phong` (no shadows), `shadow1` (a
    /// 2048² shadow map, one test per pixel), `shadow4` (2 x 2 PCF).
    #[arg(long, default_value = "phong,shadow1,shadow4")]
    modes: String,
}

/// Options of `kage-bench lights`.
#[derive(clap::Args, Debug)]
pub struct LightsArgs {
    #[command(flatten)]
    common: Common,
    #[command(flatten)]
    meshes: Meshes,
}

/// One row of the raster table.
struct Row {
    name: String,
    triangles: usize,
    visibility_ms: f64,
    shadow_ms: f64,
    shading_ms: f64,
    total_ms: f64,
    /// llvmpipe's ms per frame and the RMSE between the images, when run.
    peer: Option<(f64, Option<f64>)>,
}

impl Row {
    /// The better of two rounds: the faster kage frame, the faster peer frame.
    fn best(self, other: Row) -> Row {
        let peer = match (self.peer, other.peer) {
            (Some(p), Some(q)) => Some(if q.0 < p.0 { q } else { p }),
            (p, q) => p.or(q),
        };
        Row { peer, ..if other.total_ms < self.total_ms { other } else { self } }
    }
}

/// Runs the raster table and prints it.
pub fn run(args: &RasterArgs) -> Result<()> {
    let common = &args.common;
    let mut rows = Vec::new();
    let runs = args.meshes.scenes.split(',').flat_map(|s| args.modes.split(',').map(move |m| (s.trim(), m.trim())));
    for (name, mode) in runs {
        let mesh = ensure_mesh(common, &args.meshes, name)?;
        let scene = peer_scene(&mesh, common.width, common.height, mode)?;
        let shadowed = mode != "phong";
        // Rounds alternate kage and the peer; each keeps its best round, so a burst
        // of load from a neighbour on a shared machine hurts neither side's number.
        let mut best: Option<Row> = None;
        let mut kept: Option<Row> = None;
        for _ in 0..args.rounds.max(1) {
            let label =
                if shadowed { format!("{name} {mode}, map rendered every frame") } else { format!("{name} {mode}") };
            let (row, image) = time_kage(&label, &scene, common.frames, false)?;
            let lp = &args.llvmpipe;
            let peer = lp.exists().then(|| run_llvmpipe(lp, &mesh, common, mode, &image)).transpose()?;
            let row = Row { peer, ..row };
            best = Some(match best.take() {
                None => row,
                Some(b) => b.best(row),
            });
            if shadowed {
                let (row, _) =
                    time_kage(&format!("{name} {mode}, map kept between frames"), &scene, common.frames, true)?;
                kept = Some(match kept.take() {
                    None => row,
                    Some(b) => b.best(row),
                });
            }
        }
        rows.extend(best);
        rows.extend(kept);
        eprintln!("{name} {mode}: done");
    }
    print_table(&rows, args);
    Ok(())
}

/// The peers' mesh `name`, written by their generator when missing.
fn ensure_mesh(common: &Common, meshes: &Meshes, name: &str) -> Result<PathBuf> {
    let path = meshes.meshes.join(format!("{name}.obj"));
    if !path.exists() {
        let script = common.peers().join("common/gen_scene.py");
        let status =
            Command::new("python3").arg(&script).arg("--all").arg(&meshes.meshes).status().into_diagnostic()?;
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
    let camera = Camera {
        eye: c + 1.2 * r * Vec3::new(0.0, 0.5, 1.0).normalize(),
        target: c,
        up: Vec3::Y,
        near: 0.1 * r,
        far: 2.5 * r,
        projection: Projection::Perspective { fov_y_deg: 45.0 },
        shift: glam::Vec2::ZERO,
    };
    let mut scene = Scene::new(width, height, camera);
    // The peers draw aliased frames: so does the row compared with them.
    scene.antialias = kage::scene::Antialias::None;
    scene.lights = vec![peer_light(c, r, mode)?];
    scene.materials = vec![material];
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
                // The peer's fixed map size, like for like.
                resolution: 2048,
                by_need: false,
                pcf: if mode == "shadow4" { 2 } else { 1 },
                ..ShadowSettings::default()
            },
        ),
        _ => return Err(miette!("unknown mode '{mode}' (expected phong, shadow1 or shadow4)")),
    };
    Ok(Light { kind, ambient: 0.1, falloff: Falloff::None, shadow, ..Light::default() })
}

/// Median milliseconds per frame of a renderer re-rendering `scene` (after
/// one warm-up frame), its stages' medians, and the last image; shadow maps
/// kept between frames only if `keep_maps`.
fn time_kage(name: &str, scene: &Scene, frames: usize, keep_maps: bool) -> Result<(Row, LinearImage)> {
    let options = RenderOptions { keep_shadow_maps: keep_maps, ..RenderOptions::default() };
    let mut renderer = Renderer::new(&options).map_err(|e| miette!("{e}"))?;
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
        visibility_ms: median(&mut vis),
        shadow_ms: median(&mut shadow),
        shading_ms: median(&mut shade),
        total_ms: median(&mut total),
        peer: None,
    };
    Ok((row, frame.image))
}

/// Runs llvmpipe on the same mesh; returns its median ms and the RMSE (0-255
/// scale) between its image and kage's.
fn run_llvmpipe(
    bin: &Path,
    mesh: &Path,
    common: &Common,
    mode: &str,
    ours: &LinearImage,
) -> Result<(f64, Option<f64>)> {
    let prefix = std::env::temp_dir().join("kage_bench_llvmpipe");
    let (w, h, f) = (common.width.to_string(), common.height.to_string(), common.frames.to_string());
    let out = Command::new(bin)
        .env("LP_NUM_THREADS", "2")
        .args(["-w", &w, "-h", &h, "-f", &f, "-m", mode, "-o"])
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

/// RMSE (0-255 scale) between the PNG `png` and kage's image.
fn rmse_against(png: &Path, ours: &LinearImage) -> Option<f64> {
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

fn print_table(rows: &[Row], args: &RasterArgs) {
    println!("| scene, mode | triangles | visibility ms | shadow map ms | shading ms | kage ms/frame | llvmpipe ms/frame | kage / llvmpipe | RMSE vs llvmpipe (0-255) |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let (peer, ratio, rmse) = match r.peer {
            Some((ms, rmse)) => (
                format!("{ms:.1}"),
                format!("{:.2}", r.total_ms / ms),
                rmse.map_or("n/a".into(), |e| format!("{e:.2}")),
            ),
            None if r.name.contains("kept") => ("-".into(), "not like for like".into(), "-".into()),
            None => ("not built".into(), "n/a".into(), "n/a".into()),
        };
        println!(
            "| {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {peer} | {ratio} | {rmse} |",
            r.name, r.triangles, r.visibility_ms, r.shadow_ms, r.shading_ms, r.total_ms
        );
    }
    println!(
        "\n{}x{}, median of {} frames, best of {} alternating rounds, {} threads.",
        args.common.width,
        args.common.height,
        args.common.frames,
        args.rounds.max(1),
        rayon::current_num_threads()
    );
}

/// Milliseconds per frame as the number of lights grows, with and without shadow
/// maps: seed 002's "a light is only more passes" says the cost is linear.
pub fn run_lights(args: &LightsArgs) -> Result<()> {
    let common = &args.common;
    let name = args.meshes.scenes.split(',').next().unwrap_or("sphere100k").trim();
    let mesh = ensure_mesh(common, &args.meshes, name)?;
    let base = peer_scene(&mesh, common.width, common.height, "shadow1")?;
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
            let (row, _) = time_kage(name, &scene, common.frames, true)?;
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
        "\n{name}, {}x{}, spot lights on a ring above the mesh (intensity 1/n each), maps kept between frames where \
         they fit the 64 MB budget of the first pass, median of {} frames, {} threads.",
        common.width,
        common.height,
        common.frames,
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

/// The peers' scene around `path`, for the ray benchmarks.
pub fn peer_scene_for_rays(common: &Common, meshes: &Meshes, name: &str) -> Result<(PathBuf, Scene)> {
    let mesh = ensure_mesh(common, meshes, name)?;
    let scene = peer_scene(&mesh, common.width, common.height, "phong")?;
    Ok((mesh, scene))
}
