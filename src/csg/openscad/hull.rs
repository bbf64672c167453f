//! Convex polyhedra from points and from faces: `hull()`'s solid, and the
//! planes of a faceted sphere, cylinder or convex `polyhedron`.

use glam::{DVec3, Vec3, Vec4};
use manifold_rust::linalg::Vec3 as MVec3;
use manifold_rust::manifold::Manifold;

use crate::csg::ConvexPolyhedron;

/// The convex hull of `points` as planes; `None` if the points span no volume.
///
/// The hull's triangles come from Manifold's quickhull (robust where points
/// lie on few planes: two mirrored rings of a cone's facets, say), in f64.
/// Each triangle is merged into a plane already found when its three corners
/// lie on it (a flat face of many thin triangles is one plane), largest
/// triangles first; each plane is then recomputed from the corners lying on it
/// ([`face_plane`]) and the planes are sorted, so the same points give the
/// same polyhedron, bit for bit, in any order.
#[must_use]
pub(crate) fn convex_hull(points: &[Vec3]) -> Option<ConvexPolyhedron> {
    let size = f64::from(bounds_size(points));
    if points.len() < 4 || size.is_nan() || size <= 0.0 {
        return None;
    }
    let (mut corners, triangles) = hull_mesh(points.iter().map(|p| p.as_dvec3()));
    let triangles: Vec<[DVec3; 3]> = triangles.iter().map(|t| t.map(|k| corners[k])).collect();
    if triangles.len() < 4 {
        return None;
    }
    corners.sort_by(|a, b| a.to_array().partial_cmp(&b.to_array()).unwrap_or(std::cmp::Ordering::Equal));
    corners.dedup();
    let centroid = corners.iter().copied().sum::<DVec3>() / corners.len() as f64;
    let mut triangles: Vec<(f64, DVec3, [DVec3; 3])> = triangles
        .into_iter()
        .filter_map(|[a, b, c]| {
            let cross = (b - a).cross(c - a);
            let n = cross.try_normalize()?;
            Some((cross.length(), if n.dot(a - centroid) < 0.0 { -n } else { n }, [a, b, c]))
        })
        .collect();
    triangles.sort_by(|x, y| y.0.total_cmp(&x.0));
    let eps = 1e-6 * size;
    let mut found: Vec<(DVec3, f64)> = Vec::new();
    for (_, n, tri) in triangles {
        let on = |(m, d): &(DVec3, f64)| m.dot(n) > 0.99 && tri.iter().all(|v| (m.dot(*v) - d).abs() < eps);
        if !found.iter().any(on) {
            found.push((n, n.dot(tri[0])));
        }
    }
    let mut planes: Vec<Vec4> = found
        .iter()
        .filter_map(|&(n, d)| {
            let on: Vec<DVec3> = corners.iter().copied().filter(|v| (n.dot(*v) - d).abs() < eps).collect();
            face_plane(&on, n, centroid)
        })
        .map(|(n, d)| n.as_vec3().extend(d as f32))
        .collect();
    planes.sort_by(|a, b| a.to_array().partial_cmp(&b.to_array()).unwrap_or(std::cmp::Ordering::Equal));
    planes.dedup();
    (planes.len() >= 4).then(|| ConvexPolyhedron { planes, vertices: corners.iter().map(|c| c.as_vec3()).collect() })
}

/// The hull of `points` as Manifold's quickhull makes it, in f64: its corners
/// and its triangles (indices into the corners, wound outwards).
#[must_use]
pub(super) fn hull_mesh(points: impl Iterator<Item = DVec3>) -> (Vec<DVec3>, Vec<[usize; 3]>) {
    let input: Vec<MVec3> = points.map(|p| MVec3::new(p.x, p.y, p.z)).collect();
    let mesh = Manifold::hull(&input).get_mesh_gl64(0);
    let stride = (mesh.num_prop as usize).max(3);
    let corners = mesh.vert_properties.chunks_exact(stride).map(DVec3::from_slice).collect();
    let triangles = mesh.tri_verts.chunks_exact(3).map(|t| [t[0], t[1], t[2]].map(|k| k as usize)).collect();
    (corners, triangles)
}

/// The plane of a convex face from its corners `on` (sorted, so the result
/// depends on the set alone): the corners taken in order round their centre
/// (seen along the face's rough normal `rough`), the normal by Newell's
/// method, turned away from the solid's `centroid`, through their centre.
fn face_plane(on: &[DVec3], rough: DVec3, centroid: DVec3) -> Option<(DVec3, f64)> {
    let centre = on.iter().copied().sum::<DVec3>() / on.len() as f64;
    let u = (*on.first()? - centre).try_normalize()?;
    let v = rough.cross(u);
    let mut ring: Vec<(f64, DVec3)> = on.iter().map(|&p| ((p - centre).dot(v).atan2((p - centre).dot(u)), p)).collect();
    ring.sort_by(|a, b| a.0.total_cmp(&b.0));
    let normal: DVec3 = (0..ring.len())
        .map(|k| {
            let (a, b) = (ring[k].1, ring[(k + 1) % ring.len()].1);
            DVec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y))
        })
        .sum();
    let n = normal.try_normalize()?;
    let n = if n.dot(centre - centroid) < 0.0 { -n } else { n };
    Some((n, n.dot(centre)))
}

/// The largest side of the points' bounding box.
#[must_use]
pub(crate) fn bounds_size(points: &[Vec3]) -> f32 {
    let (lo, hi) = points.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), &p| (a.min(p), b.max(p)));
    (hi - lo).max_element()
}

/// The planes of `faces` (any winding; each turned to face away from the points'
/// centroid, which lies inside a convex solid), normals by Newell's method.
/// Faces of zero area are dropped.
#[must_use]
pub(crate) fn convex_from_faces(vertices: Vec<Vec3>, faces: &[Vec<usize>]) -> ConvexPolyhedron {
    let centroid = vertices.iter().copied().sum::<Vec3>() / vertices.len().max(1) as f32;
    let planes = faces
        .iter()
        .filter_map(|f| {
            let normal: Vec3 = (0..f.len())
                .map(|k| {
                    let (a, b) = (vertices[f[k]], vertices[f[(k + 1) % f.len()]]);
                    Vec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y))
                })
                .sum();
            let n = normal.try_normalize()?;
            let centre = f.iter().map(|&i| vertices[i]).sum::<Vec3>() / f.len() as f32;
            let n = if n.dot(centre - centroid) < 0.0 { -n } else { n };
            Some(n.extend(n.dot(centre)))
        })
        .collect();
    ConvexPolyhedron { planes, vertices }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points on the circle of radius `r` about `(x, y)` at height `z`.
    fn ring(n: usize, (x, y): (f32, f32), r: f32, z: f32) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / n as f32;
                Vec3::new(x + r * a.cos(), y + r * a.sin(), z)
            })
            .collect()
    }

    #[test]
    fn a_hull_is_the_same_to_the_bit_whatever_the_order_of_its_points() {
        // A cylinder's two rings (caps of 24 coplanar corners, which a hull
        // splits into triangles in many ways) and a cube.
        let mut points: Vec<Vec3> =
            ring(24, (0.0, 0.0), 3.0, 0.0).into_iter().chain(ring(24, (0.0, 0.0), 2.0, 5.0)).collect();
        points.extend((0..8).map(|k| Vec3::new((k & 1) as f32, (k >> 1 & 1) as f32, (k >> 2) as f32) * 4.0 - 2.0));
        let first = convex_hull(&points).expect("a solid");
        for turn in 1..6 {
            points.rotate_left(turn * 7);
            if turn % 2 == 0 {
                points.reverse();
            }
            let again = convex_hull(&points).expect("a solid");
            assert_eq!(again.planes, first.planes, "after turn {turn}");
        }
        // The top cap is one plane.
        let top: Vec<&Vec4> = first.planes.iter().filter(|p| p.z > 0.999).collect();
        assert!(top.len() == 1 && (top[0].w - 5.0).abs() < 1e-5, "{top:?}");
    }

    #[test]
    fn the_hull_of_two_mirrored_cones_is_a_solid() {
        // Two frustums' rings (60 facets, radius 7 below and 10.5 above) at
        // x = ±51.2, y = 37.2: every corner lies on one of two planes, with
        // mirrored pairs (a quickhull that rounds its first simplex loses it).
        let points: Vec<Vec3> = [51.2, -51.2]
            .into_iter()
            .flat_map(|x| ring(60, (x, 37.2), 7.0, 0.0).into_iter().chain(ring(60, (x, 37.2), 10.5, 3.5)))
            .collect();
        let hull = convex_hull(&points).expect("a solid");
        // The caps are one plane each, and the middle of the slab is inside.
        assert_eq!(hull.planes.iter().filter(|p| p.z.abs() > 0.999).count(), 2);
        assert!(hull.contains(Vec3::new(0.0, 37.2, 1.75), 1e-5));
        assert!(hull.contains(Vec3::new(61.0, 37.2, 3.4), 1e-5) && !hull.contains(Vec3::new(62.0, 37.2, 3.4), 1e-5));
        for &p in &points {
            assert!(hull.contains(p, 1e-3), "{p} outside");
        }
    }

    #[test]
    fn flat_points_make_no_hull() {
        let square = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.5, 0.5, 0.0)];
        assert!(convex_hull(&square).is_none());
    }
}
