//! OpenSCAD `.scad` files: turned into the `.csg` kage reads by `openscad -o`
//! (when `openscad` is on the PATH).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

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
