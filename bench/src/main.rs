//! `kage-bench`: kage beside other engines on the same jobs, each table printed
//! as Markdown (what `docs/benchmarks.md` holds, with the command that made it).
//!
//! The peers are the programs in `../shared/peers` (Mesa llvmpipe and Embree,
//! built into `target/peers/` by `scripts/build-peers.sh`; OpenSCAD's measured
//! preview times), and the models those of `../shared/assets`; a peer that is
//! not built leaves its columns empty. Per-stage timings that need no peer are
//! criterion benchmarks: `cargo bench -p kage-bench`.

mod aa;
mod ao;
mod csg;
mod openscad;
mod raster;
mod rays;
mod section;
mod share;
mod slb;
mod soft;
mod textures;
mod threads;
mod view;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

/// kage's benchmarks beside other engines, as Markdown tables.
#[derive(Parser)]
#[command(name = "kage-bench", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Milliseconds per frame on the peers' procedural meshes, split into
    /// visibility, shadow maps and shading, beside Mesa llvmpipe (unshadowed,
    /// and with a 2048² shadow map rendered every frame, as llvmpipe does).
    Raster(raster::RasterArgs),
    /// Milliseconds per frame as the lights grow (1, 4, 16, 100 spot lights),
    /// with and without shadow maps.
    Lights(raster::LightsArgs),
    /// BVH build time and primary-ray throughput beside Embree.
    Rays(rays::RaysArgs),
    /// Seed 002 §4's hybrid (item buffer + traced secondary rays) beside the
    /// same image traced entirely by rays.
    Hybrid(rays::HybridArgs),
    /// Antialiasing: the edge pass (seed 004) and jittered passes against a
    /// 256-pass supersampled truth.
    Aa(aa::AaArgs),
    /// Ambient occlusion after the viewer's 64 passes against the reference
    /// renderer's, and what it costs a frame.
    Ao(ao::AoArgs),
    /// Section planes through the OpenSCAD corpus beside OpenSCAD's own
    /// intersection of each part with a box, meshed exactly.
    Section(section::SectionArgs),
    /// CSG solids (seed 003): the scanline walk's visible surfaces beside a ray
    /// per pixel cast at every primitive (the paper's baseline) and BVH rays,
    /// on the OpenSCAD corpus.
    Csg(csg::CsgArgs),
    /// The CSG paper's Tables 1 and 2 on random spheres, scanline beside naive
    /// ray casting.
    CsgRandom(csg::RandomArgs),
    /// The OpenSCAD corpus (parts of public projects): drawn or not, agreement
    /// with OpenSCAD's exact mesh, time to first image beside OpenSCAD's
    /// preview and Manifold's booleans, peak memory.
    Openscad(openscad::OpenscadArgs),
    /// Time to image of `kage render NAME.csg` beside OpenSCAD's preview, and
    /// frames per second when only the camera moves.
    CsgPreview(csg::PreviewArgs),
    /// The shadow maps' share of a frame on the demo, a glTF truck, a scanned
    /// mesh and the median corpus OpenSCAD model, as `kage render FILE` sets
    /// them up.
    ShadowShare(share::ShareArgs),
    /// The silhouette-line buffer (seed 000) beside shadow maps 512² to 16K²
    /// and PCF: misclassified points and boundary RMSE against shadow rays,
    /// bytes, light pass, eye pass and frame milliseconds.
    Slb(slb::SlbArgs),
    /// Soft shadows: seed 001's two maps (the paper's search, the exact
    /// distance transform, depth-aware, on maps or SLBs), PCSS and the
    /// jittered light against the ray-traced area-light truth.
    Soft(soft::SoftArgs),
    /// What textures cost a frame: each textured corpus model beside itself
    /// with its texture maps taken away, its load time and decoded bytes.
    Textures(textures::TexturesArgs),
    /// Each stage's wall time and serial share on the first scenes a user
    /// meets, and Amdahl's frame at 16 threads.
    Threads(threads::ThreadsArgs),
    /// The preview window (`kage view`, under Xvfb) orbiting a scene beside
    /// f3d offscreen on Mesa: launch to first image, ms per frame, time to the
    /// 64-pass image.
    View(view::ViewArgs),
}

/// What every table takes.
#[derive(clap::Args, Debug, Clone)]
pub struct Common {
    /// Timed frames per row (the median is reported).
    #[arg(long, default_value_t = 10)]
    pub frames: usize,
    /// Image width.
    #[arg(long, default_value_t = 1920)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 1080)]
    pub height: u32,
    /// The shared folder: `peers/` (the other engines' programs and notes) and
    /// `assets/` (the corpus of models); default `../shared` beside the
    /// repository, or `$KAGE_SHARED`.
    #[arg(long, env = "KAGE_SHARED", default_value_os_t = default_shared())]
    pub shared: PathBuf,
}

impl Common {
    /// The peers' folder.
    pub fn peers(&self) -> PathBuf {
        self.shared.join("peers")
    }

    /// The corpus of models.
    pub fn assets(&self) -> PathBuf {
        self.shared.join("assets")
    }
}

/// `../shared` beside the repository this crate is built from.
fn default_shared() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared")
}

/// The repository's own files (example scenes), whatever the working folder.
pub fn repository() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The median of `v` (0 when empty).
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// A scene's frames as the shadow tables time them: medians over the frames.
#[derive(Debug, Clone, Copy)]
pub struct FrameTimes {
    /// Wall milliseconds of the frame.
    pub frame: f64,
    /// The shadow stage (maps and per-pixel terms).
    pub shadows: f64,
    /// Shading, the shadow stage aside.
    pub shading: f64,
    /// The share of the shadow stage's wall time during which a worker had
    /// no work ([`kage::idle`]).
    pub shadow_serial: f64,
    /// The same of the whole frame.
    pub frame_serial: f64,
    /// Amdahl's prediction of the frame's milliseconds at 16 threads.
    pub frame_16: f64,
}

/// [`FrameTimes`] of `scene` over `frames` frames after a warm-up, every
/// shadow map rendered again each frame (as a one-shot render does), the
/// workers' idle time measured.
///
/// # Errors
///
/// When the scene does not render.
pub fn frame_times(scene: &kage::Scene, frames: usize) -> miette::Result<FrameTimes> {
    let options = kage::RenderOptions { keep_shadow_maps: false, measure_idle: true, ..Default::default() };
    let mut renderer = kage::Renderer::new(&options).map_err(|e| miette::miette!("{e}"))?;
    renderer.render(scene).map_err(|e| miette::miette!("{e}"))?;
    let mut v: [Vec<f64>; 6] = Default::default();
    for _ in 0..frames.max(1) {
        let start = std::time::Instant::now();
        let s = renderer.render(scene).map_err(|e| miette::miette!("{e}"))?.stats;
        let frame = s.idle.frame();
        let row = [
            start.elapsed().as_secs_f64() * 1e3,
            s.shadow_ms,
            s.shading_ms,
            s.idle.shadows.serial_share(),
            frame.serial_share(),
            frame.predicted(16),
        ];
        v.iter_mut().zip(row).for_each(|(v, x)| v.push(x));
    }
    let [frame, shadows, shading, shadow_serial, frame_serial, frame_16] = v.map(|mut v| median(&mut v));
    Ok(FrameTimes { frame, shadows, shading, shadow_serial, frame_serial, frame_16 })
}

fn main() -> miette::Result<()> {
    match Cli::parse().command {
        Command::Raster(args) => raster::run(&args),
        Command::Lights(args) => raster::run_lights(&args),
        Command::Rays(args) => rays::run(&args),
        Command::Hybrid(args) => rays::run_hybrid(&args),
        Command::Aa(args) => aa::run(&args),
        Command::Ao(args) => ao::run(&args),
        Command::Section(args) => section::run(&args),
        Command::Csg(args) => csg::run(&args),
        Command::CsgRandom(args) => csg::run_random(&args),
        Command::CsgPreview(args) => csg::run_preview(&args),
        Command::Openscad(args) => openscad::run(&args),
        Command::ShadowShare(args) => share::run(&args),
        Command::Slb(args) => slb::run(&args),
        Command::Soft(args) => soft::run(&args),
        Command::Textures(args) => textures::run(&args),
        Command::Threads(args) => threads::run(&args),
        Command::View(args) => view::run(&args),
    }
}
