//! OpenSCAD `.csg` files as models: the solid [`crate::csg::openscad`] reads,
//! a material per distinct colour, and the camera of the file's sidecar or
//! OpenSCAD's default view.

use std::path::Path;
use std::sync::Arc;

use glam::{Vec3, Vec4};

use super::{LoadedModel, SolidPart};
use crate::csg::openscad::{default_view, load_csg, sidecar_camera, CsgOptions};
use crate::error::Result;
use crate::image::srgb_to_linear;
use crate::limits::Limits;
use crate::scene::Material;

/// OpenSCAD's colour of faces without a `color` (the default "Cornfield"
/// scheme's #f9d72c), sRGB.
const CORNFIELD_FACE: [u8; 3] = [249, 215, 44];

/// A `.csg` file as a model: its solid, a material per distinct colour
/// (uncoloured primitives get OpenSCAD's face colour), and the camera of its
/// sidecar (the text of `NAME.camera.txt`, if there is one and it reads) or
/// else OpenSCAD's default view.
pub fn model(
    path: &Path,
    text: Arc<str>,
    sidecar: Option<&[u8]>,
    options: &CsgOptions,
    limits: &Limits,
) -> Result<LoadedModel> {
    let loaded = load_csg(path, text, options, limits)?;
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
    let name = path.file_stem().map_or_else(|| "csg".to_string(), |s| s.to_string_lossy().into_owned());
    let part =
        SolidPart { name, solid: Arc::new(solid), palette: palette.into_iter().map(|(_, m)| m).collect(), materials };
    Ok(LoadedModel { solids: vec![part], camera, warnings: loaded.warnings, ..Default::default() })
}

/// A plastic-like material of an OpenSCAD colour (sRGB components in 0–1; the
/// alpha is not used: solids are drawn opaque).
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
