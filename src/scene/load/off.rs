//! OFF (Object File Format), as OpenSCAD reads and writes it: `OFF`, the
//! counts of vertices, faces and edges, the vertices (x y z), then each face
//! as its corner count and corners (a polygon, concave or not, is cut into
//! triangles by [`crate::polygon`]; a colour after the corners is ignored).
//! `#` starts a comment.

use glam::{DVec3, Vec3};

use super::{checked, LoadedModel};
use crate::limits::{Limit, Limits};
use crate::polygon::face_triangles;
use crate::scene::mesh::{Mesh, NormalMode};

/// Parses OFF bytes.
pub fn load(bytes: &[u8], limits: &Limits) -> Result<LoadedModel, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "an OFF file must be text".to_string())?;
    let mut words = text.lines().flat_map(|l| l.split('#').next().unwrap_or("").split_whitespace());
    match words.next() {
        Some(w) if w.ends_with("OFF") => {}
        _ => return Err("an OFF file starts with `OFF`".into()),
    }
    let mut number = |what: &str| -> Result<f64, String> {
        let w = words.next().ok_or_else(|| format!("the file ends before {what}"))?;
        w.parse::<f64>().map_err(|_| format!("`{w}` is not a number ({what})"))
    };
    let count = |v: f64, what: &str| -> Result<usize, String> {
        (v >= 0.0 && v.fract() == 0.0 && v < 1e12)
            .then_some(v as usize)
            .ok_or_else(|| format!("{v} is not a count of {what}"))
    };
    let vertices = count(number("the vertex count")?, "vertices")?;
    let faces = count(number("the face count")?, "faces")?;
    number("the edge count")?;
    limits.check(Limit::Points, vertices as u64, || "the OFF file's vertices".into()).map_err(|e| e.to_string())?;
    limits.check(Limit::Triangles, faces as u64, || "the OFF file's faces".into()).map_err(|e| e.to_string())?;
    let mut positions = Vec::with_capacity(vertices);
    for _ in 0..vertices {
        let p = Vec3::new(number("a vertex")? as f32, number("a vertex")? as f32, number("a vertex")? as f32);
        if !p.is_finite() {
            return Err(format!("vertex {} is not finite", positions.len()));
        }
        positions.push(p);
    }
    let points: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
    let mut triangles = Vec::with_capacity(faces);
    // Faces are read line by line (a colour may follow the corners), after
    // the header's and the vertices' words.
    let lines = text.lines().map(|l| l.split('#').next().unwrap_or("").trim()).filter(|l| !l.is_empty());
    let mut seen = 0usize;
    let mut face = 0usize;
    let header_and_vertices = 4 + 3 * vertices;
    for line in lines {
        let ws: Vec<&str> = line.split_whitespace().collect();
        if seen < header_and_vertices {
            seen += ws.len();
            continue;
        }
        let corners =
            count(ws[0].parse::<f64>().map_err(|_| format!("`{}` is not a corner count", ws[0]))?, "corners")?;
        if ws.len() < 1 + corners {
            return Err(format!("face {face} lists fewer than its {corners} corners"));
        }
        let ix: Vec<u32> = ws[1..=corners]
            .iter()
            .map(|w| w.parse::<u32>().ok().filter(|&i| (i as usize) < vertices))
            .collect::<Option<_>>()
            .ok_or_else(|| format!("face {face} names a vertex that is not one of the {vertices}"))?;
        face_triangles(&points, &ix, &mut triangles);
        face += 1;
    }
    let mut model = LoadedModel::default();
    let built = Mesh::new(positions, Vec::new(), Vec::new(), triangles, NormalMode::Flat);
    let mesh = checked(&mut model, std::path::Path::new("off"), built, "OFF")?;
    Ok(LoadedModel { warnings: model.warnings, ..LoadedModel::single(mesh) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tetrahedron_with_a_square_face_reads() {
        let off = "OFF\n# a pyramid\n5 5 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n4 0 3 2 1\n3 0 1 4 255 0 0\n3 1 2 4\n3 2 3 4\n3 3 0 4\n";
        let m = load(off.as_bytes(), &Limits::default()).unwrap();
        assert_eq!(m.parts[0].mesh.triangles.len(), 6);
        assert!(load(b"OFF\n3 1 0\n0 0 0\n1 0 0\n", &Limits::default()).unwrap_err().contains("ends before"));
        assert!(load(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", &Limits::default())
            .unwrap_err()
            .contains("face 0 names a vertex that is not one of"));
    }

    #[test]
    fn a_concave_face_is_not_fanned() {
        // An L-shaped prism whose ends are six-cornered concave faces: two
        // ends of area 72 and sides of 44 × 8. A fan of an end covers the
        // L's notch and part of the L twice over, so its triangles' areas
        // add up to more than the surface's.
        let off = include_str!("../../../tests/data/openscad/parts/step.off");
        let m = load(off.as_bytes(), &Limits::default()).unwrap();
        let area = m.parts[0].mesh.surface_area();
        assert!((area - (2.0 * 72.0 + 44.0 * 8.0)).abs() < 1e-3, "area {area}");
    }
}
