//! Polygon faces cut into triangles, for every mesh reader that meets faces of
//! more than three corners (OFF, OBJ, OpenSCAD's `polyhedron`).
//!
//! A face may be concave (an L-shaped end of a step, a letter's outline), and
//! its corners need not lie quite in one plane. A convex face is fanned from its
//! first corner; any other is cut by Manifold's ear clipper in the face's own
//! plane (the plane of Newell's normal). A fan of a concave face covers area
//! outside the face and leaves part of it uncovered: a closed mesh read that way
//! is no longer the solid its file describes.
//!
//! Triangles keep the face's winding. A face with no area (all corners on one
//! line, or fewer than three) gives no triangles.

use glam::{DVec2, DVec3};
use manifold_rust::linalg::Vec2 as MVec2;
use manifold_rust::polygon::triangulate;

/// Appends the triangles of `face` (indices into `points`) to `out`.
///
/// # Panics
///
/// If an index of `face` is not an index of `points`.
pub fn face_triangles(points: &[DVec3], face: &[u32], out: &mut Vec<[u32; 3]>) {
    match face.len() {
        0..=2 => {}
        3 => out.push([face[0], face[1], face[2]]),
        _ => {
            let corners: Vec<DVec3> = face.iter().map(|&i| points[i as usize]).collect();
            let Some((u, v)) = face_plane(&corners) else { return };
            let flat: Vec<DVec2> = corners.iter().map(|c| DVec2::new(c.dot(u), c.dot(v))).collect();
            if is_convex(&flat) {
                out.extend((1..face.len() - 1).map(|k| [face[0], face[k], face[k + 1]]));
                return;
            }
            let polygon: Vec<MVec2> = flat.iter().map(|p| MVec2::new(p.x, p.y)).collect();
            for t in triangulate(&vec![polygon], -1.0, true) {
                out.push([t.x, t.y, t.z].map(|k| face[k as usize]));
            }
        }
    }
}

/// Two axes spanning the plane of a face, wound as the face is (so that the
/// face runs counter-clockwise in them); `None` if the face has no area.
fn face_plane(corners: &[DVec3]) -> Option<(DVec3, DVec3)> {
    // Newell's normal: the face's winding, whatever its shape.
    let normal: DVec3 = (0..corners.len()).map(|k| corners[k].cross(corners[(k + 1) % corners.len()])).sum();
    let n = normal.try_normalize()?;
    let u = n.any_orthonormal_vector();
    Some((u, n.cross(u)))
}

/// Whether a counter-clockwise polygon turns left (or runs straight) at every
/// corner and goes round once.
fn is_convex(flat: &[DVec2]) -> bool {
    let n = flat.len();
    let mut turned = 0.0;
    for k in 0..n {
        let a = flat[(k + 1) % n] - flat[k];
        let b = flat[(k + 2) % n] - flat[(k + 1) % n];
        if a.perp_dot(b) < 0.0 {
            return false;
        }
        turned += a.angle_to(b).abs();
    }
    // A star's corners all turn left too, but it goes round more than once.
    turned < std::f64::consts::TAU + 1e-6
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Twice the area of each triangle, signed by `normal`.
    fn areas(points: &[DVec3], tris: &[[u32; 3]], normal: DVec3) -> Vec<f64> {
        tris.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| points[i as usize]);
                (b - a).cross(c - a).dot(normal)
            })
            .collect()
    }

    #[test]
    fn a_concave_face_is_cut_inside_itself() {
        // An L (area 12 * 4 + 4 * 6 = 72) in the plane y = 0, wound so that
        // its normal is -y; a fan from its last corner would cover the notch.
        let l = [(0., 0.), (12., 0.), (12., 4.), (4., 4.), (4., 10.), (0., 10.)];
        let points: Vec<DVec3> = l.iter().map(|&(x, z)| DVec3::new(x, 0.0, z)).collect();
        for start in 0..6u32 {
            let face: Vec<u32> = (0..6).map(|k| (start + k) % 6).collect();
            let mut tris = Vec::new();
            face_triangles(&points, &face, &mut tris);
            assert_eq!(tris.len(), 4, "from corner {start}");
            let a = areas(&points, &tris, -DVec3::Y);
            assert!(a.iter().all(|&x| x > 0.0), "from corner {start}: a triangle is wound against the face: {a:?}");
            assert!((a.iter().sum::<f64>() / 2.0 - 72.0).abs() < 1e-9, "from corner {start}: {a:?}");
        }
    }

    #[test]
    fn a_convex_face_is_fanned_and_a_star_is_not() {
        let square: Vec<DVec3> = [(0., 0.), (1., 0.), (1., 1.), (0., 1.)].map(|(x, y)| DVec3::new(x, y, 0.0)).to_vec();
        let mut tris = Vec::new();
        face_triangles(&square, &[0, 1, 2, 3], &mut tris);
        assert_eq!(tris, [[0, 1, 2], [0, 2, 3]]);
        // A pentagram's corners in star order: every turn is left, but a fan
        // would cover the middle pentagon several times over.
        let star: Vec<DVec3> = (0..5)
            .map(|k| {
                let a = std::f64::consts::TAU * f64::from(k * 2 % 5) / 5.0;
                DVec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        assert!(!is_convex(&star.iter().map(|p| p.truncate()).collect::<Vec<_>>()));
    }

    #[test]
    fn a_face_without_area_gives_nothing() {
        let line: Vec<DVec3> = (0..4).map(|k| DVec3::new(f64::from(k), 0.0, 0.0)).collect();
        let mut tris = Vec::new();
        face_triangles(&line, &[0, 1, 2, 3], &mut tris);
        face_triangles(&line, &[0, 1], &mut tris);
        assert!(tris.is_empty());
    }
}
