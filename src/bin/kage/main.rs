//! `kage`: render scenes and models, and benchmark the renderer.
//!
//! Library errors arrive typed; this binary turns them into reports that point at
//! the offending line of a scene file.

mod bench;
mod report;

use std::path::{Path, PathBuf};

use clap::{Parser, Subcommand};
use kage::resolve::Exposure;
use kage::scene::{demo::demo_scene, file, Scene};
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
    /// Render a scene file (.toml) or a model (.obj, .stl, .gltf, .glb); with no
    /// input, the built-in demo scene.
    Render(RenderArgs),
    /// Time frames at 1920x1080 on the peers' procedural scenes and print a table.
    Bench(bench::BenchArgs),
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
    /// Brightness of PNG output: stops (e.g. 1.5, -1) or `auto`; overrides the scene.
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    exposure: Option<Exposure>,
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
        Command::Bench(args) => bench::run(&args),
    }
}

fn load(input: Option<&Path>, width: Option<u32>, height: Option<u32>) -> kage::error::Result<Scene> {
    let is_model = |p: &Path| {
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
        matches!(ext.as_str(), "obj" | "stl" | "gltf" | "glb")
    };
    let mut scene = match input {
        None => demo_scene()?,
        Some(p) if is_model(p) => file::scene_for_model(p, width.unwrap_or(960), height.unwrap_or(540))?,
        Some(p) => file::load_scene(p)?,
    };
    scene.width = width.unwrap_or(scene.width);
    scene.height = height.unwrap_or(scene.height);
    Ok(scene)
}

fn render_command(args: &RenderArgs) -> kage::error::Result<()> {
    let scene = load(args.input.as_deref(), args.width, args.height)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let frame = render(&scene, &RenderOptions { threads: args.threads })?;
    let exposure = args.exposure.unwrap_or(scene.exposure).scale(&frame.image);
    kage::output::write_image(&frame.image, &args.output, exposure)?;
    if frame.visibility.items().iter().all(|i| i.is_none()) {
        eprintln!("warning: no object is in view: the image shows only the background (check the camera)");
    }
    let s = frame.stats;
    eprintln!(
        "wrote {} ({}x{}, {} triangles): visibility {:.1} ms, shading {:.1} ms",
        args.output.display(),
        scene.width,
        scene.height,
        s.raster.triangles,
        s.visibility_ms,
        s.shading_ms
    );
    Ok(())
}
