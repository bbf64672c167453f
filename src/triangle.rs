//! Watertight ray/triangle intersection (Woop, Benthin and Wald, "Watertight
//! Ray/Triangle Intersection", JCGT 2013): the triangle is moved into a frame where
//! the ray runs along +z, and the three edge functions are evaluated there. A ray
//! through an edge or vertex shared by two triangles hits at least one of them —
//! never slips between — which Möller–Trumbore does not promise.

use glam::{DVec3, Vec2, Vec3};

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
        let kz = d.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let unit = |k: usize| Vec3::AXES[k];
        let (sx, sy) = (d[kx] / d[kz], d[ky] / d[kz]);
        let rows = [unit(kx) - sx * unit(kz), unit(ky) - sy * unit(kz), unit(kz)];
        ShearedRay { origin: ray.origin, rows, inv_dz: 1.0 / d[kz] }
    }

    /// Distance and barycentrics (b1, b2) of the hit with triangle `p` in
    /// `(t_min, t_max)`, from either side.
    #[must_use]
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
            // On an edge in f32: decide in f64 so neighbours agree.
            let e = |p: Vec3, q: Vec3| (q.x as f64 * p.y as f64 - q.y as f64 * p.x as f64) as f32;
            (u, v, w) = (e(b, c), e(c, a), e(a, b));
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
