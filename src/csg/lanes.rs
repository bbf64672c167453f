//! Eight pixels of a scanline at once (coherence along a scanline the SIMD
//! way; seed 003 §5.2.2's own reuse of a pixel's answer is
//! [`crate::visibility::coherence`]): one primitive's interval at pixels `x0..x0 + 8` of a row, each
//! of the parent module's closed-form procedures ([`super::shapes::sphere`],
//! [`super::shapes::frustum`], [`super::shapes::unit_cube`], [`super::shapes::polyhedron`]) run in
//! `f32x8` lanes, one pixel per lane.
//!
//! Every lane does the same IEEE operations in the same order as the scalar
//! procedure and picks among its cases with masks where the scalar one
//! branches, so each lane's `t` is the scalar one to the bit, with the same
//! face: the scanline walk's answer does not depend on which path found it.
//! The property tests below hold the lanes to that.

use glam::{Mat3A, Vec3, Vec4};
use wide::f32x8;

use super::shapes::{BOTTOM, SIDE, TOP};
use crate::camera::RowLine;
use crate::csg::{ConvexPolyhedron, Shape};

/// Eight pixels' rays `o + t·d`, a coordinate per array entry.
#[derive(Debug, Clone, Copy)]
pub(super) struct RayLanes {
    o: [f32x8; 3],
    d: [f32x8; 3],
}

impl RayLanes {
    /// Pixels `x0..x0 + 8` of `line`, each as [`RowLine::at`] makes it.
    pub(super) fn new(line: &RowLine, x0: f32) -> RayLanes {
        let x = f32x8::new(std::array::from_fn(|j| x0 + j as f32));
        let at = |base: Vec3, step: Vec3| -> [f32x8; 3] { std::array::from_fn(|k| s(base[k]) + s(step[k]) * x) };
        RayLanes { o: at(line.origin, line.origin_step), d: at(line.dir, line.dir_step) }
    }
}

/// Eight pixels' intervals of one primitive: entry and exit `t` with their
/// faces, and which lanes meet it.
#[derive(Debug, Clone, Copy)]
pub(super) struct SpanLanes {
    pub(super) enter: (f32x8, f32x8),
    pub(super) exit: (f32x8, f32x8),
    /// All ones in the lanes whose ray meets the primitive.
    pub(super) hit: f32x8,
}

const ZERO: f32x8 = f32x8::ZERO;

fn s(v: f32) -> f32x8 {
    f32x8::splat(v)
}

/// `(t, face)` pairs chosen lane by lane.
fn pick(mask: f32x8, a: (f32x8, f32x8), b: (f32x8, f32x8)) -> (f32x8, f32x8) {
    (mask.select(a.0, b.0), mask.select(a.1, b.1))
}

/// `(a·b)` as the scalar `Vec3::dot`: `x·x' + y·y' + z·z'`, left to right.
fn dot(a: [f32x8; 3], b: [f32x8; 3]) -> f32x8 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The interval of a convex unit shape ([`super::shapes::unit_span`]) in
/// eight lanes; `None` for a mesh's layer, found ray by ray.
pub(super) fn shape(shape: &Shape, r: &RayLanes) -> Option<SpanLanes> {
    Some(match shape {
        Shape::Sphere => sphere(r),
        Shape::Frustum { bottom, top } => frustum(*bottom, *top, r),
        Shape::Polyhedron(poly) => polyhedron(poly, r),
        Shape::Mesh { .. } => return None,
    })
}

/// [`super::shapes::roots`] in lanes: the smaller and larger root, and where they are real.
fn roots(a: f32x8, b: f32x8, c: f32x8) -> (f32x8, f32x8, f32x8) {
    let disc = b * b - a * c;
    let real = !(disc.simd_lt(ZERO) | a.simd_eq(ZERO));
    let sign = b.is_sign_negative().select(s(-1.0), s(1.0));
    let q = -(b + sign * disc.sqrt());
    let (r0, r1) = (q / a, c / q);
    let lo_first = r0.simd_lt(r1);
    (lo_first.select(r0, r1), lo_first.select(r1, r0), real)
}

/// [`super::shapes::sphere`] in lanes.
fn sphere(r: &RayLanes) -> SpanLanes {
    let (t0, t1, hit) = roots(dot(r.d, r.d), dot(r.o, r.d), dot(r.o, r.o) - s(1.0));
    SpanLanes { enter: (t0, ZERO), exit: (t1, ZERO), hit }
}

/// [`super::shapes::slab_z`] in lanes.
fn slab_z(r: &RayLanes) -> SpanLanes {
    let (oz, dz) = (r.o[2], r.d[2]);
    let flat = dz.simd_eq(ZERO);
    let (ta, tb) = ((-oz) / dz, (s(1.0) - oz) / dz);
    let up = dz.simd_gt(ZERO);
    let enter = pick(up, (ta, s(BOTTOM as f32)), (tb, s(TOP as f32)));
    let exit = pick(up, (tb, s(TOP as f32)), (ta, s(BOTTOM as f32)));
    let within = s(0.0).simd_le(oz) & oz.simd_le(s(1.0));
    SpanLanes {
        enter: pick(flat, (s(f32::NEG_INFINITY), s(BOTTOM as f32)), enter),
        exit: pick(flat, (s(f32::INFINITY), s(TOP as f32)), exit),
        hit: !flat | within,
    }
}

/// [`super::shapes::frustum`] in lanes: each of the scalar procedure's cases (the
/// quadric's inside one interval, two half-lines, one half-line, all of the
/// line, none) chosen by mask, then the same clipping by the slab.
fn frustum(bottom: f32, top: f32, r: &RayLanes) -> SpanLanes {
    if bottom == top {
        return cylinder(bottom, r);
    }
    let (o, d) = (r.o, r.d);
    let k = s(top - bottom);
    let slab = slab_z(r);
    let r_o = s(bottom) + k * o[2];
    let a = (d[0] * d[0] + d[1] * d[1]) - k * k * d[2] * d[2];
    let b = (o[0] * d[0] + o[1] * d[1]) - k * d[2] * r_o;
    let c = (o[0] * o[0] + o[1] * o[1]) - r_o * r_o;
    let (r0, r1, real) = roots(a, b, c);
    let (inf, neg_inf) = (s(f32::INFINITY), s(f32::NEG_INFINITY));
    let between = real & a.simd_gt(ZERO);
    let outside = real & !a.simd_gt(ZERO);
    let half = !real & a.simd_eq(ZERO) & !b.simd_eq(ZERO);
    let all = !real & !half & c.simd_le(ZERO);
    let t = -c / (s(2.0) * b);
    let half_range = pick(b.simd_gt(ZERO), (neg_inf, t), (t, inf));
    // First range: (r0, r1) | (−∞, r0) | half-line | all | none.
    let none = (inf, neg_inf);
    let mut first = pick(between, (r0, r1), none);
    first = pick(outside, (neg_inf, r0), first);
    first = pick(half, half_range, first);
    first = pick(all, (neg_inf, inf), first);
    let second = pick(outside, (r1, inf), none);
    let ((s0, n0), (s1, n1)) = (slab.enter, slab.exit);
    let clip = |(q0, q1): (f32x8, f32x8)| {
        let enter = pick(q0.simd_gt(s0), (q0, s(SIDE as f32)), (s0, n0));
        let exit = pick(q1.simd_lt(s1), (q1, s(SIDE as f32)), (s1, n1));
        (enter, exit, enter.0.simd_lt(exit.0))
    };
    let (e1, x1, ok1) = clip(first);
    let (e2, x2, ok2) = clip(second);
    // Both: the earlier entry (the first's on a tie), the later exit.
    let enter = pick(ok1 & ok2, pick(e1.0.simd_le(e2.0), e1, e2), pick(ok1, e1, e2));
    let exit = pick(ok1 & ok2, pick(x1.0.simd_ge(x2.0), x1, x2), pick(ok1, x1, x2));
    SpanLanes { enter, exit, hit: slab.hit & (between | outside | half | all) & (ok1 | ok2) }
}

/// [`super::shapes::cylinder`] in lanes: between the roots, all of a line
/// within the radius, or none; then clipped by the slab.
fn cylinder(radius: f32, r: &RayLanes) -> SpanLanes {
    let (o, d) = (r.o, r.d);
    let slab = slab_z(r);
    let a = d[0] * d[0] + d[1] * d[1];
    let b = o[0] * d[0] + o[1] * d[1];
    let c = (o[0] * o[0] + o[1] * o[1]) - s(radius) * s(radius);
    let (r0, r1, real) = roots(a, b, c);
    let all = !real & c.simd_le(ZERO);
    let (inf, neg_inf) = (s(f32::INFINITY), s(f32::NEG_INFINITY));
    let (q0, q1) = pick(real, (r0, r1), pick(all, (neg_inf, inf), (inf, neg_inf)));
    let ((s0, n0), (s1, n1)) = (slab.enter, slab.exit);
    let enter = pick(q0.simd_gt(s0), (q0, s(SIDE as f32)), (s0, n0));
    let exit = pick(q1.simd_lt(s1), (q1, s(SIDE as f32)), (s1, n1));
    SpanLanes { enter, exit, hit: slab.hit & (real | all) & enter.0.simd_lt(exit.0) }
}

/// [`super::shapes::unit_cube`] in lanes.
pub(super) fn unit_cube(r: &RayLanes) -> SpanLanes {
    let (mut enter, mut exit) = ((s(f32::NEG_INFINITY), ZERO), (s(f32::INFINITY), ZERO));
    let mut miss = ZERO;
    for axis in 0..3 {
        let (o, d, face) = (r.o[axis], r.d[axis], s(2.0 * axis as f32));
        let (at_one, at_zero) = ((s(1.0) - o) / d, (-o) / d);
        let flat = d.simd_eq(ZERO);
        miss |= flat & ((s(1.0) - o).simd_lt(ZERO) | o.simd_lt(ZERO));
        let up = d.simd_gt(ZERO);
        let inward = pick(up, (at_zero, face + s(1.0)), (at_one, face));
        let outward = pick(up, (at_one, face), (at_zero, face + s(1.0)));
        exit = pick(!flat & outward.0.simd_lt(exit.0), outward, exit);
        enter = pick(!flat & inward.0.simd_gt(enter.0), inward, enter);
    }
    finish(enter, exit, miss)
}

/// [`super::shapes::polyhedron`] in lanes: every plane clips all eight rays.
pub(super) fn polyhedron(poly: &ConvexPolyhedron, r: &RayLanes) -> SpanLanes {
    planes((0..).zip(&poly.planes), r)
}

/// [`polyhedron`] by the planes `faces` (face index and plane, in rising
/// order of index, so that ties go to the first face as they do there).
pub(super) fn planes<'a>(faces: impl Iterator<Item = (u32, &'a Vec4)>, r: &RayLanes) -> SpanLanes {
    let (mut enter, mut exit) = ((s(f32::NEG_INFINITY), ZERO), (s(f32::INFINITY), ZERO));
    let mut miss = ZERO;
    for (face, plane) in faces {
        let n = plane.truncate().to_array().map(s);
        let (along, gap) = (dot(n, r.d), s(plane.w) - dot(n, r.o));
        let parallel = along.simd_eq(ZERO);
        miss |= parallel & gap.simd_lt(ZERO);
        let t = gap / along;
        let leaving = along.simd_gt(ZERO);
        let face = s(face as f32);
        exit = pick(leaving & t.simd_lt(exit.0), (t, face), exit);
        enter = pick(!leaving & !parallel & t.simd_gt(enter.0), (t, face), enter);
    }
    finish(enter, exit, miss)
}

/// The unit outward normals, in solid space, where the rays `r` cross
/// `face` of the unit `shape` at `t` (eight crossings of one face): the shape's
/// normal ([`super::shapes::unit_normal`]) carried by the normal matrix `m`,
/// then normalised or zero, as the scalar `(m * n).normalize_or_zero()` does.
pub(super) fn normals(shape: &Shape, face: u32, r: &RayLanes, t: f32x8, m: &Mat3A) -> [f32x8; 3] {
    let p: [f32x8; 3] = std::array::from_fn(|k| r.o[k] + r.d[k] * t);
    let n = match shape {
        Shape::Sphere => p,
        Shape::Frustum { bottom, top } if face == SIDE => {
            let k = top - bottom;
            [p[0], p[1], s(-k) * (s(*bottom) + s(k) * p[2])]
        }
        // A flat face: one normal.
        _ => super::shapes::unit_normal(shape, face, Vec3::ZERO).to_array().map(s),
    };
    // `Mat3A * v`: the columns scaled by v's components, summed left to right.
    let (cx, cy, cz) = (m.x_axis, m.y_axis, m.z_axis);
    let v: [f32x8; 3] = std::array::from_fn(|k| s(cx[k]) * n[0] + s(cy[k]) * n[1] + s(cz[k]) * n[2]);
    let rcp = s(1.0) / dot(v, v).sqrt();
    let finite = rcp.simd_gt(ZERO) & rcp.simd_lt(s(f32::INFINITY));
    v.map(|c| finite.select(c * rcp, ZERO))
}

/// A clipped interval's lanes: met where nothing missed, the entry before
/// the exit and both finite.
fn finish(enter: (f32x8, f32x8), exit: (f32x8, f32x8), miss: f32x8) -> SpanLanes {
    let hit = !miss & enter.0.simd_lt(exit.0) & enter.0.is_finite() & exit.0.is_finite();
    SpanLanes { enter, exit, hit }
}
