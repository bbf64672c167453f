//! Seed 002 eq. 1, eight pixels at a time.
//!
//! The scalar path ([`super::surface`] + [`super::phong`]) says what is computed;
//! this module computes the same thing for eight neighbouring pixels of a row in
//! SIMD lanes (`wide::f32x8`), which is what makes per-pixel Phong affordable on a
//! CPU. Per lane it gathers the pixel's prepared triangle and material, then runs
//! the ray/plane intersection, normal interpolation and every light's ambient,
//! diffuse and specular terms as vector arithmetic. A test holds it to the scalar
//! path.

use glam::{Vec2, Vec3};
use wide::f32x8;

use super::phong::Coefficients;
use super::surface::{PreparedTriangle, SurfacePoint};
use crate::scene::camera::PixelRays;
use crate::scene::{Falloff, Light, LightKind};

/// Pixels shaded together.
pub const LANES: usize = 8;

type F = f32x8;

/// Eight 3-vectors, one per lane.
#[derive(Debug, Clone, Copy)]
struct V3 {
    x: F,
    y: F,
    z: F,
}

impl V3 {
    fn splat(v: Vec3) -> V3 {
        V3 { x: F::splat(v.x), y: F::splat(v.y), z: F::splat(v.z) }
    }
    fn dot(self, o: V3) -> F {
        self.x.mul_add(o.x, self.y.mul_add(o.y, self.z * o.z))
    }
    fn cross(self, o: V3) -> V3 {
        V3 { x: self.y * o.z - self.z * o.y, y: self.z * o.x - self.x * o.z, z: self.x * o.y - self.y * o.x }
    }
    fn add(self, o: V3) -> V3 {
        V3 { x: self.x + o.x, y: self.y + o.y, z: self.z + o.z }
    }
    fn sub(self, o: V3) -> V3 {
        V3 { x: self.x - o.x, y: self.y - o.y, z: self.z - o.z }
    }
    fn mul(self, o: V3) -> V3 {
        V3 { x: self.x * o.x, y: self.y * o.y, z: self.z * o.z }
    }
    fn scale(self, s: F) -> V3 {
        V3 { x: self.x * s, y: self.y * s, z: self.z * s }
    }
    fn select(mask: F, a: V3, b: V3) -> V3 {
        V3 { x: mask.select(a.x, b.x), y: mask.select(a.y, b.y), z: mask.select(a.z, b.z) }
    }
    /// Unit vector, or `fallback` where the length is zero.
    fn normalize_or(self, fallback: V3) -> V3 {
        let len2 = self.dot(self);
        let ok = len2.simd_gt(F::splat(f32::MIN_POSITIVE));
        let n = self.scale(rsqrt(len2.max(F::splat(f32::MIN_POSITIVE))));
        V3::select(ok, n, fallback)
    }
    fn lane(&self, i: usize) -> Vec3 {
        Vec3::new(self.x.as_array()[i], self.y.as_array()[i], self.z.as_array()[i])
    }
}

/// `1/√x` to about 23 bits: the hardware estimate refined by one Newton step,
/// several times cheaper than a square root and a division.
fn rsqrt(x: F) -> F {
    let y = x.recip_sqrt();
    y * (F::splat(1.5) - F::splat(0.5) * x * y * y)
}

/// Per-lane values gathered one lane at a time before the vector work.
#[derive(Debug, Clone, Copy, Default)]
struct Gather {
    v: [[f32; LANES]; 3],
}

impl Gather {
    fn set(&mut self, i: usize, v: Vec3) {
        self.v[0][i] = v.x;
        self.v[1][i] = v.y;
        self.v[2][i] = v.z;
    }
    fn fill(&mut self, v: Vec3) {
        self.v = [[v.x; LANES], [v.y; LANES], [v.z; LANES]];
    }
    fn load(&self) -> V3 {
        V3 { x: F::new(self.v[0]), y: F::new(self.v[1]), z: F::new(self.v[2]) }
    }
}

/// One block of up to eight pixels whose triangles and materials are known.
#[derive(Debug, Default)]
pub struct Block {
    a: Gather,
    e1: Gather,
    e2: Gather,
    n: [Gather; 3],
    geometric: Gather,
    /// Texture u of the three vertices (x, y, z = vertex 0, 1, 2).
    u: Gather,
    /// Texture v of the three vertices.
    v: Gather,
    material: [usize; LANES],
    ka: Gather,
    kd: Gather,
    ks: Gather,
    ke: Gather,
    shininess: [f32; LANES],
    textured: [bool; LANES],
    /// Which lanes hold a pixel that sees something.
    pub live: [bool; LANES],
}

impl Block {
    /// Empties every lane.
    pub fn clear(&mut self) {
        self.live = [false; LANES];
        self.textured = [false; LANES];
    }

    /// Puts pixel `i` of the block on `tri`, with constant coefficients `k` if its
    /// material has no maps (`None`: sampled after the intersection).
    pub fn set(&mut self, i: usize, tri: &PreparedTriangle, k: Option<&Coefficients>) {
        let g = tri.geometry();
        self.a.set(i, g.a);
        self.e1.set(i, g.e1);
        self.e2.set(i, g.e2);
        for (slot, n) in self.n.iter_mut().zip(g.normals) {
            slot.set(i, n);
        }
        self.geometric.set(i, g.geometric);
        let uv = g.uvs.unwrap_or_default();
        self.u.set(i, Vec3::new(uv[0].x, uv[1].x, uv[2].x));
        self.v.set(i, Vec3::new(uv[0].y, uv[1].y, uv[2].y));
        self.material[i] = tri.material;
        self.live[i] = true;
        self.textured[i] = k.is_none();
        if let Some(k) = k {
            self.set_coefficients(i, k);
        }
    }

    /// Puts every pixel of the block on `tri` (the common case inside a large
    /// triangle): the same as [`Block::set`] on each lane, with vector stores.
    pub fn set_all(&mut self, tri: &PreparedTriangle, k: Option<&Coefficients>) {
        let g = tri.geometry();
        self.a.fill(g.a);
        self.e1.fill(g.e1);
        self.e2.fill(g.e2);
        for (slot, n) in self.n.iter_mut().zip(g.normals) {
            slot.fill(n);
        }
        self.geometric.fill(g.geometric);
        let uv = g.uvs.unwrap_or_default();
        self.u.fill(Vec3::new(uv[0].x, uv[1].x, uv[2].x));
        self.v.fill(Vec3::new(uv[0].y, uv[1].y, uv[2].y));
        self.material = [tri.material; LANES];
        self.live = [true; LANES];
        self.textured = [k.is_none(); LANES];
        if let Some(k) = k {
            let (ka, kd, ks, ke, n) = k.parts();
            self.ka.fill(ka);
            self.kd.fill(kd);
            self.ks.fill(ks);
            self.ke.fill(ke);
            self.shininess = [n; LANES];
        }
    }

    fn set_coefficients(&mut self, i: usize, k: &Coefficients) {
        let (ka, kd, ks, ke, n) = k.parts();
        self.ka.set(i, ka);
        self.kd.set(i, kd);
        self.ks.set(i, ks);
        self.ke.set(i, ke);
        self.shininess[i] = n;
    }

    /// Shades the block: `x0` is the first pixel's column on row `y`; lanes with a
    /// textured material get their coefficients from `coefficients_at`. Writes the
    /// colours of live lanes to `out`.
    pub fn shade(
        &mut self,
        rays: &PixelRays,
        (x0, y): (usize, usize),
        lights: &[Light],
        coefficients_at: impl Fn(&SurfacePoint) -> Coefficients,
        out: &mut [Vec3],
    ) {
        let (origin, dir) = lane_rays(rays, x0, y);
        let (a, e1, e2) = (self.a.load(), self.e1.load(), self.e2.load());
        // Möller–Trumbore against the plane (see surface::intersect_plane).
        let pvec = dir.cross(e2);
        let det = e1.dot(pvec);
        let det = det.abs().simd_lt(F::splat(f32::MIN_POSITIVE)).select(F::splat(f32::MIN_POSITIVE), det);
        let inv = F::ONE / det;
        let tvec = origin.sub(a);
        let qvec = tvec.cross(e1);
        let (b1, b2, t) = (tvec.dot(pvec) * inv, dir.dot(qvec) * inv, e2.dot(qvec) * inv);
        let b0 = F::ONE - b1 - b2;
        let interp = |g: &[Gather; 3]| g[0].load().scale(b0).add(g[1].load().scale(b1)).add(g[2].load().scale(b2));
        let n = interp(&self.n).normalize_or(self.geometric.load());
        let to_eye = V3 { x: -dir.x, y: -dir.y, z: -dir.z };
        let facing = n.dot(to_eye).simd_lt(F::ZERO);
        let n = V3::select(facing, V3 { x: -n.x, y: -n.y, z: -n.z }, n);
        let p = origin.add(dir.scale(t));
        self.sample_textures(b0, b1, b2, (&p, &n, &to_eye), &coefficients_at);
        let rgb = self.lights(lights, &p, &n, &to_eye);
        for (i, px) in out.iter_mut().enumerate() {
            if self.live[i] {
                *px = rgb.lane(i);
            }
        }
    }

    fn sample_textures(&mut self, b0: F, b1: F, b2: F, (p, n, v): (&V3, &V3, &V3), at: &impl Fn(&SurfacePoint) -> Coefficients) {
        if !self.textured.iter().zip(&self.live).any(|(t, l)| *t && *l) {
            return;
        }
        let (u, w) = (self.u.load(), self.v.load());
        let uu = u.x * b0 + u.y * b1 + u.z * b2;
        let vv = w.x * b0 + w.y * b1 + w.z * b2;
        for i in 0..LANES {
            if self.textured[i] && self.live[i] {
                let s = SurfacePoint {
                    position: p.lane(i),
                    normal: n.lane(i),
                    to_eye: v.lane(i),
                    uv: Vec2::new(uu.as_array()[i], vv.as_array()[i]),
                    material: self.material[i],
                };
                let k = at(&s);
                self.set_coefficients(i, &k);
            }
        }
    }

    fn lights(&self, lights: &[Light], p: &V3, n: &V3, v: &V3) -> V3 {
        let (ka, kd, ks) = (self.ka.load(), self.kd.load(), self.ks.load());
        let shininess = F::new(self.shininess);
        let n0 = self.shininess[0];
        let whole = (self.shininess.iter().all(|&n| n == n0) && n0.fract() == 0.0 && (1.0..=4096.0).contains(&n0)).then_some(n0 as u32);
        let ambient: Vec3 = lights.iter().map(|l| l.color * l.ambient).sum();
        let mut diffuse = V3::splat(Vec3::ZERO);
        let mut specular = V3::splat(Vec3::ZERO);
        for light in lights {
            let (l, radiance) = incident(light, p);
            let cos_theta = n.dot(l);
            let lit = cos_theta.simd_gt(F::ZERO);
            let r = n.scale(cos_theta + cos_theta).sub(l);
            let cos_alpha = r.dot(*v).max(F::ZERO);
            let spec = power(cos_alpha, shininess, whole);
            let d = lit.select(cos_theta, F::ZERO);
            let s = lit.select(spec, F::ZERO);
            diffuse = diffuse.add(radiance.scale(d));
            specular = specular.add(radiance.scale(s));
        }
        ka.mul(V3::splat(ambient)).add(kd.mul(diffuse)).add(ks.mul(specular)).add(self.ke.load())
    }
}

/// `x^n` per lane for x ≥ 0: by repeated squaring when every lane has the same
/// whole exponent `whole` (exact, and several times faster), else through
/// exp/log.
fn power(x: F, n: F, whole: Option<u32>) -> F {
    match whole {
        Some(mut e) => {
            let (mut base, mut acc) = (x, F::ONE);
            while e > 0 {
                if e & 1 == 1 {
                    acc *= base;
                }
                base *= base;
                e >>= 1;
            }
            acc
        }
        None => x.simd_gt(F::ZERO).select(x.powf_simd(n), F::ZERO),
    }
}

/// Unit direction towards the light and radiance, per lane (as `Light::incident`).
fn incident(light: &Light, p: &V3) -> (V3, V3) {
    let scale = V3::splat(light.color * light.intensity);
    let positional = |pos: Vec3| {
        let d = V3::splat(pos).sub(*p);
        let dist2 = d.dot(d).max(F::splat(1e-12));
        let l = d.scale(rsqrt(dist2));
        let att = match light.falloff {
            Falloff::None => F::ONE,
            Falloff::InverseSquare => F::ONE / dist2,
        };
        (l, att)
    };
    match light.kind {
        LightKind::Directional { direction } => (V3::splat(-direction), scale),
        LightKind::Point { position } => {
            let (l, att) = positional(position);
            (l, scale.scale(att))
        }
        LightKind::Spot { position, direction, inner, outer } => {
            let (l, att) = positional(position);
            let cos = -l.dot(V3::splat(direction));
            let (ci, co) = (inner.cos(), outer.cos());
            let t = if ci > co {
                ((cos - F::splat(co)) / F::splat(ci - co)).max(F::ZERO).min(F::ONE)
            } else {
                cos.simd_lt(F::splat(co)).select(F::ZERO, F::ONE)
            };
            let cone = t * t * (F::splat(3.0) - t - t);
            (l, scale.scale(att * cone))
        }
    }
}

/// Origins and unit directions of the rays through pixels `x0 .. x0 + 8` of row `y`.
fn lane_rays(rays: &PixelRays, x0: usize, y: usize) -> (V3, V3) {
    const STEPS: F = F::new([0.5, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5]);
    let xs = F::splat(x0 as f32) + STEPS;
    let ndc_x = xs * F::splat(2.0 / rays.size.x) - F::ONE;
    let ndc_y = F::splat(1.0 - 2.0 * (y as f32 + 0.5) / rays.size.y);
    let offset = V3::splat(rays.right).scale(ndc_x).add(V3::splat(rays.up).scale(ndc_y));
    if rays.ortho {
        (V3::splat(rays.origin).add(offset), V3::splat(rays.forward.normalize()))
    } else {
        let d = V3::splat(rays.forward).add(offset);
        (V3::splat(rays.origin), d.normalize_or(V3::splat(rays.forward)))
    }
}
