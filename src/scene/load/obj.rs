//! Wavefront OBJ with MTL materials, through `tobj`.
//!
//! Polygons, concave or not, are cut into triangles by [`crate::polygon`]; OBJ's texture v runs upwards, kage's downwards, so
//! v is flipped. A missing `.mtl` file is a warning (many OBJs name one they never
//! shipped); a texture named by an `.mtl` is looked up in another letter case
//! when the exact name is absent, and one not found at all is a warning and a
//! magenta checker. [`material`] documents how `illum` maps to kage's materials.

use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, DVec3, Vec2, Vec3};

use super::{checked, Files, LoadedModel, Part};
use crate::error::Error;
use crate::polygon::face_triangles;
use crate::scene::mesh::{Mesh, NormalMode};
use crate::scene::{Material, Texture};

/// Parses OBJ bytes; `path` locates the MTL files and textures it names.
pub(super) fn load(bytes: &[u8], path: &Path, from: Files) -> Result<LoadedModel, String> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let options = tobj::LoadOptions { triangulate: false, single_index: true, ..Default::default() };
    let mtl_warnings = std::cell::RefCell::new(Vec::new());
    let parsed = super::contained("the OBJ reader (tobj)", || {
        tobj::load_obj_buf(&mut Cursor::new(bytes), &options, |mtl| {
            let file = dir.join(mtl);
            let bytes = from.read(&file).map_err(|e| {
                if let Error::Limit(over) = e {
                    mtl_warnings.borrow_mut().push(over.to_string());
                }
                tobj::LoadError::OpenFileFailed
            })?;
            let text = normalised_mtl(&String::from_utf8_lossy(&bytes), &file, &mut mtl_warnings.borrow_mut());
            tobj::load_mtl_buf(&mut Cursor::new(text.as_bytes()))
        })
    });
    let (models, materials) = parsed?.map_err(|e| format!("OBJ parse error: {e}"))?;
    let mut out = LoadedModel::default();
    out.warnings.extend(mtl_warnings.into_inner());
    let materials = materials.unwrap_or_else(|e| {
        out.warnings.push(format!("{}: materials not loaded ({e}); using the default material", path.display()));
        Vec::new()
    });
    // Images several materials name are decoded once.
    let mut decoded = HashMap::new();
    let mut materials: Vec<Material> =
        materials.iter().map(|m| material(m, dir, from, &mut decoded, &mut out.warnings)).collect();
    crate::scene::material::interleave_maps(&mut materials);
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
        out.parts.push(Part {
            name: m.name,
            mesh: Arc::new(mesh),
            material,
            transform: Affine3A::IDENTITY,
            ghost: false,
        });
    }
    if out.parts.is_empty() {
        return Err(first_error.unwrap_or_else(|| "the file has no triangles".into()));
    }
    Ok(out)
}

/// Keys whose values tobj reads as exactly three numbers (and panics on fewer).
const COLOUR_KEYS: [&str; 4] = ["Ka", "Kd", "Ks", "Ke"];

/// Keys whose first value tobj reads as one number (and `illum`, a whole
/// number from 0 to 255).
const NUMBER_KEYS: [&str; 4] = ["Ns", "Ni", "d", "illum"];

/// Keys whose value tobj reads as a file name (and fails on none).
const TEXTURE_KEYS: [&str; 8] = ["map_Ka", "map_Kd", "map_Ks", "map_Bump", "map_bump", "map_Ns", "bump", "map_d"];

/// `text` of MTL file `file` as tobj can read it whole: every colour given by
/// one number written out as three (the MTL format allows `Kd 0.5` for grey);
/// a colour of two numbers, which the format does not allow, taken as grey
/// of the first; a line tobj would refuse (a word that is not a number where
/// one is read, a texture key without a file, a material without a name)
/// left out. Each change but the first is a warning naming the line: one bad
/// line no longer costs the file's other materials.
fn normalised_mtl(text: &str, file: &Path, warnings: &mut Vec<String>) -> String {
    let mut out = String::with_capacity(text.len() + 64);
    for (n, line) in text.lines().enumerate() {
        let at = || format!("{}:{}", file.display(), n + 1);
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("");
        let values: Vec<&str> = words.collect();
        let bad = match key {
            k if COLOUR_KEYS.contains(&k) => values.iter().take(3).find(|v| v.parse::<f32>().is_err()),
            "illum" => values.first().filter(|v| v.parse::<u8>().is_err()),
            k if NUMBER_KEYS.contains(&k) => values.first().filter(|v| v.parse::<f32>().is_err()),
            _ => None,
        };
        if let Some(bad) = bad {
            warnings.push(format!("{}: `{}`: `{bad}` is not a number; the line is ignored", at(), line.trim()));
            continue;
        }
        let nameless = (TEXTURE_KEYS.contains(&key) || key == "newmtl") && values.is_empty();
        if nameless || (NUMBER_KEYS.contains(&key) && values.is_empty()) {
            warnings.push(format!("{}: `{key}` has no value; ignored", at()));
        } else if COLOUR_KEYS.contains(&key) && values.is_empty() {
            warnings.push(format!("{}: `{key}` has no numbers; ignored", at()));
        } else if COLOUR_KEYS.contains(&key) && values.len() < 3 {
            if values.len() == 2 {
                warnings.push(format!(
                    "{}: `{key}` has two numbers (one or three expected); taken as grey {}",
                    at(),
                    values[0]
                ));
            }
            let v = values[0];
            out.push_str(&format!("{key} {v} {v} {v}\n"));
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

fn mesh(m: &tobj::Mesh) -> Result<(Mesh, crate::scene::mesh::MeshRepairs), String> {
    let v3 = |a: &[f32]| a.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect::<Vec<_>>();
    let uvs = m.texcoords.chunks_exact(2).map(|c| Vec2::new(c[0], 1.0 - c[1])).collect();
    let positions = v3(&m.positions);
    let triangles = if m.face_arities.is_empty() {
        m.indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
    } else {
        let points: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
        if m.indices.iter().any(|&i| i as usize >= points.len()) {
            return Err("a face names a vertex the file does not have".into());
        }
        let mut triangles = Vec::with_capacity(m.indices.len());
        let mut at = 0;
        for &n in &m.face_arities {
            let face = m.indices.get(at..at + n as usize).ok_or("a face lists more corners than the file has")?;
            face_triangles(&points, face, &mut triangles);
            at += n as usize;
        }
        triangles
    };
    Mesh::new(positions, v3(&m.normals), uvs, triangles, NormalMode::Smooth)
}

/// A `.mtl` material as kage's. The illumination model `illum` says which of
/// `Ks`, `Tf`, `d` and `Ni` mean what:
///
/// | `illum` | meaning (MTL) | kage |
/// |---|---|---|
/// | 0, 1 | colour, no highlight | `ks` = 0 |
/// | 2 | highlight | Phong `ks` = `Ks` |
/// | 3, 5 | ray-traced reflection (5: with Fresnel) | `kr` = `Ks` |
/// | 4 | glass: see-through, ray-traced reflection | `kr` = `Ks`, opacity `d` |
/// | 6, 7 | refraction (7: with Fresnel) | `kr` = `Ks`, `kt` = `Tf` × (1 − max `Ks`), `ior` = `Ni` |
/// | 8 | reflection from a map, not traced | `km` = `Ks` (the environment) |
/// | 9 | glass, reflection from a map | `km` = `Ks`, opacity `d` |
///
/// Without `illum`, or for any other value, it is model 2. kage has no Fresnel
/// term: models 5 and 7 reflect `Ks` at every angle. Every model takes its
/// opacity from `d` (or 1 − `Tr` when `d` is absent; 0 is read as opaque outside
/// the glass models 4 and 9); `Ke` is the emission. A dissolve map `map_d`
/// is an alpha test: the surface is kept where the image's alpha (or, in a
/// grey image, its grey) is at least one half.
fn material(
    m: &tobj::Material,
    dir: &Path,
    from: Files,
    decoded: &mut HashMap<PathBuf, Arc<Texture>>,
    warnings: &mut Vec<String>,
) -> Material {
    let d = Material::default();
    let v = |c: Option<[f32; 3]>, default: Vec3| c.map_or(default, Vec3::from);
    let mut map = |name: &Option<String>| -> Vec<_> {
        name.iter()
            .map(|n| {
                let path = dir.join(n.trim());
                let texture = decoded.entry(path).or_insert_with_key(|path| {
                    super::texture_or_placeholder(path, true, from.assets, from.limits, warnings)
                });
                Arc::clone(texture)
            })
            .collect()
    };
    let kd = v(m.diffuse, d.kd);
    let ks = v(m.specular, d.ks);
    let extra = |key: &str| {
        m.unknown_param.get(key).map(|v| v.split_whitespace().filter_map(|w| w.parse::<f32>().ok()).collect::<Vec<_>>())
    };
    let tf = match extra("Tf").as_deref() {
        Some([r, g, b, ..]) => Vec3::new(*r, *g, *b),
        Some([t]) => Vec3::splat(*t),
        _ => Vec3::ONE,
    };
    let dissolve = m.dissolve.or_else(|| match extra("Tr").as_deref() {
        Some([t, ..]) => Some(1.0 - t),
        _ => None,
    });
    let opacity = dissolve.filter(|o| o.is_finite()).map_or(1.0, |o| o.clamp(0.0, 1.0));
    let ior = m.optical_density.filter(|n| n.is_finite() && *n >= 1.0).unwrap_or(d.ior);
    let diffuse = map(&m.diffuse_texture);
    // Ka follows Kd, so an untextured ambient would flatten a textured surface.
    let ambient = if m.ambient_texture.is_some() { map(&m.ambient_texture) } else { diffuse.clone() };
    let mut out = Material {
        name: m.name.clone(),
        // Many exporters write Ka = 0 or 1 regardless; treat ambient as following Kd
        // unless the file gives a non-black, non-white value.
        ka: match m.ambient {
            Some(a) if a != [0.0; 3] && a != [1.0; 3] => Vec3::from(a),
            _ => kd,
        },
        kd,
        ks,
        shininess: m.shininess.unwrap_or(d.shininess).max(1.0),
        ke: v(m.emissive, Vec3::ZERO).max(Vec3::ZERO),
        maps: crate::scene::ComponentMaps {
            ambient,
            diffuse,
            specular: map(&m.specular_texture),
            emission: Vec::new(),
            mirror: None,
            roughness: None,
            alpha: None,
            normal: None,
            filter: Default::default(),
        },
        two_sided: false,
        ..Material::default()
    };
    match m.illumination_model {
        Some(0 | 1) => out.ks = Vec3::ZERO,
        Some(3 | 5) => out.kr = ks,
        Some(4) => (out.kr, out.opacity) = (ks, opacity),
        Some(6 | 7) => (out.kr, out.kt, out.ior) = (ks, tf * (1.0 - ks.max_element()).max(0.0), ior),
        Some(8) => out.km = ks,
        Some(9) => (out.km, out.opacity) = (ks, opacity),
        // A dissolve of 0 on an opaque model is an exporter's slip far more
        // often than an invisible surface.
        _ => out.opacity = if opacity > 0.0 { opacity } else { 1.0 },
    }
    // A dissolve map cuts the surface out (leaves, chains, fences): kept
    // where the image's alpha, or its grey where it has none, is at least
    // one half.
    if let Some(mask) = map(&m.dissolve_texture).pop() {
        (out.maps.alpha, out.cutoff) = (Some(Arc::new(mask.coverage())), Some(0.5));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_concave_face_is_cut_inside_itself() {
        // One L-shaped face (area 72) listed from its top corner, from where
        // a fan sweeps across the notch: its triangles' areas would add up
        // to more than the face's.
        let l = [(0., 10.), (0., 0.), (12., 0.), (12., 4.), (4., 4.), (4., 10.)];
        let obj = tobj::Mesh {
            positions: l.iter().flat_map(|&(x, y)| [x, y, 0.0]).collect(),
            indices: (0..6).collect(),
            face_arities: vec![6],
            ..Default::default()
        };
        let area = mesh(&obj).unwrap().0.surface_area();
        assert!((area - 72.0).abs() < 1e-3, "area {area}");
    }

    #[test]
    fn a_bad_line_of_an_mtl_costs_only_that_line() {
        let mtl =
            "newmtl stone\nKa 0.0000 0.0000 0.0000c\nKd 0.5 0.4 0.3\nillum 2x\nmap_Kd\n\nnewmtl wood\nKd 0.6\nNs abc\n";
        let mut warnings = Vec::new();
        let text = normalised_mtl(mtl, Path::new("room.mtl"), &mut warnings);
        let (materials, _) = tobj::load_mtl_buf(&mut Cursor::new(text.as_bytes())).expect("tobj reads what is left");
        assert_eq!(materials.len(), 2);
        assert_eq!(materials[0].diffuse, Some([0.5, 0.4, 0.3]));
        assert_eq!(materials[1].diffuse, Some([0.6, 0.6, 0.6]));
        let lines: Vec<&str> = warnings.iter().map(|w| w.split(": ").next().unwrap()).collect();
        assert_eq!(lines, ["room.mtl:2", "room.mtl:4", "room.mtl:5", "room.mtl:9"], "{warnings:#?}");
        assert!(warnings[0].contains("`0.0000c` is not a number"), "{}", warnings[0]);
    }
}
