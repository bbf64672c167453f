//! `kage`: render scenes, models and OpenSCAD files; compare images.
//!
//! Library errors arrive typed; this binary turns them into reports that point at
//! the offending line of a scene file.

mod batch;
mod render;
mod report;
mod scad;
mod tiles;
mod view;

use std::path::PathBuf;

use clap::{Parser, Subcommand};
use kage::image::ToneCurve;

use render::{render_command, RenderArgs};

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
    /// OpenSCAD .csg or .scad); with no input, the built-in demo scene. Also
    /// the frames of a turntable or camera path, and tiles of a frame.
    Render(RenderArgs),
    /// Open a window on a scene file or a model (the demo with none): orbit,
    /// pan and zoom, switch shadow methods and antialiasing, see each pass;
    /// reloads when the file changes. H in the window lists the keys.
    View(view::ViewArgs),
    /// Measure image A against reference B: RMSE, PSNR, max error, share over a
    /// threshold, mask disagreement; optionally write a false-colour difference.
    Compare(CompareArgs),
    /// Put the .exr tiles of one image (`kage render --tile` or `--region`)
    /// back together; refuses tiles from different images, overlapping
    /// tiles and gaps.
    Merge(MergeArgs),
    /// Render every model in a folder (or listed in a text file, one path a
    /// line) into a folder of images: keeps going past files that fail and
    /// names them at the end (exit code 1), skips images newer than their
    /// model (run it again to resume), and can take one share of the files.
    Batch(batch::BatchArgs),
}

#[derive(clap::Args)]
struct MergeArgs {
    /// The tiles (.exr).
    #[arg(required = true)]
    tiles: Vec<PathBuf>,
    /// The whole image: .exr or .pfm (linear), .png or .jpg (8-bit, with the
    /// exposure and tone curve the tiles were rendered with).
    #[arg(short, long)]
    output: PathBuf,
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

fn main() -> miette::Result<()> {
    let cli = Cli::parse();
    // Paths and locations stay on one line, so they can be copied and grepped.
    miette::set_hook(Box::new(|_| Box::new(miette::MietteHandlerOpts::new().wrap_lines(false).build())))?;
    match cli.command {
        Command::Render(args) => render_command(&args),
        Command::Compare(args) => compare_command(&args).map_err(report::to_report),
        Command::Merge(args) => merge_command(&args),
        Command::Batch(args) => batch::run(&args),
        Command::View(args) => view::run(&args).map_err(|e| miette::miette!("{e}")),
    }
}

fn merge_command(args: &MergeArgs) -> miette::Result<()> {
    kage::output::check_output(&args.output).map_err(report::to_report)?;
    let tiles: Vec<tiles::Tile> =
        args.tiles.iter().map(|p| tiles::read_tile(p)).collect::<Result<_, _>>().map_err(|e| miette::miette!("{e}"))?;
    let (exposure, tone) = tiles.first().map(|t| (t.exposure, t.tone)).unwrap_or_default();
    if let Some(t) = tiles.iter().find(|t| t.exposure != exposure || t.tone != tone) {
        miette::bail!(
            "{} was rendered with another exposure or tone curve than {}",
            t.path.display(),
            tiles[0].path.display()
        );
    }
    let whole = tiles::merge(&tiles).map_err(|e| miette::miette!("{e}"))?;
    kage::output::write_image(&whole, &args.output, exposure.scale(&whole), tone).map_err(report::to_report)?;
    eprintln!("wrote {} ({}x{}, from {} tiles)", args.output.display(), whole.width(), whole.height(), tiles.len());
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
        kage::output::write_image(&d, path, 1.0, ToneCurve::Clip)?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;
    use kage::scene::ShadowMethod;
    use kage::Component;

    use super::*;

    /// The help text of `kage SUBCOMMAND --ARG`.
    fn help(subcommand: &str, arg: &str) -> String {
        let cli = Cli::command();
        let sub = cli.find_subcommand(subcommand).unwrap_or_else(|| panic!("no `{subcommand}`"));
        let found = sub.get_arguments().find(|a| a.get_id() == arg).unwrap_or_else(|| panic!("no --{arg}"));
        found.get_help().map(ToString::to_string).unwrap_or_default()
    }

    /// Each option's help names every value the code accepts, so a method
    /// or part added to the library cannot go unmentioned.
    #[test]
    fn help_texts_name_every_value_the_code_accepts() {
        let shadows = help("render", "shadows");
        for name in ShadowMethod::names() {
            assert!(shadows.contains(&format!("`{name}`")), "--shadows does not name `{name}`: {shadows}");
        }
        let aov = help("render", "aov");
        for component in Component::ALL {
            assert!(aov.contains(component.name()), "--aov does not name {}: {aov}", component.name());
        }
        let count = ["one", "two", "three", "four", "five", "six", "seven", "eight", "nine"][Component::ALL.len() - 1];
        assert!(aov.contains(&format!("these {count}")), "--aov all does not say {count}: {aov}");
        let tonemap = help("render", "tonemap");
        for (name, _) in ToneCurve::NAMES {
            assert!(tonemap.contains(&format!("`{name}`")), "--tonemap does not name `{name}`: {tonemap}");
        }
        let script = help("view", "script");
        for (_, usage) in view::script::ACTIONS {
            assert!(script.contains(&format!("`{usage}")), "--script does not show `{usage}`: {script}");
        }
    }
}
