//! Wavefront OBJ with MTL materials, through `tobj`.
//!
//! Polygons are fan-triangulated; OBJ's texture v runs upwards, kage's downwards, so
//! v is flipped. A missing `.mtl` file is a warning (many OBJs name one they never
//! shipped); a missing texture named by an `.mtl` is an error.

use std::io::Cursor;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};

use super::{checked, AssetSource, LoadedModel, Part};
use crate::scene::mesh::{Mesh, NormalMode};
use crate::scene::Material;

/// Parses OBJ bytes; `path` locates the MTL files and textures it names.
pub fn load(bytes: &[u8], path: &Path, assets: &dyn AssetSource) -> Result<LoadedModel, String> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let (models, materials) = tobj::load_obj_buf(&mut Cursor::new(bytes), &options, |mtl| {
        let bytes = assets.read(&dir.join(mtl)).map_err(|_| tobj::LoadError::OpenFileFailed)?;
        tobj::load_mtl_buf(&mut Cursor::new(bytes))
    })
    .map_err(|e| format!("OBJ parse error: {e}"))?;
    let mut out = LoadedModel::default();
    let materials = materials.unwrap_or_else(|e| {
        out.warnings.push(format!("{}: materials not loaded ({e}); using the default material", path.display()));
        Vec::new()
    });
    let materials: Vec<Material> = materials.iter().map(|m| material(m, dir, assets)).collect::<Result<_, _>>()?;
    let mut first_error = None;
    for m in models {
        let built = mesh(&m.mesh);
        let mesh = match checked(&mut out, path, built, &format!("object '{}'", m.name)) {
            Ok(mesh) => mesh,
            Err(e) => {
                out.warnings.push(format!("{}: {e}; skipped", path.display()));
                first_error.get_or_insert(e);
                continue;
            }
        };
        let material = m.mesh.material_id.and_then(|i| materials.get(i).cloned());
        out.parts.push(Part { name: m.name, mesh: Arc::new(mesh), material, transform: Affine3A::IDENTITY });
    }
    if out.parts.is_empty() {
        return Err(first_error.unwrap_or_else(|| "the file has no triangles".into()));
    }
    Ok(out)
}

fn mesh(m: &tobj::Mesh) -> Result<(Mesh, crate::scene::mesh::MeshRepairs), String> {
    let v3 = |a: &[f32]| a.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect::<Vec<_>>();
    let uvs = m.texcoords.chunks_exact(2).map(|c| Vec2::new(c[0], 1.0 - c[1])).collect();
    let triangles = m.indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    Mesh::new(v3(&m.positions), v3(&m.normals), uvs, triangles, NormalMode::Smooth)
}

fn material(m: &tobj::Material, dir: &Path, assets: &dyn AssetSource) -> Result<Material, String> {
    let d = Material::default();
    let v = |c: Option<[f32; 3]>, default: Vec3| c.map_or(default, Vec3::from);
    let map = |name: &Option<String>| -> Result<_, String> {
        name.as_ref()
            .map(|n| crate::scene::load::texture(&dir.join(n.trim()), true, assets).map_err(|e| e.to_string()))
            .transpose()
    };
    let kd = v(m.diffuse, d.kd);
    Ok(Material {
        name: m.name.clone(),
        // Many exporters write Ka = 0 or 1 regardless; treat ambient as following Kd
        // unless the file gives a non-black, non-white value.
        ka: match m.ambient {
            Some(a) if a != [0.0; 3] && a != [1.0; 3] => Vec3::from(a),
            _ => kd,
        },
        kd,
        ks: v(m.specular, d.ks),
        shininess: m.shininess.unwrap_or(d.shininess).max(1.0),
        ke: Vec3::ZERO,
        maps: crate::scene::ComponentMaps {
            // Ka follows Kd, so an untextured ambient would flatten a textured surface.
            ambient: map(&m.ambient_texture.clone().or_else(|| m.diffuse_texture.clone()))?.into_iter().collect(),
            diffuse: map(&m.diffuse_texture)?.into_iter().collect(),
            specular: map(&m.specular_texture)?.into_iter().collect(),
            emission: Vec::new(),
            filter: Default::default(),
        },
        two_sided: false,
        ..Material::default()
    })
}
