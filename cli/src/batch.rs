//! `kage batch`: an image for every model of a folder or a list, for a
//! catalogue of parts. Each file renders as `kage render FILE` would (with
//! the options after `--`); a file that fails is named at the end and the
//! rest still render; an image newer than its file is kept, so a run that
//! stopped resumes where it stopped; `--shard I/N` takes every N-th file from
//! the I-th, so N machines share a catalogue with nothing to coordinate.

use std::path::{Path, PathBuf};

use clap::Parser;
use kage::scene::load::InputFormat;

use crate::render::{render_command, RenderArgs};
use crate::tiles;

/// `kage batch`.
#[derive(clap::Args)]
pub struct BatchArgs {
    /// A folder (searched with its subfolders for .obj, .stl, .gltf, .glb,
    /// .csg and .scad files) or a text file listing one file a line (a
    /// scene .toml too; relative to the list's folder; # starts a comment).
    input: PathBuf,
    /// Folder for the images (made when missing): each at its file's path
    /// under the input folder, named after the file with `.png` (or
    /// `--format`) added: parts/arm.stl → OUT/parts/arm.stl.png.
    #[arg(short, long)]
    output: PathBuf,
    /// Image format: png, jpg, exr or pfm.
    #[arg(long, default_value = "png")]
    format: String,
    /// Render only share I (from 0) of N: the files whose place in the
    /// sorted list is I modulo N.
    #[arg(long, value_parser = tiles::parse_share, value_name = "I/N")]
    shard: Option<(u32, u32)>,
    /// Render every file, even where its image is newer than it.
    #[arg(long)]
    force: bool,
    /// Options for every render, as `kage render` takes them, after `--`:
    /// e.g. `-- --width 320 --height 240 --orbit 30,20`.
    #[arg(last = true, value_name = "RENDER OPTIONS")]
    render: Vec<String>,
}

/// `kage render`'s arguments alone, to read the options after `--`.
#[derive(Parser)]
#[command(name = "kage render")]
struct RenderOnly {
    #[command(flatten)]
    args: RenderArgs,
}

/// One file of the batch: where it is and the image it makes.
#[derive(Debug, Clone, PartialEq)]
struct Item {
    input: PathBuf,
    image: PathBuf,
}

pub fn run(args: &BatchArgs) -> miette::Result<()> {
    let format = args.format.to_ascii_lowercase();
    if !matches!(format.as_str(), "png" | "jpg" | "jpeg" | "exr" | "pfm") {
        miette::bail!("--format {}: use png, jpg, exr or pfm", args.format);
    }
    // The options are checked once, before any file.
    let options = |input: &Path, image: &Path| {
        let mut argv = vec!["kage render".to_string()];
        argv.extend(args.render.iter().cloned());
        argv.extend(["-o".into(), image.display().to_string(), input.display().to_string()]);
        RenderOnly::try_parse_from(argv).map(|r| r.args)
    };
    options(Path::new("model.stl"), Path::new("model.png"))
        .map_err(|e| miette::miette!("the render options after --: {e}"))?;
    let mut items = items(&args.input, &args.output, &format)?;
    if let Some((i, n)) = args.shard {
        items = items.into_iter().enumerate().filter(|(k, _)| *k as u32 % n == i).map(|(_, it)| it).collect();
    }
    let has_openscad = std::process::Command::new("openscad").arg("--version").output().is_ok();
    let (scad, items): (Vec<Item>, Vec<Item>) =
        items.into_iter().partition(|it| !has_openscad && InputFormat::from_path(&it.input) == Some(InputFormat::Scad));
    if !scad.is_empty() {
        eprintln!("warning: skipping {} .scad files: `openscad` is not on the PATH", scad.len());
    }
    let (stale, fresh): (Vec<Item>, Vec<Item>) = items.into_iter().partition(|it| args.force || !up_to_date(it));
    let bar = indicatif::ProgressBar::new(stale.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} files, {elapsed} (eta {eta}) {msg}")
            .expect("valid template"),
    );
    let mut failed = Vec::new();
    for it in &stale {
        bar.set_message(it.input.display().to_string());
        if let Err(e) = render_one(it, &options) {
            bar.suspend(|| eprintln!("failed: {}: {e}", it.input.display()));
            failed.push((it.input.clone(), e));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let rendered = stale.len() - failed.len();
    eprintln!("{rendered} rendered, {} up to date, {} failed", fresh.len(), failed.len());
    if failed.is_empty() {
        return Ok(());
    }
    for (path, e) in &failed {
        eprintln!("  {}: {}", path.display(), e.lines().next().unwrap_or_default());
    }
    miette::bail!(
        "{} of {} files failed ({rendered} rendered, {} up to date)",
        failed.len(),
        stale.len() + fresh.len(),
        fresh.len()
    )
}

/// Renders one file into a temporary folder beside its image, then moves
/// what it wrote (the image, and its parts with `--aov`) into place: a batch
/// stopped part way leaves no half-written image that looks up to date. A
/// panic is caught and reported as the file's failure.
fn render_one(it: &Item, options: &impl Fn(&Path, &Path) -> Result<RenderArgs, clap::Error>) -> Result<(), String> {
    let folder = it.image.parent().unwrap_or(Path::new("."));
    let partial = folder.join(format!(".kage-partial-{}", std::process::id()));
    std::fs::create_dir_all(&partial).map_err(|e| format!("cannot make {}: {e}", partial.display()))?;
    let name = it.image.file_name().unwrap_or_default();
    let mut args = options(&it.input, &partial.join(name)).map_err(|e| e.to_string())?;
    args.quiet = true;
    let done = std::panic::catch_unwind(|| render_command(&args));
    let result = match done {
        Ok(Ok(())) => move_all(&partial, folder),
        Ok(Err(report)) => Err(format!("{report}")),
        Err(panic) => {
            let what =
                panic.downcast_ref::<String>().cloned().or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()));
            Err(format!("kage crashed on it: {}", what.unwrap_or_default()))
        }
    };
    std::fs::remove_dir_all(&partial).ok();
    result
}

/// Moves every file of folder `from` into folder `to`.
fn move_all(from: &Path, to: &Path) -> Result<(), String> {
    let entries = std::fs::read_dir(from).map_err(|e| format!("cannot read {}: {e}", from.display()))?;
    for entry in entries.flatten() {
        let target = to.join(entry.file_name());
        std::fs::rename(entry.path(), &target).map_err(|e| format!("cannot write {}: {e}", target.display()))?;
    }
    Ok(())
}

/// Whether `it`'s image is newer than its file.
fn up_to_date(it: &Item) -> bool {
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    matches!((modified(&it.input), modified(&it.image)), (Some(i), Some(o)) if o >= i)
}

/// The batch's files, sorted, each with its image's path under `out`.
fn items(input: &Path, out: &Path, format: &str) -> miette::Result<Vec<Item>> {
    let image = |relative: &Path| {
        let name = relative.file_name().and_then(|n| n.to_str()).unwrap_or("model");
        out.join(relative).with_file_name(format!("{name}.{format}"))
    };
    let mut items = Vec::new();
    if input.is_dir() {
        let mut files = Vec::new();
        walk(input, &mut files).map_err(|e| miette::miette!("cannot read the folder {}: {e}", input.display()))?;
        for f in files.into_iter().filter(|f| InputFormat::from_path(f).is_some_and(InputFormat::is_model)) {
            let relative = f.strip_prefix(input).unwrap_or(&f).to_path_buf();
            items.push(Item { image: image(&relative), input: f });
        }
    } else {
        let text =
            std::fs::read_to_string(input).map_err(|e| miette::miette!("cannot read {}: {e}", input.display()))?;
        let base = input.parent().unwrap_or(Path::new("."));
        for line in text.lines().map(|l| l.split('#').next().unwrap_or_default().trim()).filter(|l| !l.is_empty()) {
            let listed = Path::new(line);
            let relative: PathBuf = if listed.is_absolute() {
                listed.file_name().map(PathBuf::from).unwrap_or_default()
            } else {
                listed.components().filter(|c| matches!(c, std::path::Component::Normal(_))).collect()
            };
            items.push(Item { input: base.join(listed), image: image(&relative) });
        }
    }
    items.sort_by(|a, b| a.input.cmp(&b.input));
    items.dedup();
    Ok(items)
}

/// Every file under `folder`, through its subfolders (links are not
/// followed).
fn walk(folder: &Path, files: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(folder)? {
        let entry = entry?;
        let kind = entry.file_type()?;
        if kind.is_dir() {
            walk(&entry.path(), files)?;
        } else if kind.is_file() {
            files.push(entry.path());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_gives_its_models_sorted_with_their_images_beside_each_other() {
        let dir = std::env::temp_dir().join(format!("kage-batch-items-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("b")).unwrap();
        for f in ["b/arm.stl", "a.obj", "notes.txt", "b/arm.obj", "Cargo.toml"] {
            std::fs::write(dir.join(f), "").unwrap();
        }
        let found = items(&dir, Path::new("out"), "png").unwrap();
        let names: Vec<(PathBuf, PathBuf)> =
            found.into_iter().map(|i| (i.input.strip_prefix(&dir).unwrap().to_path_buf(), i.image)).collect();
        assert_eq!(
            names,
            vec![
                ("a.obj".into(), "out/a.obj.png".into()),
                ("b/arm.obj".into(), "out/b/arm.obj.png".into()),
                ("b/arm.stl".into(), "out/b/arm.stl.png".into()),
            ]
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
