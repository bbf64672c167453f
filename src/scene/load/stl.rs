//! STL, binary and ASCII: the format CAD and 3D-printing tools export.
//!
//! STL stores independent facets with no shared vertices, so every part is
//! flat-shaded from its facet geometry (stored facet normals are often wrong and are
//! ignored).

use glam::Vec3;

use super::{checked, LoadedModel};
use crate::limits::{Limit, Limits};
use crate::scene::mesh::{Mesh, NormalMode};

/// Parses STL bytes (binary when the size matches the triangle count, else ASCII
/// if it begins with `solid`; keywords in any letter case).
pub fn load(bytes: &[u8], limits: &Limits) -> Result<LoadedModel, String> {
    let positions = if is_binary(bytes) { binary(bytes, limits)? } else { ascii(bytes)? };
    let triangles = (0..positions.len() as u32 / 3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    let mut model = LoadedModel::default();
    let built = Mesh::new(positions, Vec::new(), Vec::new(), triangles, NormalMode::Flat);
    let mesh = checked(&mut model, std::path::Path::new("stl"), built, "STL")?;
    Ok(LoadedModel { warnings: model.warnings, ..LoadedModel::single(mesh) })
}

/// Binary when the size matches the header's triangle count (a binary
/// header may begin with "solid" too), else ASCII when the text begins with
/// `solid` in any letter case.
fn is_binary(bytes: &[u8]) -> bool {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        if 84 + 50 * n == bytes.len() as u64 {
            return true;
        }
    }
    let text = bytes.trim_ascii_start();
    !(text.len() >= 5 && text[..5].eq_ignore_ascii_case(b"solid"))
}

fn binary(bytes: &[u8], limits: &Limits) -> Result<Vec<Vec3>, String> {
    if bytes.len() < 84 {
        return Err("file too short for a binary STL header".into());
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    limits.check(Limit::Triangles, n as u64, || "the STL header".into()).map_err(|e| e.to_string())?;
    let body = &bytes[84..];
    if body.len() < n.saturating_mul(50) {
        return Err(format!("header promises {n} triangles but the file holds {}", body.len() / 50));
    }
    let f = |o: usize| f32::from_le_bytes([body[o], body[o + 1], body[o + 2], body[o + 3]]);
    Ok((0..n)
        .flat_map(|t| (0..3).map(move |v| 50 * t + 12 + 12 * v))
        .map(|o| Vec3::new(f(o), f(o + 4), f(o + 8)))
        .collect())
}

fn ascii(bytes: &[u8]) -> Result<Vec<Vec3>, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "not a binary STL and not UTF-8 text".to_string())?;
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if !words.next().is_some_and(|w| w.eq_ignore_ascii_case("vertex")) {
            continue;
        }
        let xyz: Vec<f32> =
            words.map(str::parse).collect::<Result<_, _>>().map_err(|e| format!("line {}: {e}", n + 1))?;
        let [x, y, z] = xyz[..] else {
            return Err(format!("line {}: a vertex needs 3 numbers", n + 1));
        };
        out.push(Vec3::new(x, y, z));
    }
    if out.len() % 3 != 0 {
        return Err(format!("{} vertices is not a whole number of facets", out.len()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n";

    #[test]
    fn ascii_and_binary_agree() {
        let a = load(ASCII.as_bytes(), &Limits::default()).unwrap();
        let mut bin = vec![0u8; 80];
        bin.extend(1u32.to_le_bytes());
        bin.extend([0u8; 12]);
        for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
            v.iter().for_each(|c| bin.extend(c.to_le_bytes()));
        }
        bin.extend([0u8; 2]);
        let b = load(&bin, &Limits::default()).unwrap();
        assert_eq!(a.parts[0].mesh.positions, b.parts[0].mesh.positions);
        assert_eq!(a.parts[0].mesh.normals[0], Vec3::Z);
    }

    #[test]
    fn truncated_binary_is_an_error() {
        let mut bin = vec![0u8; 80];
        bin.extend(5u32.to_le_bytes());
        bin.extend([0u8; 60]);
        assert!(load(&bin, &Limits::default()).unwrap_err().contains("promises 5 triangles"));
    }

    #[test]
    fn upper_case_ascii_is_ascii_and_a_solid_header_can_be_binary() {
        // The words' spaces, read as a binary header's count, would promise
        // 538,976,288 triangles.
        let upper = ASCII.to_uppercase().replace("SOLID T", "  SOLID PART").replace("ENDSOLID T", "ENDSOLID PART");
        assert!(upper.len() > 84);
        let a = load(upper.as_bytes(), &Limits::default()).unwrap();
        assert_eq!(a.parts[0].mesh.positions.len(), 3);
        let mut bin = b"solid exported by a CAD tool".to_vec();
        bin.resize(80, b' ');
        bin.extend(1u32.to_le_bytes());
        bin.extend([0u8; 12]);
        for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
            v.iter().for_each(|c| bin.extend(c.to_le_bytes()));
        }
        bin.extend([0u8; 2]);
        assert_eq!(load(&bin, &Limits::default()).unwrap().parts[0].mesh.positions.len(), 3);
    }
}
