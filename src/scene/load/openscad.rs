//! OpenSCAD `.csg` files as models: the solid [`crate::csg::openscad`] reads,
//! a material per distinct colour, and the camera of the file's sidecar or
//! OpenSCAD's default view.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec3, Vec4};

use super::{Files, InputFormat, LoadedModel, Part, SolidPart};
use crate::csg::openscad::{
    default_view, load_csg_with, sidecar_camera, surface_mesh, CsgOptions, Ghost, GhostKind, Imports, Tinted,
};
use crate::csg::CsgSolid;
use crate::error::Result;
use crate::image::srgb_to_linear;
use crate::scene::mesh::{Mesh, NormalMode};
use crate::scene::Material;

/// OpenSCAD's colour of faces without a `color` (the default "Cornfield"
/// scheme's #f9d72c), sRGB.
const CORNFIELD_FACE: [u8; 3] = [249, 215, 44];

/// The files a `.csg` imports, read through the model's assets relative to
/// the `.csg` file's folder.
struct CsgImports<'a> {
    files: Files<'a>,
    folder: PathBuf,
}

impl Imports for CsgImports<'_> {
    fn mesh(&self, file: &str) -> std::result::Result<(Vec<Vec3>, Vec<[u32; 3]>), String> {
        let path = self.folder.join(file);
        let bytes = self.bytes(file)?;
        let shown = self.files.assets.display_path(&path);
        let fail = |e: String| format!("{}: {e}", shown.display());
        let model = match InputFormat::from_path(&path) {
            Some(InputFormat::Stl) => super::stl::load(&bytes, self.files.limits).map_err(fail)?,
            Some(InputFormat::Obj) => super::obj::load(&bytes, &path, self.files).map_err(fail)?,
            Some(InputFormat::Off) => super::off::load(&bytes, self.files.limits).map_err(fail)?,
            _ => return Err(fail("kage imports .stl, .obj and .off meshes (and .svg and .dxf drawings)".into())),
        };
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        for part in &model.parts {
            let base = positions.len() as u32;
            positions.extend(part.mesh.positions.iter().map(|p| part.transform.transform_point3(*p)));
            triangles.extend(part.mesh.triangles.iter().map(|t| t.map(|i| base + i)));
        }
        Ok((positions, triangles))
    }

    fn bytes(&self, file: &str) -> std::result::Result<Vec<u8>, String> {
        self.files.read(&self.folder.join(file)).map_err(|e| e.to_string())
    }
}

/// A `.csg` file (`path`, read through `assets`; `shown` names it in
/// messages) as a model: its solid, a material per distinct colour
/// (uncoloured primitives get OpenSCAD's face colour), and the camera of its
/// sidecar (the text of `NAME.camera.txt`, if there is one and it reads) or
/// else OpenSCAD's default view. Its `import()` and `surface()` files are
/// read through `assets`, relative to its folder.
pub fn model(
    (path, shown): (&Path, &Path),
    text: Arc<str>,
    sidecar: Option<&[u8]>,
    options: &CsgOptions,
    files: Files,
) -> Result<LoadedModel> {
    let imports = CsgImports { files, folder: path.parent().map(Path::to_path_buf).unwrap_or_default() };
    let loaded = load_csg_with(shown, text, options, files.limits, &imports)?;
    let solid = loaded.solid;
    let camera = sidecar
        .and_then(|b| std::str::from_utf8(b).ok())
        .and_then(sidecar_camera)
        .map(|(c, _, _)| c)
        .or_else(|| solid.bounds().map(default_view));
    let mut palette: Vec<(Vec4, Material)> = Vec::new();
    let default = Vec3::from(CORNFIELD_FACE.map(|c| f32::from(c) / 255.0)).extend(1.0);
    let materials = solid
        .primitives
        .iter()
        .map(|p| {
            let rgba = p.color.unwrap_or(default);
            palette.iter().position(|(c, _)| *c == rgba).unwrap_or_else(|| {
                palette.push((rgba, colour_material(rgba, palette.len())));
                palette.len() - 1
            })
        })
        .collect();
    let name = shown.file_stem().map_or_else(|| "csg".to_string(), |s| s.to_string_lossy().into_owned());
    let mut parts: Vec<Part> = loaded.see_through.iter().filter_map(|t| tinted_part(t, &name)).collect();
    parts.extend(loaded.ghosts.iter().filter_map(|g| ghost_part(g, &name)));
    let part =
        SolidPart { name, solid: Arc::new(solid), palette: palette.into_iter().map(|(_, m)| m).collect(), materials };
    Ok(LoadedModel { solids: vec![part], parts, camera, warnings: loaded.warnings, ..Default::default() })
}

/// A `#` or `%` subtree as a see-through mesh in OpenSCAD's preview colour
/// that casts no shadow; `None` if it has no surface.
fn ghost_part(ghost: &Ghost, model: &str) -> Option<Part> {
    let mark = match ghost.kind {
        GhostKind::Highlight => "#",
        GhostKind::Background => "%",
    };
    let name = format!("{model} {mark} at bytes {}..{}", ghost.source.start, ghost.source.end);
    see_through_part(&ghost.solid, ghost.kind.color(), format!("OpenSCAD {mark}"), name, true)
}

/// A `color()` subtree with an alpha below 1 as a see-through mesh in its
/// colour; `None` if it has no surface.
fn tinted_part(tinted: &Tinted, model: &str) -> Option<Part> {
    let name = format!("{model} colour at bytes {}..{}", tinted.source.start, tinted.source.end);
    see_through_part(&tinted.solid, tinted.color, format!("OpenSCAD colour {}", tinted.color), name, false)
}

/// `solid`'s surface as a two-sided mesh part of colour and opacity `rgba`
/// (a ghost is left out of shadows and turned off by the viewer's key);
/// `None` if it has no surface.
fn see_through_part(solid: &CsgSolid, rgba: Vec4, material: String, name: String, ghost: bool) -> Option<Part> {
    let (positions, triangles) = surface_mesh(solid);
    let mesh = Mesh::new(positions, Vec::new(), Vec::new(), triangles, NormalMode::Flat).ok()?.0;
    let material = Material { name: material, opacity: rgba.w, two_sided: true, ..colour_material(rgba, 0) };
    Some(Part { name, mesh: Arc::new(mesh), material: Some(material), transform: glam::Affine3A::IDENTITY, ghost })
}

/// A plastic-like material of an OpenSCAD colour (sRGB components in 0–1; the
/// alpha is not used here: solids are drawn opaque, and a see-through colour
/// is a part of its own).
fn colour_material(rgba: Vec4, index: usize) -> Material {
    let linear = Vec3::new(srgb_to_linear(rgba.x), srgb_to_linear(rgba.y), srgb_to_linear(rgba.z));
    Material {
        name: format!("csg colour {index}"),
        ka: linear,
        kd: linear,
        ks: Vec3::splat(0.25),
        ..Material::default()
    }
}
