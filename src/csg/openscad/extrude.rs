//! `linear_extrude()` and `rotate_extrude()` as unions of convex polyhedra:
//! each convex piece of the region ([`super::partition`]) becomes one
//! primitive per slice (a straight extrusion has one slice) or per segment
//! of the revolution.
//!
//! - A straight extrusion of a convex piece, scaled alike in x and y, is the
//!   convex prism between the piece and its scaled copy: OpenSCAD's own mesh,
//!   exactly (its side quads are planar).
//! - A twisted extrusion, or one scaled differently in x and y, has side
//!   quads that are not planar; OpenSCAD splits each into two triangles,
//!   the diagonal chosen by the twist's sense, and the solid is no union of
//!   convex prisms (a twisted triangular prism is Schönhardt's polyhedron,
//!   which no tetrahedra fill). It is OpenSCAD's own mesh, as a closed mesh
//!   primitive ([`Layers::mesh`]).
//! - A revolution of a convex piece between two angles is convex (a point is
//!   `α·u + β·v + z·ẑ` for the two ends' radial directions u and v, with
//!   `(α + β, z)` in the piece and α, β ≥ 0: a linear image of a convex set),
//!   and its corners are OpenSCAD's: each segment is exactly OpenSCAD's mesh.
//!   That is the faceted revolution. The exact one is smooth: a convex piece
//!   revolved a whole turn is the inside of the cones its outer edges sweep
//!   less the cones its inner edges sweep ([`revolution`]), a part turn that
//!   cut by a wedge ([`wedge`]); a few quadrics per piece in place of a
//!   polyhedron per piece and segment.

use glam::{DAffine2, DMat2, DVec2, Vec3};

use manifold_rust::linalg::Vec2 as MVec2;
use manifold_rust::polygon::triangulate;

use super::flat::{signed_area, Region};
use super::hull::convex_from_faces;
use crate::csg::{ClosedMesh, ConvexPolyhedron};

/// The convex polyhedron between a convex counter-clockwise `bottom` at
/// height `z0` and `top` (the same corners moved by a map that keeps the piece
/// convex, or all one point) at `z1`.
#[must_use]
pub(crate) fn slab(bottom: &[DVec2], top: &[DVec2], z0: f64, z1: f64) -> ConvexPolyhedron {
    let n = bottom.len();
    let lift = |p: DVec2, z: f64| Vec3::new(p.x as f32, p.y as f32, z as f32);
    let vertices: Vec<Vec3> = bottom.iter().map(|&p| lift(p, z0)).chain(top.iter().map(|&p| lift(p, z1))).collect();
    let mut faces: Vec<Vec<usize>> = vec![(0..n).rev().collect(), (n..2 * n).collect()];
    faces.extend((0..n).map(|i| vec![i, (i + 1) % n, n + (i + 1) % n, n + i]));
    // A top shrunk to a point (scale 0) leaves a face of no area: dropped.
    convex_from_faces(vertices, &faces)
}

/// How a `linear_extrude()` places its layers: `slices` of height `h` from
/// `z0`, layer k turned by `−twist·k/slices` degrees, then scaled by
/// `1 + (scale − 1)·k/slices`, as OpenSCAD does.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layers {
    pub(crate) z0: f64,
    pub(crate) height: f64,
    pub(crate) twist_deg: f64,
    pub(crate) slices: usize,
    pub(crate) scale: DVec2,
}

impl Layers {
    /// The map of layer `k` (0 the bottom, `slices` the top).
    #[must_use]
    pub(crate) fn map(&self, k: usize) -> DAffine2 {
        let f = k as f64 / self.slices as f64;
        let scale = DVec2::ONE + (self.scale - DVec2::ONE) * f;
        DAffine2::from_mat2(DMat2::from_diagonal(scale) * DMat2::from_angle((-self.twist_deg * f).to_radians()))
    }

    /// The height of layer `k`.
    #[must_use]
    pub(crate) fn z(&self, k: usize) -> f64 {
        self.z0 + self.height * k as f64 / self.slices as f64
    }

    /// Whether each slice of a convex piece is exactly OpenSCAD's mesh: no
    /// twist and the same scale in x and y (planar side quads).
    #[must_use]
    pub(crate) fn prisms(&self) -> bool {
        self.twist_deg == 0.0 && self.scale.x == self.scale.y
    }

    /// The whole extrusion of `region` as OpenSCAD meshes it: each layer's
    /// contours, each side quad split along the diagonal OpenSCAD picks (by
    /// the twist's sense, the other way round for holes; without a twist,
    /// the shorter), the region's triangles as caps (none on top when it is
    /// scaled to a point).
    #[must_use]
    pub(crate) fn mesh(&self, region: &Region) -> Option<ClosedMesh> {
        let contours = region.contours();
        let per_layer: usize = contours.iter().map(Vec::len).sum();
        let mut positions = Vec::with_capacity(per_layer * (self.slices + 1));
        for k in 0..=self.slices {
            let (m, z) = (self.map(k), self.z(k) as f32);
            positions.extend(contours.iter().flatten().map(|p| {
                let q = m.transform_point2(*p);
                Vec3::new(q.x as f32, q.y as f32, z)
            }));
        }
        let index = |k: usize, at: usize| (k * per_layer + at) as u32;
        let mut triangles = Vec::new();
        let pointed = self.scale == DVec2::ZERO;
        for k in 0..self.slices {
            // Twisted: OpenSCAD's `sin(rot1 − rot2) ≥ 0` picks the diagonal
            // (the other one for holes); stretched, the shorter one.
            let f = |k: usize| -self.twist_deg * k as f64 / self.slices as f64;
            let by_twist = (f(k) - f(k + 1)).to_radians().sin() >= 0.0;
            let mut start = 0;
            for c in contours {
                let outer = signed_area(c) > 0.0;
                for i in 0..c.len() {
                    let (p, q) = (start + i, start + (i + 1) % c.len());
                    let (p1, q1, p2, q2) = (index(k, p), index(k, q), index(k + 1, p), index(k + 1, q));
                    let at = |v: u32| positions[v as usize];
                    let p1_q2 = if self.twist_deg == 0.0 {
                        at(p1).distance(at(q2)) <= at(p2).distance(at(q1))
                    } else {
                        by_twist == outer
                    };
                    let top_point = pointed && k + 1 == self.slices;
                    if p1_q2 {
                        triangles.push([p1, q2, q1]);
                        if !top_point {
                            triangles.push([q2, p1, p2]);
                        }
                    } else {
                        triangles.push([p1, p2, q1]);
                        if !top_point {
                            triangles.push([p2, q2, q1]);
                        }
                    }
                }
                start += c.len();
            }
        }
        let flat: Vec<Vec<MVec2>> = contours.iter().map(|c| c.iter().map(|p| MVec2::new(p.x, p.y)).collect()).collect();
        for t in triangulate(&flat, -1.0, true) {
            let t = [t.x, t.y, t.z].map(|i| i as usize);
            triangles.push([index(0, t[0]), index(0, t[2]), index(0, t[1])]);
            if !pointed {
                triangles.push(t.map(|i| index(self.slices, i)));
            }
        }
        ClosedMesh::new(positions, triangles)
    }

    /// The slices of one convex piece.
    pub(crate) fn slabs<'a>(&'a self, piece: &'a [DVec2]) -> impl Iterator<Item = ConvexPolyhedron> + 'a {
        (0..self.slices).map(move |k| {
            let (a, b) = (self.map(k), self.map(k + 1));
            let bottom: Vec<DVec2> = piece.iter().map(|p| a.transform_point2(*p)).collect();
            let top: Vec<DVec2> = piece.iter().map(|p| b.transform_point2(*p)).collect();
            slab(&bottom, &top, self.z(k), self.z(k + 1))
        })
    }
}

/// The segments of a convex `piece` (x ≥ 0) revolved about the z axis:
/// `segments` of them from 0 to `angle_deg` degrees (the profile's x along
/// the radial direction, its y up), each the convex solid between the piece
/// at two neighbouring angles.
pub(crate) fn revolved(
    piece: &[DVec2],
    angle_deg: f64,
    segments: usize,
) -> impl Iterator<Item = ConvexPolyhedron> + '_ {
    let n = piece.len();
    let at = move |k: usize| {
        let a = (angle_deg * k as f64 / segments as f64).to_radians();
        let (s, c) = a.sin_cos();
        piece.iter().map(move |p| Vec3::new((p.x * c) as f32, (p.x * s) as f32, p.y as f32))
    };
    (0..segments).map(move |k| {
        let vertices: Vec<Vec3> = at(k).chain(at(k + 1)).collect();
        let mut faces: Vec<Vec<usize>> = vec![(0..n).collect(), (n..2 * n).collect()];
        faces.extend((0..n).map(|i| vec![i, (i + 1) % n, n + (i + 1) % n, n + i]));
        // Corners on the axis meet themselves: their faces lose a corner
        // and keep their plane (Newell's method over repeated corners).
        convex_from_faces(vertices, &faces)
    })
}

/// A solid frustum about the z axis: radius `r0` at height `z0`, `r1` at
/// `z1` (`z0 < z1`; one radius may be 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Cone {
    pub(crate) z0: f64,
    pub(crate) z1: f64,
    pub(crate) r0: f64,
    pub(crate) r1: f64,
}

/// A convex profile piece revolved a whole turn, exactly: the points inside
/// every cone of `within` and outside every cone of `without`.
///
/// The piece is the intersection of its edges' half-planes. An edge facing
/// away from the axis bounds the radius from above by a line in z, which
/// revolves into a solid cone over the piece's heights; an edge facing the
/// axis bounds it from below, and its revolution is the outside of a cone;
/// a level edge is the piece's top or bottom, which the first cones' heights
/// already hold. A revolved rectangle is a tube: one cylinder less another.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Revolution {
    pub(crate) within: Vec<Cone>,
    pub(crate) without: Vec<Cone>,
}

/// The exact revolution of a convex counter-clockwise `piece` with x ≥ 0
/// (x the radius, y the height), or `None` if it has no area.
#[must_use]
pub(crate) fn revolution(piece: &[DVec2]) -> Option<Revolution> {
    let (z0, z1) = piece.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.y), hi.max(p.y)));
    let reach = piece.iter().fold(0.0f64, |r, p| r.max(p.x));
    let size = (z1 - z0).max(reach);
    if !(z1 - z0 > 1e-9 * size && reach > 1e-9 * size) {
        return None;
    }
    // Cutters reach a little past the piece's heights, so that no face of a
    // cutter lies on a face of what it cuts.
    let margin = 0.01 * (z1 - z0);
    let mut out = Revolution { within: Vec::new(), without: Vec::new() };
    for (i, &a) in piece.iter().enumerate() {
        let b = piece[(i + 1) % piece.len()];
        let d = b - a;
        // The outward normal is (d.y, −d.x): its x says which way the edge faces.
        if d.y.abs() <= 1e-9 * d.length().max(size * 1e-9) {
            continue;
        }
        let radius = |z: f64| a.x + (z - a.y) * d.x / d.y;
        if d.y > 0.0 {
            let (r0, r1) = (radius(z0).max(0.0), radius(z1).max(0.0));
            out.within.push(Cone { z0, z1, r0, r1 });
        } else {
            // The cone's part of positive radius, from z0 − margin to z1 + margin.
            let (mut lo, mut hi) = (z0 - margin, z1 + margin);
            let apex = a.y - a.x * d.y / d.x;
            if d.x != 0.0 && apex > lo && apex < hi {
                if radius(lo) > radius(hi) {
                    hi = apex;
                } else {
                    lo = apex;
                }
            }
            let (r0, r1) = (radius(lo).max(0.0), radius(hi).max(0.0));
            if r0.max(r1) > 1e-9 * size {
                out.without.push(Cone { z0: lo, z1: hi, r0, r1 });
            }
        }
    }
    (!out.within.is_empty()).then_some(out)
}

/// The wedge of space between the half-planes through the z axis at angles
/// `from_deg` and `to_deg` (counter-clockwise, at most 180° apart), inside
/// the box of half-width `reach` about the axis from `z0` to `z1`.
#[must_use]
pub(crate) fn wedge(from_deg: f64, to_deg: f64, reach: f64, z0: f64, z1: f64) -> ConvexPolyhedron {
    let (u, v) = (DVec2::from_angle(from_deg.to_radians()), DVec2::from_angle(to_deg.to_radians()));
    let mut square = vec![
        DVec2::new(-reach, -reach),
        DVec2::new(reach, -reach),
        DVec2::new(reach, reach),
        DVec2::new(-reach, reach),
    ];
    // Keep the side counter-clockwise of u, then the side clockwise of v.
    square = clip(&square, |p| u.perp_dot(p));
    square = clip(&square, |p| p.perp_dot(v));
    slab(&square, &square, z0, z1)
}

/// The part of a convex polygon where `side` ≥ 0 (side linear).
fn clip(polygon: &[DVec2], side: impl Fn(DVec2) -> f64) -> Vec<DVec2> {
    let mut out = Vec::with_capacity(polygon.len() + 1);
    for (i, &a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % polygon.len()];
        let (sa, sb) = (side(a), side(b));
        if sa >= 0.0 {
            out.push(a);
        }
        if (sa >= 0.0) != (sb >= 0.0) {
            out.push(a + (b - a) * (sa / (sa - sb)));
        }
    }
    out.dedup_by(|p, q| p.distance(*q) < 1e-12);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_prism_is_its_piece_between_two_heights() {
        let tri = [DVec2::ZERO, DVec2::new(2.0, 0.0), DVec2::new(0.0, 2.0)];
        let p = slab(&tri, &tri, -1.0, 3.0);
        assert_eq!(p.planes.len(), 5);
        assert!(p.contains(Vec3::new(0.5, 0.5, 2.9), 0.0) && !p.contains(Vec3::new(0.5, 0.5, 3.1), 0.0));
        assert!(!p.contains(Vec3::new(1.1, 1.1, 0.0), 0.0));
        // Scaled to a point: a pyramid.
        let apex = [DVec2::ZERO; 3];
        let q = slab(&tri, &apex, 0.0, 1.0);
        assert_eq!(q.planes.len(), 4);
        assert!(q.contains(Vec3::new(0.2, 0.2, 0.5), 1e-6) && !q.contains(Vec3::new(0.6, 0.6, 0.5), 1e-6));
    }

    #[test]
    fn layers_turn_then_scale_as_openscad_does() {
        // linear_extrude(height = 10, twist = 90, slices = 3, scale = [2, 1]):
        // OpenSCAD puts the square's corner (2, 0) at (2.3094, -1) on layer 1
        // and (0, -2) at (4, -2)... read off its STL.
        let l = Layers { z0: 0.0, height: 10.0, twist_deg: 90.0, slices: 3, scale: DVec2::new(2.0, 1.0) };
        let p = l.map(1).transform_point2(DVec2::new(2.0, 0.0));
        assert!((p - DVec2::new(2.3094, -1.0)).length() < 1e-4, "{p}");
        let q = l.map(3).transform_point2(DVec2::new(2.0, 2.0));
        assert!((q - DVec2::new(4.0, -2.0)).length() < 1e-9, "{q}");
    }

    #[test]
    fn a_revolved_square_segment_is_convex_and_holds_its_ring() {
        // translate([5, 0]) square([1, 2]) revolved in 8 segments.
        let sq = [DVec2::new(5.0, 0.0), DVec2::new(6.0, 0.0), DVec2::new(6.0, 2.0), DVec2::new(5.0, 2.0)];
        let segs: Vec<ConvexPolyhedron> = revolved(&sq, 360.0, 8).collect();
        assert_eq!(segs.len(), 8);
        assert!(segs.iter().all(|s| s.planes.len() == 6));
        let mid = Vec3::new(5.5 * (22.5f32).to_radians().cos(), 5.5 * (22.5f32).to_radians().sin(), 1.0);
        assert!(segs[0].contains(mid, 1e-5) && !segs[1].contains(mid, 1e-5));
        // A piece touching the axis makes a wedge of a cone.
        let tri = [DVec2::ZERO, DVec2::new(3.0, 0.0), DVec2::new(0.0, 3.0)];
        let cone: Vec<ConvexPolyhedron> = revolved(&tri, 90.0, 2).collect();
        assert!(cone[0].contains(Vec3::new(1.0, 0.3, 1.0), 1e-5));
        assert!(!cone[0].contains(Vec3::new(1.0, 0.3, 2.5), 1e-5));
    }
}
