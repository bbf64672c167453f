//! Mesh and texture files: Wavefront OBJ + MTL, STL (binary and ASCII), glTF 2.0,
//! OFF (as OpenSCAD writes it);
//! and OpenSCAD `.csg` files ([`crate::csg::openscad`] reads the solid).
//! [`InputFormat`] is the one table of which extension names which format.
//!
//! Each loader turns a file into a [`LoadedModel`]: parts (a mesh with an optional
//! material of its own and a placement), solids (an OpenSCAD file's CSG solid
//! and its colours), and for glTF the file's camera and lights (for OpenSCAD its
//! camera sidecar's, or OpenSCAD's default view).
//! Files are read through an [`AssetSource`], so the built-in demo scene can be
//! served from bytes compiled into the binary.

mod format;
mod gltf;
mod obj;
mod off;
mod openscad;
mod stl;

use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Vec3};

use super::mesh::{Mesh, MeshRepairs};
use super::{Light, Material, Texture, Up};
use crate::camera::Camera;
use crate::csg::openscad::CsgOptions;
use crate::csg::CsgSolid;
use crate::error::{Error, Result};
use crate::limits::{Limit, Limits};

pub use format::InputFormat;

/// Where scene files find the files they name.
pub trait AssetSource: Sync {
    /// Reads a file named relative to the scene.
    fn read(&self, path: &Path) -> io::Result<Vec<u8>>;
    /// Reads a file of at most `max` bytes; a longer one is an error of
    /// kind [`io::ErrorKind::FileTooLarge`] holding a [`FileTooLarge`], found
    /// without reading more than `max + 1` bytes where the source can (a
    /// path may name `/dev/zero`). By default [`AssetSource::read`], measured.
    fn read_at_most(&self, path: &Path, max: u64) -> io::Result<Vec<u8>> {
        let bytes = self.read(path)?;
        FileTooLarge::check(bytes.len() as u64, max)?;
        Ok(bytes)
    }
    /// The path a user should see for `path` in messages.
    fn display_path(&self, path: &Path) -> PathBuf;
    /// The folder on disk relative paths start from, if files live on disk.
    fn base_dir(&self) -> Option<&Path> {
        None
    }
    /// A file that exists under `path` spelled in another letter case (files
    /// named on one system and unpacked on another), if there is exactly one.
    fn find_ignoring_case(&self, _path: &Path) -> Option<PathBuf> {
        None
    }
}

/// The payload of an [`io::ErrorKind::FileTooLarge`] error from
/// [`AssetSource::read_at_most`]: how long the file is (or at least is).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileTooLarge {
    /// Its length in bytes, as far as it was read.
    pub bytes: u64,
}

impl FileTooLarge {
    /// `Ok` when `bytes` ≤ `max`, else the error.
    ///
    /// # Errors
    ///
    /// An [`io::ErrorKind::FileTooLarge`] error holding `bytes`.
    pub fn check(bytes: u64, max: u64) -> io::Result<()> {
        if bytes <= max {
            return Ok(());
        }
        Err(io::Error::new(io::ErrorKind::FileTooLarge, FileTooLarge { bytes }))
    }
}

impl std::fmt::Display for FileTooLarge {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the file holds {} bytes or more", self.bytes)
    }
}

impl std::error::Error for FileTooLarge {}

/// Files on disk, relative to a base folder (the scene file's).
#[derive(Debug, Clone)]
pub struct FileSystem {
    /// Folder relative paths start from.
    pub base: PathBuf,
}

impl AssetSource for FileSystem {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        std::fs::read(self.base.join(path))
    }
    /// Reads a regular file only: a device (`/dev/zero`), pipe or folder
    /// named as a mesh or texture is refused before anything is read, and
    /// so is a file the file system says is longer than `max`.
    fn read_at_most(&self, path: &Path, max: u64) -> io::Result<Vec<u8>> {
        use std::io::Read;
        let path = self.base.join(path);
        let meta = std::fs::metadata(&path)?;
        if !meta.is_file() {
            return Err(io::Error::new(io::ErrorKind::InvalidInput, "not a regular file (a device, pipe or folder)"));
        }
        FileTooLarge::check(meta.len(), max)?;
        let mut bytes = Vec::new();
        std::fs::File::open(&path)?.take(max.saturating_add(1)).read_to_end(&mut bytes)?;
        FileTooLarge::check(bytes.len() as u64, max)?;
        Ok(bytes)
    }
    fn display_path(&self, path: &Path) -> PathBuf {
        self.base.join(path)
    }
    fn base_dir(&self) -> Option<&Path> {
        Some(&self.base)
    }
    fn find_ignoring_case(&self, path: &Path) -> Option<PathBuf> {
        let mut found = PathBuf::new();
        for part in path.components() {
            let std::path::Component::Normal(name) = part else {
                found.push(part);
                continue;
            };
            if self.base.join(&found).join(name).exists() {
                found.push(name);
                continue;
            }
            let want = name.to_str()?.to_lowercase();
            let mut matches = std::fs::read_dir(self.base.join(&found))
                .ok()?
                .filter_map(|e| e.ok()?.file_name().into_string().ok())
                .filter(|n| n.to_lowercase() == want);
            let first = matches.next()?;
            if matches.next().is_some() {
                return None; // ambiguous
            }
            found.push(first);
        }
        Some(found)
    }
}

/// Files compiled into the binary, looked up by file name.
#[derive(Debug, Clone, Copy)]
pub struct Embedded(pub &'static [(&'static str, &'static [u8])]);

impl AssetSource for Embedded {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        self.0.iter().find(|(n, _)| *n == name).map(|(_, b)| b.to_vec()).ok_or_else(|| {
            io::Error::new(io::ErrorKind::NotFound, format!("'{name}' is not one of the built-in files"))
        })
    }
    fn display_path(&self, path: &Path) -> PathBuf {
        Path::new("<builtin>").join(path)
    }
}

/// Files held in memory, by the path a scene names them with: a scene and
/// its files handed over whole (dropped into a viewer, built by a test or a
/// fuzzer), read without touching the disk.
#[derive(Debug, Clone, Default)]
pub struct InMemory {
    /// Each file's bytes.
    pub files: HashMap<PathBuf, Vec<u8>>,
}

impl AssetSource for InMemory {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        self.files.get(path).cloned().ok_or_else(|| {
            io::Error::new(io::ErrorKind::NotFound, format!("'{}' is not among the files given", path.display()))
        })
    }
    fn display_path(&self, path: &Path) -> PathBuf {
        path.to_path_buf()
    }
}

/// One mesh of a model, with its own material if the file gave one.
#[derive(Debug, Clone)]
pub struct Part {
    /// Name from the file (object, group or glTF mesh name).
    pub name: String,
    /// Geometry.
    pub mesh: Arc<Mesh>,
    /// Material from the file, if any.
    pub material: Option<Material>,
    /// Placement inside the model (glTF node transforms).
    pub transform: Affine3A,
    /// An OpenSCAD `#` or `%` part drawn see-through over the model: it
    /// casts no shadow, and a viewer may hide it ([`crate::scene::Object::ghost`]).
    pub ghost: bool,
}

/// One CSG solid of a model (an OpenSCAD `.csg` file), with the materials its
/// primitives' colours make.
#[derive(Debug, Clone)]
pub struct SolidPart {
    /// Name (the file's).
    pub name: String,
    /// The solid.
    pub solid: Arc<CsgSolid>,
    /// The distinct materials of its primitives.
    pub palette: Vec<Material>,
    /// Per primitive: index into `palette`.
    pub materials: Vec<usize>,
}

/// Everything a model file contributes to a scene.
#[derive(Debug, Clone, Default)]
pub struct LoadedModel {
    /// Meshes.
    pub parts: Vec<Part>,
    /// CSG solids.
    pub solids: Vec<SolidPart>,
    /// The file's first camera (glTF), already placed in the model's space.
    pub camera: Option<Camera>,
    /// The file's lights (glTF `KHR_lights_punctual`).
    pub lights: Vec<Light>,
    /// What the loader repaired or ignored.
    pub warnings: Vec<String>,
    /// The up axis its format's files use: z for STL and OpenSCAD, y for
    /// OBJ and glTF.
    pub up: Up,
}

impl LoadedModel {
    /// A model of one mesh without a material.
    #[must_use]
    pub fn single(mesh: Mesh) -> LoadedModel {
        let part = Part {
            name: "mesh".into(),
            mesh: Arc::new(mesh),
            material: None,
            transform: Affine3A::IDENTITY,
            ghost: false,
        };
        LoadedModel { parts: vec![part], ..Default::default() }
    }

    /// Bounds of all parts in model space.
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let meshes = self.parts.iter().map(|p| {
            let (a, b) = p.mesh.bounds();
            let (a, b) = (p.transform.transform_point3(a), p.transform.transform_point3(b));
            (a.min(b), a.max(b))
        });
        let solids = self.solids.iter().filter_map(|s| s.solid.bounds());
        meshes.chain(solids).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
    }

    /// Notes a part's repairs: one warning per file, counting the
    /// zero-area triangles of all its parts (a scene of many objects would
    /// otherwise say it once per object).
    fn note_repairs(&mut self, path: &Path, repairs: MeshRepairs) {
        if repairs.degenerate_triangles == 0 {
            return;
        }
        let (head, tail) = (format!("{}: dropped ", path.display()), " zero-area triangle(s)");
        let earlier = self.warnings.iter_mut().find_map(|w| {
            let count = w.strip_prefix(head.as_str())?.strip_suffix(tail)?.parse::<usize>().ok()?;
            Some((w, count))
        });
        match earlier {
            Some((w, count)) => *w = format!("{head}{}{tail}", count + repairs.degenerate_triangles),
            None => self.warnings.push(format!("{head}{}{tail}", repairs.degenerate_triangles)),
        }
    }
}

/// Loads a model file, choosing the loader by extension (`.csg` files with
/// the default [`CsgOptions`]), within the default [`Limits`].
///
/// # Errors
///
/// As [`model_with`].
pub fn model(path: &Path, assets: &dyn AssetSource) -> Result<LoadedModel> {
    model_with(path, assets, &CsgOptions::default(), &Limits::default())
}

/// Loads a model file, choosing the loader by extension; `.csg` files are read
/// with `csg`. Nothing it asks for may pass `limits`.
///
/// # Errors
///
/// [`Error::Read`] when the file cannot be read, [`Error::MeshLoad`] when it
/// does not parse (or its format is unknown, or it asks for more than a
/// limit allows), [`Error::MeshInvalid`] when its data cannot be drawn, an
/// OpenSCAD file's located [`Error::CsgSyntax`] / [`Error::CsgInvalid`], and
/// [`Error::Limit`] when the file is larger than [`Limit::FileMb`].
pub fn model_with(path: &Path, assets: &dyn AssetSource, csg: &CsgOptions, limits: &Limits) -> Result<LoadedModel> {
    let shown = assets.display_path(path);
    let from = Files { assets, limits };
    let fail = |message: String| Error::MeshLoad { path: shown.clone(), message };
    let bytes = || read(path, assets, limits);
    let model = match InputFormat::from_path(path) {
        Some(InputFormat::Obj) => obj::load(&bytes()?, path, from).map_err(fail)?,
        Some(InputFormat::Stl) => LoadedModel { up: Up::Z, ..stl::load(&bytes()?, limits).map_err(fail)? },
        Some(InputFormat::Off) => LoadedModel { up: Up::Z, ..off::load(&bytes()?, limits).map_err(fail)? },
        Some(InputFormat::Gltf) => gltf::load(&bytes()?, path, from).map_err(fail)?,
        Some(InputFormat::Csg) => {
            let text = String::from_utf8(bytes()?).map_err(|_| fail("the file is not UTF-8 text".into()))?;
            let sidecar = read(&path.with_extension("camera.txt"), assets, limits).ok();
            LoadedModel { up: Up::Z, ..openscad::model((path, &shown), text.into(), sidecar.as_deref(), csg, from)? }
        }
        Some(InputFormat::Scene | InputFormat::Scad) | None => {
            return Err(fail(format!("not a model kage reads; it reads {}", InputFormat::described())));
        }
    };
    Ok(model)
}

/// Where a loader reads the files a model names, and what it may ask for.
#[derive(Clone, Copy)]
struct Files<'a> {
    assets: &'a dyn AssetSource,
    limits: &'a Limits,
}

impl Files<'_> {
    /// [`read`] within these limits.
    fn read(&self, path: &Path) -> Result<Vec<u8>> {
        read(path, self.assets, self.limits)
    }
}

/// Reads a file through `assets`, naming it in the error; refused past
/// [`Limit::FileMb`] (after reading at most one byte more).
///
/// # Errors
///
/// [`Error::Read`], naming the file as `assets` shows it; [`Error::Limit`]
/// when it is too large.
pub fn read(path: &Path, assets: &dyn AssetSource, limits: &Limits) -> Result<Vec<u8>> {
    let shown = || assets.display_path(path);
    assets.read_at_most(path, limits.bytes(Limit::FileMb)).map_err(|source| {
        match source.get_ref().and_then(|e| e.downcast_ref::<FileTooLarge>()) {
            Some(over) => match limits.check_bytes(Limit::FileMb, over.bytes, || format!("{}", shown().display())) {
                Err(e) => Error::Limit(e),
                Ok(()) => Error::Read { path: shown(), source },
            },
            None => Error::Read { path: shown(), source },
        }
    })
}

/// Loads a colour (`srgb`) or data texture, its size checked against
/// [`Limit::TexturePixels`] from the image header before it is decoded.
///
/// # Errors
///
/// [`Error::Read`] when the file cannot be read, [`Error::TextureLoad`] when
/// it does not decode or is too large.
pub fn texture(path: &Path, srgb: bool, assets: &dyn AssetSource, limits: &Limits) -> Result<Arc<Texture>> {
    // OpenEXR and Radiance HDR hold linear values whatever they depict.
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    let srgb = srgb && !matches!(ext.as_str(), "exr" | "hdr");
    let bytes = read(path, assets, limits)?;
    Texture::decode(&bytes, srgb, limits)
        .map(Arc::new)
        .map_err(|message| Error::TextureLoad { path: assets.display_path(path), message })
}

/// A colour (`srgb`) or data texture a model names, found in another letter
/// case when the exact name is absent. A texture that cannot be found or
/// decoded is a warning in `warnings` and comes out as [`placeholder`], so
/// the model still renders and the surface shows what is missing.
pub fn texture_or_placeholder(
    path: &Path,
    srgb: bool,
    assets: &dyn AssetSource,
    limits: &Limits,
    warnings: &mut Vec<String>,
) -> Arc<Texture> {
    match texture(path, srgb, assets, limits) {
        Ok(t) => return t,
        Err(Error::Read { source, .. }) if source.kind() == io::ErrorKind::NotFound => {
            if let Some(other) = assets.find_ignoring_case(path) {
                match texture(&other, srgb, assets, limits) {
                    Ok(t) => return t,
                    Err(e) => warnings.push(format!("{e}; drawn as a magenta checker")),
                }
            } else {
                warnings.push(format!(
                    "texture {} not found; drawn as a magenta checker",
                    assets.display_path(path).display()
                ));
            }
        }
        Err(e) => warnings.push(format!("{e}; drawn as a magenta checker")),
    }
    placeholder()
}

/// The stand-in for a missing texture: an 8 × 8 magenta and grey checker,
/// unmistakable on any model.
#[must_use]
pub fn placeholder() -> Arc<Texture> {
    let texels =
        (0..64).map(|i| if (i % 8 + i / 8) % 2 == 0 { Vec3::new(1.0, 0.0, 1.0) } else { Vec3::splat(0.2) }).collect();
    Arc::new(Texture::from_texels(8, 8, texels))
}

/// Builds a checked mesh, turning problems into a message for the loader's error and
/// recording repairs in `model`.
fn checked(
    model: &mut LoadedModel,
    path: &Path,
    built: Result<(Mesh, MeshRepairs), String>,
    what: &str,
) -> Result<Mesh, String> {
    let (mesh, repairs) = built.map_err(|e| format!("{what}: {e}"))?;
    model.note_repairs(path, repairs);
    Ok(mesh)
}

/// Runs `read`, a dependency's reader, turning a panic inside it into an
/// error naming `reader`: bad input must never take kage down, and where a
/// reader is known to panic on some input the input is checked first; this
/// catches the cases not yet known.
fn contained<T>(reader: &str, read: impl FnOnce() -> T) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(read)).map_err(|panic| {
        let why = panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".into());
        format!("{reader} failed on this file ({why}); the file is malformed or the reader has a bug")
    })
}
