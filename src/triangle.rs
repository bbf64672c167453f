//! Watertight ray/triangle intersection (Woop, Benthin and Wald, "Watertight
//! Ray/Triangle Intersection", JCGT 2013): the triangle is moved into a frame where
//! the ray runs along +z, and the three edge functions are evaluated there. A ray
//! through an edge or vertex shared by two triangles hits at least one of them —
//! never slips between — which Möller–Trumbore does not promise.

use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;
use wide::f32x8;

use crate::camera::Ray;

/// A ray prepared for many triangle tests.
#[derive(Debug, Clone, Copy)]
pub struct ShearedRay {
    origin: Vec3,
    /// The axis permutation and shear as three rows: sheared = (rx·a, ry·a, rz·a)
    /// for a = vertex − origin, with rx = e_kx − Sx·e_kz, ry = e_ky − Sy·e_kz,
    /// rz = e_kz (kz the dominant direction axis). The zero entries make each dot
    /// product exactly `a[kx] − Sx·a[kz]`, as the paper computes it, without
    /// indexing by a run-time axis.
    rows: [Vec3; 3],
    /// 1 / d[kz]: scales the interpolated z to the ray's t.
    inv_dz: f32,
}

impl ShearedRay {
    /// Prepares `ray` (direction need not be unit length; `t` is in its units).
    #[must_use]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.dir;
        let a = d.abs();
        // The dominant axis as a unit vector, chosen without branches (rays of
        // one image turn from one axis to another unpredictably), then the two
        // after it in cyclic order, swapped when the ray runs down that axis
        // so the triangle's winding is kept.
        let on_x = (a.x >= a.y) & (a.x >= a.z);
        let on_y = !on_x & (a.y >= a.z);
        let z = Vec3::new(f32::from(u8::from(on_x)), f32::from(u8::from(on_y)), f32::from(u8::from(!on_x & !on_y)));
        let x = Vec3::new(z.z, z.x, z.y);
        let y = Vec3::new(x.z, x.x, x.y);
        let dz = d.dot(z);
        let down = glam::BVec3::splat(dz < 0.0);
        let (x, y) = (Vec3::select(down, y, x), Vec3::select(down, x, y));
        let (sx, sy) = (d.dot(x) / dz, d.dot(y) / dz);
        ShearedRay { origin: ray.origin, rows: [x - sx * z, y - sy * z, z], inv_dz: 1.0 / dz }
    }

    /// Distance and barycentrics (b1, b2) of the hit with triangle `p` in
    /// `(t_min, t_max)`, from either side.
    #[must_use]
    #[inline]
    pub fn intersect(&self, p: &[Vec3; 3], t_min: f32, t_max: f32) -> Option<(f32, Vec2)> {
        let [rx, ry, rz] = self.rows;
        // Not `p.map(..)`: array map is not inlined here and costs a call per vertex.
        let shear = |v: Vec3| {
            let a = v - self.origin;
            Vec3::new(rx.dot(a), ry.dot(a), rz.dot(a))
        };
        let (a, b, c) = (shear(p[0]), shear(p[1]), shear(p[2]));
        let mut u = c.x * b.y - c.y * b.x;
        let mut v = a.x * c.y - a.y * c.x;
        let mut w = b.x * a.y - b.y * a.x;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            (u, v, w) = on_an_edge(a, b, c);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = self.inv_dz * (u * a.z + v * b.z + w * c.z);
        let t = t_scaled / det;
        if !(t > t_min && t < t_max) {
            return None;
        }
        Some((t, Vec2::new(v / det, w / det)))
    }
}

/// The hits of up to [`LANES`] triangles with one ray, tested at once
/// ([`ShearedRay::intersect_lanes`]).
#[derive(Debug, Clone, Copy)]
pub struct LaneHits {
    /// A bit per triangle hit in `(t_min, t_max)`.
    pub hits: u32,
    /// Per lane, the distance of its hit.
    pub t: [f32; LANES],
    /// Per lane, the barycentric weights (b1, b2) of its hit.
    pub b1: [f32; LANES],
    /// See [`LaneHits::b1`].
    pub b2: [f32; LANES],
}

impl LaneHits {
    /// The lanes hit, in lane order.
    pub fn lanes(&self) -> impl Iterator<Item = usize> {
        set_bits(self.hits)
    }
}

/// The bits set in `mask`, lowest first (a lane mask's lanes).
pub(crate) fn set_bits(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        let k = (mask != 0).then(|| mask.trailing_zeros() as usize)?;
        mask &= mask - 1;
        Some(k)
    })
}

/// Triangles [`ShearedRay::intersect_lanes`] tests at once.
pub const LANES: usize = 8;

/// Triangles stored coordinate by coordinate (nine columns: the x, y, z of
/// each corner), so that eight consecutive triangles' coordinates load as
/// eight-lane vectors with no gathering ([`ShearedRay::intersect_lanes`]).
#[derive(Debug, Clone, Default)]
pub struct TriangleColumns {
    /// Corner-major: column `3 · corner + axis`, a triangle an entry, padded
    /// with [`LANES`] zeros so any eight-lane load from a triangle fits.
    columns: [Vec<f32>; 9],
}

impl TriangleColumns {
    /// The columns of `triangles`, in their order.
    #[must_use]
    pub fn new(triangles: &[[Vec3; 3]]) -> TriangleColumns {
        Self::from_fn(triangles.len(), |j| triangles[j])
    }

    /// The columns of `triangles` taken in `order` (a BVH's leaf order): entry
    /// `j` is triangle `order[j]`.
    ///
    /// # Panics
    /// If `order` names a triangle out of range.
    #[must_use]
    pub fn in_order(triangles: &[[Vec3; 3]], order: &[u32]) -> TriangleColumns {
        Self::from_fn(order.len(), |j| triangles[order[j] as usize])
    }

    /// The columns of `n` triangles, entry `j` being `triangle(j)`: blocks of
    /// entries filled in parallel, each triangle asked once.
    fn from_fn(n: usize, triangle: impl Fn(usize) -> [Vec3; 3] + Sync) -> TriangleColumns {
        const BLOCK: usize = 1 << 12;
        let mut columns: [Vec<f32>; 9] = std::array::from_fn(|_| vec![0.0; n + LANES]);
        let mut chunks = columns.each_mut().map(|c| c[..n].chunks_mut(BLOCK));
        let blocks: Vec<[&mut [f32]; 9]> = (0..n.div_ceil(BLOCK))
            .map(|_| std::array::from_fn(|c| chunks[c].next().expect("as many blocks")))
            .collect();
        blocks.into_par_iter().enumerate().for_each(|(b, mut block)| {
            for k in 0..block[0].len() {
                let t = triangle(b * BLOCK + k);
                for (c, column) in block.iter_mut().enumerate() {
                    column[k] = t[c / 3][c % 3];
                }
            }
        });
        TriangleColumns { columns }
    }

    /// Triangles stored.
    #[must_use]
    pub fn len(&self) -> usize {
        self.columns[0].len().saturating_sub(LANES)
    }

    /// Whether none is.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Triangle `i`.
    ///
    /// # Panics
    /// If `i` is out of range.
    #[must_use]
    pub fn get(&self, i: usize) -> [Vec3; 3] {
        assert!(i < self.len(), "triangle {i} of {}", self.len());
        let c = |k: usize| self.columns[k][i];
        [Vec3::new(c(0), c(1), c(2)), Vec3::new(c(3), c(4), c(5)), Vec3::new(c(6), c(7), c(8))]
    }

    /// Column `c` from triangle `start`, eight lanes.
    #[inline(always)]
    fn lanes(&self, c: usize, start: usize) -> f32x8 {
        let v: [f32; LANES] = self.columns[c][start..start + LANES].try_into().expect("padded columns");
        f32x8::from(v)
    }
}

impl ShearedRay {
    /// [`ShearedRay::intersect`] of the `count` (at most [`LANES`]) triangles
    /// from `start` of `triangles` at once, one a lane: every lane's answer is
    /// the one-triangle test's, bit for bit (the same operations in the same
    /// order; a lane on an edge is decided by the one-triangle test, in f64).
    ///
    /// # Panics
    /// If `count` exceeds [`LANES`] or the triangles are out of range.
    #[must_use]
    #[inline]
    pub fn intersect_lanes(
        &self,
        triangles: &TriangleColumns,
        start: usize,
        count: usize,
        t_min: f32,
        t_max: f32,
    ) -> LaneHits {
        assert!(count <= LANES && start + count <= triangles.len(), "triangles {start}+{count}");
        let [rx, ry, rz] = self.rows.map(|r| [r.x, r.y, r.z].map(f32x8::splat));
        let o = [self.origin.x, self.origin.y, self.origin.z].map(f32x8::splat);
        let shear = |corner: usize| {
            let axis = |k: usize| triangles.lanes(3 * corner + k, start) - o[k];
            let (x, y, z) = (axis(0), axis(1), axis(2));
            let row = |r: &[f32x8; 3]| r[0] * x + r[1] * y + r[2] * z;
            (row(&rx), row(&ry), row(&rz))
        };
        let ((ax, ay, az), (bx, by, bz), (cx, cy, cz)) = (shear(0), shear(1), shear(2));
        let (u, v, w) = (cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax);
        let zero = f32x8::ZERO;
        let used = (1u32 << count) - 1;
        let on_edge = (u.simd_eq(zero) | v.simd_eq(zero) | w.simd_eq(zero)).to_bitmask() & used;
        let negative = u.simd_lt(zero) | v.simd_lt(zero) | w.simd_lt(zero);
        let positive = u.simd_gt(zero) | v.simd_gt(zero) | w.simd_gt(zero);
        let det = u + v + w;
        let t = f32x8::splat(self.inv_dz) * (u * az + v * bz + w * cz) / det;
        let inside = !(negative & positive) & !det.simd_eq(zero);
        let within = t.simd_gt(f32x8::splat(t_min)) & t.simd_lt(f32x8::splat(t_max));
        let mut out = LaneHits {
            hits: (inside & within).to_bitmask() & used & !on_edge,
            t: t.to_array(),
            b1: (v / det).to_array(),
            b2: (w / det).to_array(),
        };
        for k in set_bits(on_edge) {
            if let Some((t, b)) = self.intersect(&triangles.get(start + k), t_min, t_max) {
                out.hits |= 1 << k;
                (out.t[k], out.b1[k], out.b2[k]) = (t, b.x, b.y);
            }
        }
        out
    }
}

/// Eight rays prepared for triangle tests together, one a lane
/// ([`RayLanes::intersect_triangle`]): the rays of a packet walked through
/// the BVH together test a leaf's triangles once for all of them. Each
/// lane holds what [`ShearedRay::new`] computes for its ray, computed lane
/// by lane with the same operations.
#[derive(Debug, Clone, Copy)]
pub struct RayLanes {
    origin: [f32x8; 3],
    dir: [f32x8; 3],
    /// Each ray's rows ([`ShearedRay`]'s), entry by entry across the lanes.
    rows: [[f32x8; 3]; 3],
    inv_dz: f32x8,
}

impl RayLanes {
    /// Prepares eight rays (a lane each).
    #[must_use]
    pub fn new(rays: &[Ray; LANES]) -> RayLanes {
        let (mut origin, mut dir) = ([[0.0; LANES]; 3], [[0.0; LANES]; 3]);
        for (lane, r) in rays.iter().enumerate() {
            (0..3).for_each(|k| (origin[k][lane], dir[k][lane]) = (r.origin[k], r.dir[k]));
        }
        let (origin, d) = (origin.map(f32x8::from), dir.map(f32x8::from));
        let a = d.map(f32x8::abs);
        let one = f32x8::splat(1.0);
        let on_x = a[0].simd_ge(a[1]) & a[0].simd_ge(a[2]);
        let on_y = !on_x & a[1].simd_ge(a[2]);
        let z = [on_x, on_y, !on_x & !on_y].map(|m| m & one);
        let x = [z[2], z[0], z[1]];
        let y = [x[2], x[0], x[1]];
        let dot = |v: &[f32x8; 3]| d[0] * v[0] + d[1] * v[1] + d[2] * v[2];
        let dz = dot(&z);
        let down = dz.simd_lt(f32x8::ZERO);
        let pick = |m: f32x8, t: f32x8, f: f32x8| (m & t) | (!m & f);
        let (x, y) = (std::array::from_fn(|k| pick(down, y[k], x[k])), std::array::from_fn(|k| pick(down, x[k], y[k])));
        let (sx, sy) = (dot(&x) / dz, dot(&y) / dz);
        let rows = [std::array::from_fn(|k| x[k] - sx * z[k]), std::array::from_fn(|k| y[k] - sy * z[k]), z];
        RayLanes { origin, dir: d, rows, inv_dz: one / dz }
    }

    /// The rays' origins and directions, axis by axis, a ray a lane.
    #[must_use]
    pub(crate) fn lanes(&self) -> ([f32x8; 3], [f32x8; 3]) {
        (self.origin, self.dir)
    }

    /// Lane `lane`'s ray prepared alone: [`ShearedRay::new`] of it, read
    /// from the lanes (the same values).
    #[must_use]
    pub fn lane(&self, lane: usize) -> ShearedRay {
        let at = |v: f32x8| v.to_array()[lane];
        let row = |r: &[f32x8; 3]| Vec3::new(at(r[0]), at(r[1]), at(r[2]));
        ShearedRay {
            origin: row(&self.origin),
            rows: [row(&self.rows[0]), row(&self.rows[1]), row(&self.rows[2])],
            inv_dz: at(self.inv_dz),
        }
    }

    /// The ray of `lane`.
    #[must_use]
    fn ray(&self, lane: usize) -> Ray {
        let axis = |v: &[f32x8; 3]| Vec3::new(v[0].to_array()[lane], v[1].to_array()[lane], v[2].to_array()[lane]);
        Ray { origin: axis(&self.origin), dir: axis(&self.dir) }
    }

    /// [`ShearedRay::intersect`] of triangle `i` of `triangles` with the rays
    /// of `lanes`, at once: every lane's answer is the one-ray test's, bit for
    /// bit (the same operations in the same order; a lane on an edge is
    /// decided by the one-ray test, in f64). `t_max` is per lane.
    ///
    /// # Panics
    /// If `i` is out of range.
    #[must_use]
    #[inline]
    pub fn intersect_triangle(
        &self,
        triangles: &TriangleColumns,
        i: usize,
        lanes: u32,
        t_min: f32,
        t_max: f32x8,
    ) -> LaneHits {
        assert!(i < triangles.len(), "triangle {i} of {}", triangles.len());
        let [rx, ry, rz] = &self.rows;
        let shear = |corner: usize| {
            let axis = |k: usize| f32x8::splat(triangles.columns[3 * corner + k][i]) - self.origin[k];
            let (x, y, z) = (axis(0), axis(1), axis(2));
            let row = |r: &[f32x8; 3]| r[0] * x + r[1] * y + r[2] * z;
            (row(rx), row(ry), row(rz))
        };
        let ((ax, ay, az), (bx, by, bz), (cx, cy, cz)) = (shear(0), shear(1), shear(2));
        let (u, v, w) = (cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax);
        let zero = f32x8::ZERO;
        let on_edge = (u.simd_eq(zero) | v.simd_eq(zero) | w.simd_eq(zero)).to_bitmask() & lanes;
        let negative = u.simd_lt(zero) | v.simd_lt(zero) | w.simd_lt(zero);
        let positive = u.simd_gt(zero) | v.simd_gt(zero) | w.simd_gt(zero);
        let det = u + v + w;
        let t = self.inv_dz * (u * az + v * bz + w * cz) / det;
        let inside = !(negative & positive) & !det.simd_eq(zero);
        let within = t.simd_gt(f32x8::splat(t_min)) & t.simd_lt(t_max);
        let mut out = LaneHits {
            hits: (inside & within).to_bitmask() & lanes & !on_edge,
            t: t.to_array(),
            b1: (v / det).to_array(),
            b2: (w / det).to_array(),
        };
        if on_edge != 0 {
            let (p, t_max) = (triangles.get(i), t_max.to_array());
            for k in set_bits(on_edge) {
                if let Some((t, b)) = ShearedRay::new(&self.ray(k)).intersect(&p, t_min, t_max[k]) {
                    out.hits |= 1 << k;
                    (out.t[k], out.b1[k], out.b2[k]) = (t, b.x, b.y);
                }
            }
        }
        out
    }
}

/// The edge functions of a ray on an edge in f32, decided in f64 so neighbours
/// agree (rare: kept out of the inlined test).
#[cold]
#[inline(never)]
fn on_an_edge(a: Vec3, b: Vec3, c: Vec3) -> (f32, f32, f32) {
    let e = |p: Vec3, q: Vec3| (q.x as f64 * p.y as f64 - q.y as f64 * p.x as f64) as f32;
    (e(b, c), e(c, a), e(a, b))
}

/// Möller–Trumbore in f64 with the inside test, for tests and rare exact needs.
#[must_use]
pub fn intersect_f64(ray: &Ray, p: &[Vec3; 3]) -> Option<(f64, [f64; 2])> {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let [a, b, c] = p.map(Vec3::as_dvec3);
    let (e1, e2) = (b - a, c - a);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-300 {
        return None;
    }
    let tv: DVec3 = o - a;
    let u = tv.dot(pv) / det;
    let q = tv.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some((t, [u, v]))
}

#[cfg(test)]
mod tests {
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    use super::*;

    fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray { origin: Vec3::from(o), dir: Vec3::from(d) }
    }

    #[test]
    fn hits_the_middle_and_reports_barycentrics() {
        let tri = [Vec3::new(0.0, 0.0, 5.0), Vec3::new(1.0, 0.0, 5.0), Vec3::new(0.0, 1.0, 5.0)];
        let r = ray([0.25, 0.25, 0.0], [0.0, 0.0, 1.0]);
        let (t, b) = ShearedRay::new(&r).intersect(&tri, 0.0, f32::INFINITY).unwrap();
        assert!((t - 5.0).abs() < 1e-6 && (b - Vec2::splat(0.25)).length() < 1e-6, "{t} {b}");
        assert!(ShearedRay::new(&r).intersect(&tri, 0.0, 4.0).is_none());
        assert!(ShearedRay::new(&ray([2.0, 2.0, 0.0], [0.0, 0.0, 1.0])).intersect(&tri, 0.0, 9.0).is_none());
    }

    /// Lane `k`'s hit: its distance and barycentrics.
    fn lane_hit(lanes: &LaneHits, k: usize) -> Option<(f32, Vec2)> {
        (lanes.hits >> k & 1 == 1).then(|| (lanes.t[k], Vec2::new(lanes.b1[k], lanes.b2[k])))
    }

    /// A hit's bits, to compare answers exactly.
    fn bits(hit: Option<(f32, Vec2)>) -> Option<[u32; 3]> {
        hit.map(|(t, b)| [t.to_bits(), b.x.to_bits(), b.y.to_bits()])
    }

    /// Columns taken in an order hold, at entry `j`, triangle `order[j]`,
    /// across several of the blocks filled in parallel, and zeros past the end.
    #[test]
    fn columns_in_order_hold_the_ordered_triangles() {
        let mut rng = StdRng::seed_from_u64(3);
        let n = 10_007;
        let tris: Vec<[Vec3; 3]> =
            (0..n).map(|_| [(); 3].map(|_| Vec3::new(rng.gen(), rng.gen(), rng.gen()))).collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        (0..n).for_each(|i| order.swap(i, rng.gen_range(0..n)));
        let columns = TriangleColumns::in_order(&tris, &order);
        assert_eq!(columns.len(), n);
        assert!((0..n).all(|j| columns.get(j) == tris[order[j] as usize]));
        assert!((0..9).all(|c| columns.lanes(c, n) == f32x8::ZERO));
        assert!((0..n).all(|j| TriangleColumns::new(&tris).get(j) == tris[j]));
    }

    /// Eight lanes answer what eight one-triangle tests answer, bit for bit:
    /// random triangles and rays, rays aimed at vertices and edges (where the
    /// f64 decision may be taken), degenerate triangles, lanes past the count.
    #[test]
    fn eight_lanes_answer_as_one_triangle_tests_do() {
        let mut rng = StdRng::seed_from_u64(7);
        let mut r = || rng.gen_range(-1.0f32..1.0);
        let mut hits = 0;
        for round in 0..4000 {
            let mut tris: Vec<[Vec3; 3]> =
                (0..LANES).map(|_| [(); 3].map(|_| Vec3::new(r(), r(), r() + 3.0))).collect();
            // A degenerate triangle, and a ray through a vertex or an edge midpoint.
            tris[round % LANES] = [tris[0][0]; 3];
            let k = (round / LANES) % LANES;
            let aim = if round % 3 == 0 { tris[k][0] } else { (tris[k][1] + tris[k][2]) * 0.5 };
            let origin = Vec3::new(r(), r(), r() - 2.0);
            let dir = if round % 2 == 0 { aim - origin } else { Vec3::new(r(), r(), 1.0) };
            let sr = ShearedRay::new(&Ray { origin, dir });
            let columns = TriangleColumns::new(&tris);
            let (t_min, t_max) = (0.0, if round % 5 == 0 { 1.0 } else { f32::INFINITY });
            for count in [LANES, 5] {
                let lanes = sr.intersect_lanes(&columns, 0, count, t_min, t_max);
                for (i, tri) in tris.iter().enumerate() {
                    let one = sr.intersect(tri, t_min, t_max).filter(|_| i < count);
                    assert_eq!(bits(one), bits(lane_hit(&lanes, i)), "round {round} lane {i}");
                    hits += usize::from(one.is_some());
                }
            }
        }
        assert!(hits > 2000, "{hits} hits: the rays must hit often enough to mean anything");
        assert_eq!(TriangleColumns::new(&[]).len(), 0);
    }

    /// Eight rays in lanes answer what eight one-ray tests answer, bit for
    /// bit: rays along every axis both ways (the shear's permutation differs
    /// lane to lane) and with two axes of equal length, rays aimed at
    /// vertices and edges, a degenerate triangle, a limit per lane, lanes
    /// left out.
    #[test]
    fn eight_rays_in_lanes_answer_as_one_ray_tests_do() {
        let mut rng = StdRng::seed_from_u64(9);
        let mut r = || rng.gen_range(-1.0f32..1.0);
        let mut hits = 0;
        for round in 0..3000 {
            let mut tri = [(); 3].map(|_| Vec3::new(r(), r(), r()));
            if round % 7 == 0 {
                tri[2] = tri[1];
            }
            let rays: [Ray; LANES] = std::array::from_fn(|k| {
                let origin = Vec3::new(r(), r(), r()) * 3.0;
                let aim = match (round + k) % 3 {
                    0 => tri[k % 3],
                    1 => (tri[0] + tri[1]) * 0.5,
                    _ => Vec3::new(r(), r(), r()) * 0.5,
                };
                if k == 7 && round % 2 == 0 {
                    // Two axes of equal length: the dominant axis is chosen by a tie.
                    let c = r();
                    let dir = Vec3::new(c, -c, 0.4 * c * r());
                    return Ray { origin: aim - dir * 2.0, dir };
                }
                Ray { origin, dir: aim - origin }
            });
            let t_max: [f32; LANES] = std::array::from_fn(|k| if k % 3 == 0 { 0.9 } else { f32::INFINITY });
            let used = if round % 4 == 0 { 0b1011_0110 } else { 0xff };
            let columns = TriangleColumns::new(&[tri]);
            let lanes = RayLanes::new(&rays).intersect_triangle(&columns, 0, used, 0.0, f32x8::from(t_max));
            for (k, ray) in rays.iter().enumerate() {
                let one = ShearedRay::new(ray).intersect(&tri, 0.0, t_max[k]).filter(|_| used >> k & 1 == 1);
                assert_eq!(bits(one), bits(lane_hit(&lanes, k)), "round {round} lane {k}");
                hits += usize::from(one.is_some());
            }
        }
        assert!(hits > 5000, "{hits} hits: the rays must hit often enough to mean anything");
    }

    /// Rays through the shared edge of a quad split in two always hit one half.
    #[test]
    fn no_ray_slips_through_a_shared_edge() {
        let (a, b, c, d) = (
            Vec3::new(-1.0, -1.0, 3.0),
            Vec3::new(1.0, -1.0, 3.3),
            Vec3::new(1.0, 1.0, 2.7),
            Vec3::new(-1.0, 1.0, 3.1),
        );
        let (t1, t2) = ([a, b, c], [a, c, d]);
        for i in 1..2000 {
            // On the diagonal, away from its ends (the quad's corners, which a ray
            // may pass just outside of).
            let s = i as f32 / 2000.0;
            let p = a.lerp(c, s);
            let r = ray([0.1, -0.2, 0.0], (p - Vec3::new(0.1, -0.2, 0.0)).to_array());
            let sr = ShearedRay::new(&r);
            let hit =
                sr.intersect(&t1, 0.0, f32::INFINITY).is_some() || sr.intersect(&t2, 0.0, f32::INFINITY).is_some();
            assert!(hit, "ray {i} slipped through");
        }
    }

    #[test]
    fn agrees_with_f64_moller_trumbore() {
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32 * 4.0 - 2.0
        };
        let mut agree = 0;
        for _ in 0..5000 {
            let tri = [
                Vec3::new(rnd(), rnd(), rnd() + 5.0),
                Vec3::new(rnd(), rnd(), rnd() + 5.0),
                Vec3::new(rnd(), rnd(), rnd() + 5.0),
            ];
            let r = ray([rnd() * 0.2, rnd() * 0.2, 0.0], [rnd() * 0.3, rnd() * 0.3, 1.0]);
            let a = ShearedRay::new(&r).intersect(&tri, 0.0, f32::INFINITY);
            let b = intersect_f64(&r, &tri);
            match (a, b) {
                (Some((t, _)), Some((u, _))) => assert!(((t as f64 - u) / u).abs() < 1e-5),
                (None, None) => {}
                _ => continue, // grazing: within rounding of an edge
            }
            agree += 1;
        }
        assert!(agree > 4990, "{agree}");
    }
}
