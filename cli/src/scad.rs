//! OpenSCAD `.scad` files: turned into the `.csg` kage reads by `openscad -o`
//! (when `openscad` is on the PATH), then read as if that `.csg` sat beside
//! the `.scad`: its `import()` and `surface()` files are found from the
//! `.scad`'s folder, and its errors name the `.scad`, never the temporary file.

use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use kage::scene::load::{self, AssetSource, FileSystem};
use kage::scene::model::{self, ModelOptions};
use kage::Scene;

/// Runs `openscad -o <temporary>.csg scad`: the `.csg` written, in the
/// system's temporary folder (outside any folder the viewer watches); the
/// caller removes it.
///
/// # Errors
///
/// When `openscad` is not on the PATH, or what it says when it fails.
pub fn to_csg(scad: &Path) -> Result<PathBuf, String> {
    let stem = scad.file_stem().and_then(|s| s.to_str()).unwrap_or("model");
    static MADE: AtomicUsize = AtomicUsize::new(0);
    let n = MADE.fetch_add(1, Ordering::Relaxed);
    let csg = std::env::temp_dir().join(format!("kage-{}-{n}-{stem}.csg", std::process::id()));
    let run = std::process::Command::new("openscad").arg("-o").arg(&csg).arg(scad).output();
    match run {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(format!(
            "{}: a .scad file needs OpenSCAD: `openscad` is not on the PATH (install it, or use the .csg \
             that `openscad -o model.csg model.scad` writes)",
            scad.display()
        )),
        Err(e) => Err(format!("{}: openscad: {e}", scad.display())),
        Ok(out) if !out.status.success() || !csg.exists() => {
            let said = String::from_utf8_lossy(&out.stderr);
            let errors: Vec<&str> = said.lines().filter(|l| l.contains("ERROR") || l.contains("WARNING")).collect();
            let shown = if errors.is_empty() { said.trim().to_string() } else { errors.join("\n") };
            Err(format!("{}: openscad failed:\n{shown}", scad.display()))
        }
        Ok(_) => Ok(csg),
    }
}

/// The files of a model read from a `.scad`: the `.csg` OpenSCAD made of it
/// (in the temporary folder) served as `NAME.csg` beside the `.scad`, and
/// every other file from the `.scad`'s folder.
struct ScadFiles {
    folder: FileSystem,
    scad: PathBuf,
    csg: PathBuf,
}

impl ScadFiles {
    /// The name the `.csg` is read by.
    fn csg_name(&self) -> PathBuf {
        Path::new(self.scad.file_name().unwrap_or_default()).with_extension("csg")
    }
}

impl AssetSource for ScadFiles {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        if path == self.csg_name() {
            return std::fs::read(&self.csg);
        }
        self.folder.read(path)
    }

    fn read_at_most(&self, path: &Path, max: u64) -> io::Result<Vec<u8>> {
        if path == self.csg_name() {
            let bytes = std::fs::read(&self.csg)?;
            load::FileTooLarge::check(bytes.len() as u64, max)?;
            return Ok(bytes);
        }
        self.folder.read_at_most(path, max)
    }

    fn display_path(&self, path: &Path) -> PathBuf {
        if path == self.csg_name() {
            let mut shown = self.scad.clone().into_os_string();
            shown.push(" (OpenSCAD's CSG tree of it)");
            return PathBuf::from(shown);
        }
        self.folder.display_path(path)
    }

    fn base_dir(&self) -> Option<&Path> {
        self.folder.base_dir()
    }

    fn find_ignoring_case(&self, path: &Path) -> Option<PathBuf> {
        self.folder.find_ignoring_case(path)
    }
}

/// A `.scad` model as a scene, as [`model::scene_for_model_with`] makes one
/// of a model file: OpenSCAD's `.csg` of it, read from the `.scad`'s folder.
///
/// # Errors
///
/// [`kage::Error::Scene`] when OpenSCAD is missing or fails on the file;
/// otherwise what loading the `.csg` fails with, naming the `.scad`.
pub fn scene_for_scad(scad: &Path, width: u32, height: u32, options: &ModelOptions) -> kage::error::Result<Scene> {
    let csg = to_csg(scad).map_err(kage::Error::Scene)?;
    let folder = scad.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let files = ScadFiles { folder: FileSystem { base: folder.to_path_buf() }, scad: scad.to_path_buf(), csg };
    let loaded = load::model_with(&files.csg_name(), &files, &options.csg, &options.limits);
    std::fs::remove_file(&files.csg).ok();
    model::scene_for_loaded_model(&loaded?, scad, width, height, options)
}
