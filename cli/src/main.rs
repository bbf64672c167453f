//! `kage`: render scenes, models and OpenSCAD files; compare images.
//!
//! Library errors arrive typed; this binary turns them into reports that point at
//! the offending line of a scene file.

mod report;

use std::path::{Path, PathBuf};

use clap::{Parser, Subcommand};
use kage::csg::openscad::{CsgOptions, Geometry};
use kage::scene::file::{self, ModelOptions};
use kage::scene::{demo::demo_scene, Antialias, EdgeFilter, EdgeMode, EdgeSelection, Exposure, Scene, Up};
use kage::shading::{Component, ComponentSet};
use kage::{render, RenderOptions};

/// A CPU renderer for design previews.
#[derive(Parser)]
#[command(name = "kage", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file (.toml) or a model (.obj, .stl, .gltf, .glb, or an
    /// OpenSCAD .csg); with no input, the built-in demo scene.
    Render(RenderArgs),
    /// Measure image A against reference B: RMSE, PSNR, max error, share over a
    /// threshold, mask disagreement; optionally write a false-colour difference.
    Compare(CompareArgs),
}

#[derive(clap::Args)]
struct CompareArgs {
    /// The image to judge (.png/.jpg read as sRGB, .exr/.pfm as linear).
    a: PathBuf,
    /// The reference image.
    b: PathBuf,
    /// Channel difference above which a pixel counts as differing.
    #[arg(long, default_value_t = 0.01)]
    threshold: f32,
    /// Also compare as masks: a pixel is "on" when its mean channel is above LEVEL.
    #[arg(long)]
    mask: Option<f32>,
    /// Write a false-colour difference image here.
    #[arg(long)]
    diff: Option<PathBuf>,
    /// Difference shown as full red in the difference image.
    #[arg(long, default_value_t = 0.1)]
    diff_scale: f32,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene or model file (omit for the built-in demo).
    input: Option<PathBuf>,
    /// Output image: .png (8-bit sRGB), .exr or .pfm (linear float).
    #[arg(short, long, default_value = "kage.png")]
    output: PathBuf,
    /// Override the image width in pixels.
    #[arg(long)]
    width: Option<u32>,
    /// Override the image height in pixels.
    #[arg(long)]
    height: Option<u32>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Render the ray-traced reference instead of the raster pipeline.
    #[arg(long)]
    reference: bool,
    /// Reference: primary rays per pixel along each axis (n x n per pixel).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    spp: u32,
    /// Reference: shadow rays per light along each axis for lights with a size.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    light_samples: u32,
    /// Reference: no shadow rays (like the raster pipeline before shadows).
    #[arg(long)]
    no_shadows: bool,
    /// Reflection/refraction bounces for materials with `kr`/`kt` (item-buffer
    /// tracing in the raster pipeline, recursion in the reference).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(0..=16))]
    ray_depth: u32,
    /// Antialiasing: `none`; `edge` (seed 004's edge pass over silhouettes, boundaries
    /// and creases), with `:all` for every triangle edge and `:paper` for the paper's
    /// Wu-line weights (e.g. `edge:all:paper`, the paper as written); or `jitter:N`
    /// (N sub-pixel-jittered passes averaged, seed 002 §4). Overrides the scene. The
    /// reference uses --spp instead.
    #[arg(long, value_parser = parse_antialias)]
    antialias: Option<Antialias>,
    /// Also write these components, each on its own (seed 002 Fig. 4), next to the
    /// output as NAME.COMPONENT.EXT: a comma list of ambient, diffuse, specular,
    /// emission (with the background), traced; or `all`. They sum to the image.
    #[arg(long, value_parser = parse_components)]
    aov: Option<ComponentSet>,
    /// Brightness of PNG output: stops (e.g. 1.5, -1) or `auto`; overrides the scene.
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    exposure: Option<Exposure>,
    /// An OpenSCAD .csg model's spheres and cylinders: `exact` quadrics (seed
    /// 003) or `faceted` as OpenSCAD's own mesh ($fn/$fa/$fs), to compare with
    /// OpenSCAD pixel for pixel.
    #[arg(long, value_enum, default_value_t = GeometryArg::Exact)]
    geometry: GeometryArg,
    /// An OpenSCAD .csg model: skip nodes kage cannot render (linear_extrude,
    /// text, import, ...) with a warning instead of failing.
    #[arg(long)]
    skip_unsupported: bool,
    /// A model file: which of its axes points up (default: its format's — z
    /// for STL and OpenSCAD, y for OBJ and glTF).
    #[arg(long, value_enum)]
    up: Option<UpArg>,
    /// A model file: no ground under it.
    #[arg(long)]
    no_ground: bool,
    /// A model file: `framed` (a camera that frames the model) or `file` (the
    /// file's own camera: a glTF camera, an OpenSCAD camera sidecar or
    /// OpenSCAD's default view).
    #[arg(long, value_enum, default_value_t = CameraArg::Framed)]
    camera: CameraArg,
}

/// `--up`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum UpArg {
    /// +y up.
    Y,
    /// +z up.
    Z,
}

/// `--camera`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum CameraArg {
    /// A camera that frames the model.
    Framed,
    /// The file's own camera.
    File,
}

/// `--geometry`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum GeometryArg {
    /// True spheres, cylinders and cones.
    Exact,
    /// OpenSCAD's facets.
    Faceted,
}

/// `out.png` → `out.diffuse.png`.
fn aov_path(output: &Path, name: &str) -> PathBuf {
    let stem = output.file_stem().and_then(|s| s.to_str()).unwrap_or("kage");
    let ext = output.extension().and_then(|e| e.to_str()).unwrap_or("png");
    output.with_file_name(format!("{stem}.{name}.{ext}"))
}

fn parse_components(s: &str) -> Result<ComponentSet, String> {
    if s == "all" {
        return Ok(ComponentSet::ALL);
    }
    let list: Result<Vec<Component>, String> = s
        .split(',')
        .map(|name| {
            Component::from_name(name.trim()).ok_or_else(|| {
                let known: Vec<&str> = Component::ALL.iter().map(|c| c.name()).collect();
                format!("'{name}' is not a component (expected 'all' or some of {})", known.join(", "))
            })
        })
        .collect();
    Ok(ComponentSet::of(&list?))
}

fn parse_antialias(s: &str) -> Result<Antialias, String> {
    let max = kage::scene::settings::MAX_JITTER_SAMPLES;
    let bad = || {
        format!(
            "'{s}' is not an antialiasing method (expected 'none', 'edge' with optional ':all' or ':outline' and \
             ':paper' or ':coverage' (e.g. edge:all:paper), or 'jitter:N', e.g. jitter:8)"
        )
    };
    let mut parts = s.split(':');
    match parts.next() {
        Some("none") if s == "none" => Ok(Antialias::None),
        Some("edge") => {
            let mut mode = EdgeMode::default();
            for p in parts {
                match p {
                    "outline" => mode.selection = EdgeSelection::Outline,
                    "all" => mode.selection = EdgeSelection::All,
                    "coverage" => mode.filter = EdgeFilter::Coverage,
                    "paper" => mode.filter = EdgeFilter::Paper,
                    _ => return Err(bad()),
                }
            }
            Ok(Antialias::Edge(mode))
        }
        Some("jitter") => match s.split_once(':').map(|(_, n)| n.parse::<u32>()) {
            Some(Ok(k @ 1..)) if k <= max => Ok(Antialias::Jitter(k)),
            _ => Err(format!("'{s}' is not jitter:N with N a number of passes between 1 and {max}")),
        },
        _ => Err(bad()),
    }
}

fn parse_exposure(s: &str) -> Result<Exposure, String> {
    match s {
        "auto" => Ok(Exposure::Auto),
        _ => s
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .map(Exposure::Stops)
            .ok_or_else(|| format!("'{s}' is neither a number of stops nor 'auto'")),
    }
}

fn main() -> miette::Result<()> {
    let cli = Cli::parse();
    // Paths and locations stay on one line, so they can be copied and grepped.
    miette::set_hook(Box::new(|_| Box::new(miette::MietteHandlerOpts::new().wrap_lines(false).build())))?;
    match cli.command {
        Command::Render(args) => render_command(&args).map_err(report::to_report),
        Command::Compare(args) => compare_command(&args).map_err(report::to_report),
    }
}

fn load(args: &RenderArgs) -> kage::error::Result<Scene> {
    let is_model = |p: &Path| {
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
        matches!(ext.as_str(), "obj" | "stl" | "gltf" | "glb" | "csg")
    };
    let geometry = match args.geometry {
        GeometryArg::Exact => Geometry::Exact,
        GeometryArg::Faceted => Geometry::Faceted,
    };
    let options = ModelOptions {
        csg: CsgOptions { geometry, skip_unsupported: args.skip_unsupported },
        up: args.up.map(|u| match u {
            UpArg::Y => Up::Y,
            UpArg::Z => Up::Z,
        }),
        ground: !args.no_ground,
        file_camera: args.camera == CameraArg::File,
    };
    let (width, height) = (args.width, args.height);
    let mut scene = match args.input.as_deref() {
        None => demo_scene()?,
        Some(p) if is_model(p) => file::scene_for_model_with(p, width.unwrap_or(960), height.unwrap_or(540), &options)?,
        Some(p) => file::load_scene(p)?,
    };
    scene.width = width.unwrap_or(scene.width);
    scene.height = height.unwrap_or(scene.height);
    Ok(scene)
}

fn render_command(args: &RenderArgs) -> kage::error::Result<()> {
    let mut scene = load(args)?;
    scene.antialias = args.antialias.unwrap_or(scene.antialias);
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if args.reference {
        return reference_command(args, &scene);
    }
    let aovs = args.aov.unwrap_or(ComponentSet::EMPTY);
    let frame = render(
        &scene,
        &RenderOptions { threads: args.threads, ray_depth: args.ray_depth, aovs, ..RenderOptions::default() },
    )?;
    let exposure = args.exposure.unwrap_or(scene.exposure).scale(&frame.image);
    kage::output::write_image(&frame.image, &args.output, exposure)?;
    for (c, image) in &frame.aovs {
        // The same exposure as the final image, so the components add up to it.
        let path = aov_path(&args.output, c.name());
        kage::output::write_image(image, &path, exposure)?;
        eprintln!("wrote {} ({} component)", path.display(), c.name());
    }
    if frame.visibility.items().iter().all(|i| i.is_none()) {
        eprintln!("warning: no object is in view: the image shows only the background (check the camera)");
    }
    let s = frame.stats;
    eprintln!(
        "wrote {} ({}x{}, {} triangles, {} solids, {} pass{}): visibility {:.1} ms, shadow maps {:.1} ms, shading {:.1} ms, traced {:.1} ms ({} pixels)",
        args.output.display(),
        scene.width,
        scene.height,
        s.raster.triangles,
        s.raster.solids,
        s.passes,
        if s.passes == 1 { "" } else { "es" },
        s.visibility_ms,
        s.shadow_ms,
        s.shading_ms,
        s.traced_ms,
        s.traced_pixels
    );
    if let Antialias::Edge(_) = scene.antialias {
        eprintln!("edge pass (seed 004): {:.1} ms, {} pixels blended", s.edge_ms, s.edge_blends);
    }
    Ok(())
}

fn compare_command(args: &CompareArgs) -> kage::error::Result<()> {
    let (a, b) = (kage::output::read_image(&args.a)?, kage::output::read_image(&args.b)?);
    let c = kage::compare::compare(&a, &b, args.threshold)?;
    println!("rmse        {:.6}", c.rmse);
    println!("psnr        {:.2} dB", c.psnr);
    println!("max error   {:.6}", c.max_error);
    println!("over {:<6}  {:.4}% of pixels", args.threshold, 100.0 * c.share_over);
    if let Some(level) = args.mask {
        let m = kage::compare::mask_disagreement(&a, &b, level)?;
        println!("mask @ {level:<4}  {:.4}% of pixels classified differently", 100.0 * m);
    }
    if let Some(path) = &args.diff {
        let d = kage::compare::difference_image(&a, &b, args.diff_scale)?;
        kage::output::write_image(&d, path, 1.0)?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

fn reference_command(args: &RenderArgs, scene: &Scene) -> kage::error::Result<()> {
    use kage::raytrace::reference::{render_reference_until, ReferenceOptions};
    scene.validate()?;
    let opts = ReferenceOptions {
        pixel_samples: args.spp,
        light_samples: args.light_samples,
        shadows: !args.no_shadows,
        max_depth: args.ray_depth,
    };
    let bar = indicatif::ProgressBar::new(scene.height as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("reference {bar:40} {pos}/{len} rows, {elapsed} (eta {eta})")
            .expect("valid template"),
    );
    let start = std::time::Instant::now();
    // Ctrl-C stops tracing new rows; the rows already done are written out.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = stop.clone();
    let _ = ctrlc::set_handler(move || flag.store(true, std::sync::atomic::Ordering::Relaxed));
    let run = || render_reference_until(scene, &opts, &|_| bar.inc(1), &stop);
    let (image, rows) = match kage::frame::thread_pool(args.threads)? {
        Some(pool) => pool.install(run),
        None => run(),
    };
    bar.finish_and_clear();
    if rows < scene.height {
        eprintln!("interrupted: {rows} of {} rows traced; the rest of the image is black", scene.height);
    }
    let exposure = args.exposure.unwrap_or(scene.exposure).scale(&image);
    kage::output::write_image(&image, &args.output, exposure)?;
    eprintln!(
        "wrote {} (ray-traced reference, {2}x{2} rays per pixel, {3}x{3} per area light, shadows {4}): {1:.2} s",
        args.output.display(),
        start.elapsed().as_secs_f64(),
        args.spp,
        args.light_samples,
        if opts.shadows { "on" } else { "off" },
    );
    if rows < scene.height {
        std::process::exit(130); // interrupted, as shells report Ctrl-C
    }
    Ok(())
}
