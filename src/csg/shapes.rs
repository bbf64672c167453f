//! Where a ray crosses each convex primitive's unit shape (seed 003's
//! procedure 3, "front and back depth at a pixel", in closed form): the unit
//! sphere and frustum (quadrics solved exactly), the unit cube by slabs, and
//! convex polyhedra by their planes — eight planes at a time for polyhedra of
//! many. Each gives the entry and exit parameters with the faces crossed, and
//! the outward normal of a face at a point.

use glam::{Affine3A, Mat3A, Vec3, Vec3A, Vec4};
use wide::f32x8;

use crate::csg::{ConvexPolyhedron, Shape};

/// The (unnormalised) outward normal of a unit shape's face `face` at its
/// point `p`: the sphere's radius; a frustum's side (face [`SIDE`]) or caps
/// ([`BOTTOM`], [`TOP`]); a polyhedron's plane.
pub(super) fn unit_normal(shape: &Shape, face: u32, p: Vec3) -> Vec3 {
    match shape {
        Shape::Sphere => p,
        Shape::Frustum { bottom, top } => match face {
            BOTTOM => Vec3::NEG_Z,
            TOP => Vec3::Z,
            _ => {
                let k = top - bottom;
                Vec3::new(p.x, p.y, -k * (bottom + k * p.z))
            }
        },
        Shape::Polyhedron(poly) => poly.planes[face as usize].truncate(),
        Shape::Mesh { mesh, .. } => mesh.normal(face),
    }
}

/// A frustum's faces ([`unit_normal`]).
pub(super) const SIDE: u32 = 0;
/// See [`SIDE`].
pub(super) const BOTTOM: u32 = 1;
/// See [`SIDE`].
pub(super) const TOP: u32 = 2;

/// The span of the ray `o + t·d` inside a unit shape.
pub(super) fn unit_span(shape: &Shape, o: Vec3, d: Vec3) -> Option<UnitSpan> {
    match shape {
        Shape::Sphere => sphere(o, d),
        Shape::Frustum { bottom, top } => frustum(*bottom, *top, o, d),
        Shape::Polyhedron(poly) => polyhedron(poly, o, d),
        Shape::Mesh { mesh, layer } => mesh.layer_interval(*layer, o, d),
    }
}

/// The inverse transpose of the transform's linear part: carries normals.
pub(super) fn normal_matrix(m: &Affine3A) -> Mat3A {
    m.matrix3.inverse().transpose()
}

/// A span in unit-shape space: entry and exit parameters with their faces
/// ([`unit_normal`]).
pub(super) type UnitSpan = ((f32, u32), (f32, u32));

/// The roots of `a·t² + 2·b·t + c`, smaller first, if real.
pub(super) fn roots(a: f32, b: f32, c: f32) -> Option<(f32, f32)> {
    let disc = b * b - a * c;
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    // The numerically stable pair: no subtraction of nearly equal numbers.
    let q = -(b + b.signum() * disc.sqrt());
    let (r0, r1) = (q / a, c / q);
    Some(if r0 < r1 { (r0, r1) } else { (r1, r0) })
}

/// The unit sphere.
pub(super) fn sphere(o: Vec3, d: Vec3) -> Option<UnitSpan> {
    let (t0, t1) = roots(d.dot(d), o.dot(d), o.dot(o) - 1.0)?;
    Some(((t0, 0), (t1, 0)))
}

/// The frustum `0 ≤ z ≤ 1`, `x² + y² ≤ r(z)²`, `r(z) = bottom + (top − bottom)·z`:
/// the slab between the caps intersected with the quadric's inside, which within
/// the slab is one convex piece (the apex of a cone lies on a cap).
pub(super) fn frustum(bottom: f32, top: f32, o: Vec3, d: Vec3) -> Option<UnitSpan> {
    if bottom == top {
        return cylinder(bottom, o, d);
    }
    let k = top - bottom;
    let slab = slab_z(o, d)?;
    let r_o = bottom + k * o.z;
    // f(t) = x² + y² − r(z)², inside where f ≤ 0.
    let (a, b, c) = (
        d.x * d.x + d.y * d.y - k * k * d.z * d.z,
        o.x * d.x + o.y * d.y - k * d.z * r_o,
        o.x * o.x + o.y * o.y - r_o * r_o,
    );
    const ALL: (f32, f32) = (f32::NEG_INFINITY, f32::INFINITY);
    const NONE: (f32, f32) = (f32::INFINITY, f32::NEG_INFINITY);
    let inside: [(f32, f32); 2] = match roots(a, b, c) {
        // The quadric's inside along the line is between the roots (a > 0) or
        // outside them (a < 0: the line runs steeper than the cone's side).
        Some((r0, r1)) if a > 0.0 => [(r0, r1), NONE],
        Some((r0, r1)) => [(f32::NEG_INFINITY, r0), (r1, f32::INFINITY)],
        // Linear along a line parallel to the cone's side: a half-line.
        None if a == 0.0 && b != 0.0 => {
            let t = -c / (2.0 * b);
            [if b > 0.0 { (f32::NEG_INFINITY, t) } else { (t, f32::INFINITY) }, NONE]
        }
        // No crossing: all inside or all outside, as at any one point.
        None if c <= 0.0 => [ALL, NONE],
        None => return None,
    };
    let ((s0, n0), (s1, n1)) = slab;
    let mut best: Option<UnitSpan> = None;
    for (q0, q1) in inside {
        let enter = if q0 > s0 { (q0, SIDE) } else { (s0, n0) };
        let exit = if q1 < s1 { (q1, SIDE) } else { (s1, n1) };
        if enter.0 < exit.0 {
            best = Some(match best {
                None => (enter, exit),
                Some((e, x)) => (if e.0 <= enter.0 { e } else { enter }, if x.0 >= exit.0 { x } else { exit }),
            });
        }
    }
    best
}

/// [`frustum`] of one radius, a cylinder: the same equations with the
/// cone's slope `k` zero, so the quadric's inside along a line is the one
/// stretch between its roots, or all of a line parallel to the axis within
/// the radius, or nothing.
fn cylinder(radius: f32, o: Vec3, d: Vec3) -> Option<UnitSpan> {
    let ((s0, n0), (s1, n1)) = slab_z(o, d)?;
    let (a, b, c) = (d.x * d.x + d.y * d.y, o.x * d.x + o.y * d.y, o.x * o.x + o.y * o.y - radius * radius);
    let (q0, q1) = match roots(a, b, c) {
        Some(r) => r,
        None if c <= 0.0 => (f32::NEG_INFINITY, f32::INFINITY),
        None => return None,
    };
    let enter = if q0 > s0 { (q0, SIDE) } else { (s0, n0) };
    let exit = if q1 < s1 { (q1, SIDE) } else { (s1, n1) };
    (enter.0 < exit.0).then_some((enter, exit))
}

/// The slab `0 ≤ z ≤ 1` with its caps.
pub(super) fn slab_z(o: Vec3, d: Vec3) -> Option<UnitSpan> {
    if d.z == 0.0 {
        return (0.0..=1.0).contains(&o.z).then_some(((f32::NEG_INFINITY, BOTTOM), (f32::INFINITY, TOP)));
    }
    let (ta, tb) = (-o.z / d.z, (1.0 - o.z) / d.z);
    Some(if d.z > 0.0 { ((ta, BOTTOM), (tb, TOP)) } else { ((tb, TOP), (ta, BOTTOM)) })
}

/// The unit cube ([`ConvexPolyhedron::unit_cube`]) by slabs: per axis, the
/// planes at 0 and 1, one entering and one leaving, each `t` found as
/// [`polyhedron`] finds it from the cube's planes (so the same to the bit, with
/// the same faces), without the dot products.
pub(super) fn unit_cube(o: Vec3, d: Vec3) -> Option<UnitSpan> {
    // Both planes of every axis at once: two vector divisions.
    let (o, d) = (Vec3A::from(o), Vec3A::from(d));
    let (ones, zeros) = ((Vec3A::ONE - o) / d, -o / d);
    let (mut enter, mut exit) = ((f32::NEG_INFINITY, 0), (f32::INFINITY, 0));
    for axis in 0..3 {
        // Faces 2·axis (the plane at 1, outward +axis) and 2·axis + 1 (at 0).
        let (o, d, face) = (o[axis], d[axis], 2 * axis as u32);
        if d == 0.0 {
            // Parallel to both planes: outside one of them (as the plane
            // clipping tests it: a NaN passes) misses.
            if 1.0 - o < 0.0 || o < 0.0 {
                return None;
            }
            continue;
        }
        let (at_one, at_zero) = (ones[axis], zeros[axis]);
        let (inward, outward) =
            if d > 0.0 { ((at_zero, face + 1), (at_one, face)) } else { ((at_one, face), (at_zero, face + 1)) };
        if outward.0 < exit.0 {
            exit = outward;
        }
        if inward.0 > enter.0 {
            enter = inward;
        }
    }
    (enter.0 < exit.0 && enter.0.is_finite() && exit.0.is_finite()).then_some((enter, exit))
}

/// How a caster cuts a primitive's unit shape.
#[derive(Debug, Clone)]
pub(super) enum Clipping {
    /// The shape's own procedure ([`unit_span`]).
    Shape,
    /// The unit cube, by slabs ([`unit_cube`]).
    Box,
    /// A convex polyhedron of many planes, eight planes at a time.
    Lanes(Box<PlaneLanes>),
}

/// A convex polyhedron's planes in lanes of eight (structure of arrays): a
/// ray is clipped by eight planes with one division. Lanes past the last plane
/// hold `0·p ≤ 1`, which clips nothing.
#[derive(Debug, Clone)]
pub(super) struct PlaneLanes {
    normal: [Vec<f32x8>; 3],
    w: Vec<f32x8>,
    /// Its faces' corners, for leaving out faces a scanline cannot cross.
    pub(super) corners: Option<super::faces::FaceCorners>,
}

impl PlaneLanes {
    /// Planes from which lanes pay: below, a plane-by-plane loop is as quick
    /// as one pass of lanes and the reduction of their answers (measured: a
    /// pyramid's five planes, bevel gears' teeth of eight: 10–15% slower in
    /// lanes; the hull of eight faceted balls, hundreds of planes: 3x faster).
    pub(super) const MIN_PLANES: usize = 16;

    pub(super) fn new(poly: &ConvexPolyhedron) -> PlaneLanes {
        let lanes = |f: fn(&Vec4) -> f32, pad: f32| -> Vec<f32x8> {
            poly.planes.chunks(8).map(|c| f32x8::new(std::array::from_fn(|j| c.get(j).map_or(pad, f)))).collect()
        };
        PlaneLanes {
            normal: [lanes(|p| p.x, 0.0), lanes(|p| p.y, 0.0), lanes(|p| p.z, 0.0)],
            w: lanes(|p| p.w, 1.0),
            corners: super::faces::FaceCorners::new(poly),
        }
    }

    /// What [`polyhedron`] gives for the same planes, the same `t` to the bit
    /// and the same faces: each lane keeps the first of its planes with the
    /// latest entry (earliest exit), and of the lanes tied at the end the one
    /// with the first plane wins. Never inlined: it is for polyhedra of many
    /// planes, and inlined into the per-pixel interval it slowed the boxes'
    /// and small polyhedra's path by 10%.
    #[inline(never)]
    pub(super) fn clip(&self, o: Vec3, d: Vec3) -> Option<UnitSpan> {
        let s = f32x8::splat;
        let ([ox, oy, oz], [dx, dy, dz]) = (o.to_array().map(s), d.to_array().map(s));
        let zero = f32x8::ZERO;
        let (mut enter, mut exit) = ((s(f32::NEG_INFINITY), zero), (s(f32::INFINITY), zero));
        let mut miss = zero;
        let mut face = f32x8::new(std::array::from_fn(|j| j as f32));
        for (k, &w) in self.w.iter().enumerate() {
            let [nx, ny, nz] = [self.normal[0][k], self.normal[1][k], self.normal[2][k]];
            let along = nx * dx + ny * dy + nz * dz;
            let gap = w - (nx * ox + ny * oy + nz * oz);
            // Parallel to a plane and outside it: the ray misses.
            miss |= along.simd_eq(zero) & gap.simd_lt(zero);
            let t = gap / along;
            let leaves = along.simd_gt(zero) & t.simd_lt(exit.0);
            exit = (leaves.select(t, exit.0), leaves.select(face, exit.1));
            let enters = along.simd_lt(zero) & t.simd_gt(enter.0);
            enter = (enters.select(t, enter.0), enters.select(face, enter.1));
            face += s(8.0);
        }
        if miss.any() {
            return None;
        }
        let (enter, exit) = (first_of_lanes(enter, |a, b| a > b), first_of_lanes(exit, |a, b| a < b));
        (enter.0 < exit.0 && enter.0.is_finite() && exit.0.is_finite()).then_some((enter, exit))
    }
}

/// Of eight lanes' `(t, face)`, the `t` no other is `later` than, on a tie
/// the one with the first face.
#[inline(always)]
fn first_of_lanes((t, face): (f32x8, f32x8), later: impl Fn(f32, f32) -> bool) -> (f32, u32) {
    let (t, face) = (t.to_array(), face.to_array());
    let mut best = (t[0], face[0] as u32);
    for j in 1..8 {
        let f = face[j] as u32;
        if later(t[j], best.0) || (t[j] == best.0 && f < best.1) {
            best = (t[j], f);
        }
    }
    best
}

/// A convex polyhedron: the ray clipped by every face plane.
pub(super) fn polyhedron(poly: &ConvexPolyhedron, o: Vec3, d: Vec3) -> Option<UnitSpan> {
    let (mut enter, mut exit) = ((f32::NEG_INFINITY, 0), (f32::INFINITY, 0));
    for (face, plane) in (0..).zip(&poly.planes) {
        let n = plane.truncate();
        let (along, gap) = (n.dot(d), plane.w - n.dot(o));
        if along == 0.0 {
            if gap < 0.0 {
                return None;
            }
            continue;
        }
        let t = gap / along;
        if along > 0.0 {
            if t < exit.0 {
                exit = (t, face);
            }
        } else if t > enter.0 {
            enter = (t, face);
        }
    }
    (enter.0 < exit.0 && enter.0.is_finite() && exit.0.is_finite()).then_some((enter, exit))
}

#[cfg(test)]
pub(super) mod tests {
    use proptest::prelude::*;

    use super::*;

    /// A coordinate, sometimes exactly on one of the cube's planes.
    fn coordinate(range: std::ops::Range<f32>) -> impl Strategy<Value = f32> {
        prop_oneof![4 => range, 1 => Just(0.0f32), 1 => Just(1.0f32)]
    }

    pub(crate) fn vector(range: std::ops::Range<f32>) -> impl Strategy<Value = Vec3> {
        (coordinate(range.clone()), coordinate(range.clone()), coordinate(range))
            .prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        /// Eight planes at a time clip as plane by plane does: the same `t`
        /// to the bit and the same faces, for random planes (some axis
        /// aligned, some repeated so that faces tie) and rays (some parallel
        /// to a plane), any number of planes (lanes left over included).
        #[test]
        fn planes_in_lanes_clip_as_plane_by_plane(
            normals in prop::collection::vec(vector(-1.0..1.0), 1..40),
            offsets in prop::collection::vec(prop_oneof![0.2f32..2.0, Just(1.0f32)], 40),
            o in vector(-1.0..1.0),
            d in vector(-2.0..2.0),
        ) {
            let mut planes: Vec<Vec4> = normals.iter().zip(&offsets).map(|(n, &w)| n.extend(w)).collect();
            planes.extend_from_within(..planes.len() / 3);
            let poly = ConvexPolyhedron { planes, vertices: Vec::new() };
            prop_assert_eq!(PlaneLanes::new(&poly).clip(o, d), polyhedron(&poly, o, d));
        }

        /// The slab test of a box gives what clipping by the unit cube's
        /// planes gives: the same parameters to the bit and the same faces,
        /// rays parallel to a face and rays along one included.
        #[test]
        fn a_box_by_slabs_is_the_cube_by_planes(o in vector(-2.0..3.0), d in vector(-2.0..2.0)) {
            prop_assert_eq!(unit_cube(o, d), polyhedron(&ConvexPolyhedron::unit_cube(), o, d));
        }
    }
}
