//! Seed 002 eq. 1, eight pixels at a time.
//!
//! The scalar path (`surface.rs` + `phong.rs`) says what is computed;
//! this module computes the same thing for eight neighbouring pixels of a row in
//! SIMD lanes (`wide::f32x8`), which is what makes per-pixel Phong affordable on a
//! CPU. Per lane it gathers the pixel's prepared triangle and material, then runs
//! the ray/plane intersection, normal interpolation and every light's ambient,
//! diffuse and specular terms as vector arithmetic. A test holds it to the scalar
//! path.

use glam::{Vec2, Vec3};
use wide::f32x8;

use super::phong::{Coefficients, Component, ComponentSet, Components};
use super::reflection_map::Mirror;
use super::surface::{PreparedTriangle, SurfacePoint, TriangleGeometry};
use crate::camera::PixelRays;
use crate::scene::{Falloff, Light, LightKind};
use crate::shadows::{ReceiverLanes, ShadowTerm};

/// Pixels shaded together.
pub const LANES: usize = 8;

/// How a pass writes its colour into the accumulation buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Blend {
    /// The first pass of a frame: replaces what is there.
    Replace,
    /// Every later pass: adds to it (seed 002 eq. 4's sum).
    Add,
}

impl Blend {
    /// Writes `c` into `px`.
    #[inline(always)]
    pub fn apply(self, px: &mut Vec3, c: Vec3) {
        match self {
            Blend::Replace => *px = c,
            Blend::Add => *px += c,
        }
    }
}

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
#[inline(always)]
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
    km: Gather,
    shininess: [f32; LANES],
    textured: [bool; LANES],
    /// ∂P/∂u and ∂P/∂v of each lane's triangle (for its normal map).
    tangents: [[Vec3; 2]; LANES],
    /// Each lane's triangle's map to its second texture coordinates.
    second: [glam::Affine2; LANES],
    /// Each lane's triangle's vertex colours (white without them).
    colors: [[Vec3; 3]; LANES],
    /// Which lanes hold a pixel that sees something.
    pub live: [bool; LANES],
    /// The object each lane's triangle belongs to.
    object: [u32; LANES],
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
        self.object[i] = tri.item.object;
        self.live[i] = true;
        self.textured[i] = k.is_none();
        self.tangents[i] = g.tangents;
        self.second[i] = g.second;
        self.colors[i] = g.colors.unwrap_or([Vec3::ONE; 3]);
        if let Some(k) = k {
            self.set_coefficients(i, k);
        }
    }

    fn set_coefficients(&mut self, i: usize, k: &Coefficients) {
        let (ka, kd, ks, ke, n) = k.parts();
        self.ka.set(i, ka);
        self.kd.set(i, kd);
        self.ks.set(i, ks);
        self.ke.set(i, ke);
        self.km.set(i, k.km());
        self.shininess[i] = n;
    }

    /// The lanes' inputs, loaded into vectors.
    fn inputs(&self) -> LaneInputs {
        // Only the lanes in use decide the exponent's path: an empty lane holds
        // whatever an earlier block left there, and the result must not depend
        // on which blocks a worker shaded before.
        let mut used = self.shininess.iter().zip(self.live).filter_map(|(&n, live)| live.then_some(n));
        let first = used.next();
        let whole = first.filter(|&n0| used.all(|n| n == n0)).and_then(whole_exponent);
        LaneInputs {
            exponents: self.shininess.map(|n| whole_exponent(n).unwrap_or(0)),
            a: self.a.load(),
            e1: self.e1.load(),
            e2: self.e2.load(),
            n: [self.n[0].load(), self.n[1].load(), self.n[2].load()],
            geometric: self.geometric.load(),
            ka: self.ka.load(),
            kd: self.kd.load(),
            ks: self.ks.load(),
            ke: self.ke.load(),
            shininess: F::new(self.shininess),
            whole,
            object: self.object,
        }
    }

    /// Shades the block: `x0` is the first pixel's column on the row of `rays`; lanes with a
    /// textured material get their coefficients from `coefficients_at`. Writes the
    /// colours of live lanes to `out`, and, with `mirrors`, each live lane's
    /// [`Mirror`] where `reflects` says its material reflects.
    #[expect(clippy::too_many_arguments, reason = "the block's row, its pass and its two outputs")]
    pub fn shade(
        &mut self,
        rays: &RowRays,
        x0: usize,
        lighting: &Lighting,
        coefficients_at: impl Fn(&mut SurfacePoint) -> Coefficients,
        blend: Blend,
        out: &mut [Vec3],
        mirrors: Option<(&mut [Mirror], &[bool])>,
    ) {
        let mut inputs = self.inputs();
        let mut s = surface(&inputs, rays, x0);
        if self.sample_textures(&inputs, &mut s, rays, x0, &coefficients_at) {
            let textured = self.inputs();
            (inputs.ka, inputs.kd, inputs.ks, inputs.ke) = (textured.ka, textured.kd, textured.ks, textured.ke);
            (inputs.shininess, inputs.whole, inputs.exponents) =
                (textured.shininess, textured.whole, textured.exponents);
        }
        if let Some((mirrors, reflects)) = mirrors {
            let r = mirror_directions(&s);
            let km = self.km.load();
            for (i, m) in mirrors.iter_mut().enumerate() {
                if self.live[i] && reflects[self.material[i]] {
                    *m = Mirror { km: km.lane(i), r: r.lane(i) };
                }
            }
        }
        let rgb = lighting.shade(&inputs, &s, lighting.open_lanes(x0, rays.y));
        for (i, px) in out.iter_mut().enumerate() {
            if self.live[i] {
                blend.apply(px, rgb.lane(i));
            }
        }
    }

    /// Samples the maps of textured lanes (their normal maps tilt `s`'s
    /// normals); false if there were none. Each lane's footprint comes from ray
    /// differentials: the same triangle's plane met by the rays one pixel to the
    /// right and one row below.
    fn sample_textures(
        &mut self,
        inputs: &LaneInputs,
        s: &mut LaneSurface,
        rays: &RowRays,
        x0: usize,
        at: &impl Fn(&mut SurfacePoint) -> Coefficients,
    ) -> bool {
        if !self.textured.iter().zip(&self.live).any(|(t, l)| *t && *l) {
            return false;
        }
        let (u, w) = (self.u.load(), self.v.load());
        let uv_of = |s: &LaneSurface| {
            let [b0, b1, b2] = s.weights;
            ((u.x * b0 + u.y * b1 + u.z * b2).to_array(), (w.x * b0 + w.y * b1 + w.z * b2).to_array())
        };
        let (uu, vv) = uv_of(s);
        let (ur, vr) = uv_of(&surface(inputs, rays, x0 + 1));
        let (ud, vd) = uv_of(&surface(inputs, &rays.below(), x0));
        let mut normals = Gather::default();
        let weights = s.weights.map(|w| w.to_array());
        for i in 0..LANES {
            let normal = s.n.lane(i);
            normals.set(i, normal);
            if self.textured[i] && self.live[i] {
                let uv = Vec2::new(uu[i], vv[i]);
                let to_eye = s.v.lane(i);
                let geometric = inputs.geometric.lane(i);
                let mut point = SurfacePoint {
                    position: s.p.lane(i),
                    normal,
                    to_eye,
                    uv,
                    duv: [Vec2::new(ur[i], vr[i]) - uv, Vec2::new(ud[i], vd[i]) - uv],
                    tangents: self.tangents[i],
                    material: self.material[i],
                    front: geometric.dot(to_eye) >= 0.0,
                    color: (0..3).map(|k| self.colors[i][k] * weights[k][i]).sum(),
                    second: self.second[i],
                };
                let k = at(&mut point);
                self.set_coefficients(i, &k);
                normals.set(i, point.normal);
            }
        }
        s.n = normals.load();
        true
    }
}

/// Shades a run of whole blocks (`out.len()` a multiple of eight) whose pixels all
/// show `tri` with the map-free coefficients `k`, on the row `rays` describes,
/// starting at column `x0`: the inputs are broadcast into vector registers once for
/// the whole run, skipping the per-lane gather.
#[expect(clippy::too_many_arguments, reason = "the run's triangle and row, its pass and its two outputs")]
pub fn shade_run(
    tri: &PreparedTriangle,
    k: &Coefficients,
    rays: &RowRays,
    x0: usize,
    lighting: &Lighting,
    blend: Blend,
    out: &mut [Vec3],
    mut mirrors: Option<&mut [Mirror]>,
) {
    let g = tri.geometry();
    let inputs = LaneInputs::broadcast(tri, &g, Some(k));
    let row = TriangleRow::new(&g, &rays.line(x0));
    for (b, out) in out.chunks_exact_mut(LANES).enumerate() {
        let s = row.surface(&inputs, b * LANES);
        if let Some(mirrors) = mirrors.as_deref_mut() {
            let r = mirror_directions(&s);
            for (i, m) in mirrors[b * LANES..][..LANES].iter_mut().enumerate() {
                *m = Mirror { km: k.km(), r: r.lane(i) };
            }
        }
        let rgb = lighting.shade(&inputs, &s, lighting.open_lanes(x0 + b * LANES, rays.y));
        let (r, g, b) = (rgb.x.to_array(), rgb.y.to_array(), rgb.z.to_array());
        for (i, px) in out.iter_mut().enumerate() {
            blend.apply(px, Vec3::new(r[i], g[i], b[i]));
        }
    }
}

/// The view's mirror direction R = 2(N·V)N − V of each lane.
#[inline(always)]
fn mirror_directions(s: &LaneSurface) -> V3 {
    s.n.scale(s.n.dot(s.v) * F::splat(2.0)).sub(s.v)
}

/// The position and unit normal (facing the eye) that each of `count` pixels
/// from column `x0` of the row `rays` describes sees on `tri`, eight at a
/// time, as [`shade_run`] finds them: `at(i, position, normal)` for pixel
/// `x0 + i`.
pub fn run_surfaces(
    tri: &PreparedTriangle,
    rays: &RowRays,
    x0: usize,
    count: usize,
    mut at: impl FnMut(usize, Vec3, Vec3),
) {
    let g = tri.geometry();
    let inputs = LaneInputs::broadcast(tri, &g, None);
    let row = TriangleRow::new(&g, &rays.line(x0));
    for k0 in (0..count).step_by(LANES) {
        let s = row.surface(&inputs, k0);
        for i in 0..LANES.min(count - k0) {
            at(k0 + i, s.p.lane(i), s.n.lane(i));
        }
    }
}

/// One triangle and material per lane, in vector registers.
#[derive(Debug, Clone, Copy)]
struct LaneInputs {
    a: V3,
    e1: V3,
    e2: V3,
    n: [V3; 3],
    geometric: V3,
    ka: V3,
    kd: V3,
    ks: V3,
    ke: V3,
    shininess: F,
    /// The exponent shared by all lanes when it is a whole number.
    whole: Option<u32>,
    /// Each lane's exponent when it is a whole number, else 0: a lane's
    /// power is the same whatever its neighbours' exponents.
    exponents: [u32; LANES],
    /// The object each lane's surface belongs to (the shadow's receiver).
    object: [u32; LANES],
}

impl LaneInputs {
    /// `tri` (its geometry `g`) in every lane, with the material
    /// coefficients `k` (zero without).
    fn broadcast(tri: &PreparedTriangle, g: &TriangleGeometry, k: Option<&Coefficients>) -> Self {
        let zero = Vec3::ZERO;
        let (ka, kd, ks, ke, n) = k.map_or((zero, zero, zero, zero, 1.0), Coefficients::parts);
        LaneInputs {
            a: V3::splat(g.a),
            e1: V3::splat(g.e1),
            e2: V3::splat(g.e2),
            n: g.normals.map(V3::splat),
            geometric: V3::splat(g.geometric),
            ka: V3::splat(ka),
            kd: V3::splat(kd),
            ks: V3::splat(ks),
            ke: V3::splat(ke),
            shininess: F::splat(n),
            whole: whole_exponent(n),
            exponents: [whole_exponent(n).unwrap_or(0); LANES],
            object: [tri.item.object; LANES],
        }
    }

    /// The lanes' receivers of shadows: their objects and triangles' planes.
    #[inline(always)]
    fn receivers(&self) -> ReceiverLanes {
        ReceiverLanes { objects: self.object, planes: [self.geometric.x, self.geometric.y, self.geometric.z] }
    }
}

fn whole_exponent(n: f32) -> Option<u32> {
    (n.fract() == 0.0 && (1.0..=4096.0).contains(&n)).then_some(n as u32)
}

/// The surface each lane sees.
struct LaneSurface {
    p: V3,
    /// Unit normal facing the eye.
    n: V3,
    /// Unit vector to the eye.
    v: V3,
    /// Barycentric weights of the three vertices.
    weights: [F; 3],
}

/// Ray/plane intersection (Möller–Trumbore, as `surface::intersect_plane`) and
/// normal interpolation for eight pixels.
#[inline(always)]
fn surface(inp: &LaneInputs, rays: &RowRays, x0: usize) -> LaneSurface {
    let (origin, dir) = rays.at(x0);
    let pvec = dir.cross(inp.e2);
    let det = inp.e1.dot(pvec);
    let det = det.abs().simd_lt(F::splat(f32::MIN_POSITIVE)).select(F::splat(f32::MIN_POSITIVE), det);
    let inv = F::ONE / det;
    let tvec = origin.sub(inp.a);
    let qvec = tvec.cross(inp.e1);
    let (b1, b2, t) = (tvec.dot(pvec) * inv, dir.dot(qvec) * inv, inp.e2.dot(qvec) * inv);
    let b0 = F::ONE - b1 - b2;
    let v = V3 { x: -dir.x, y: -dir.y, z: -dir.z };
    LaneSurface { p: origin.add(dir.scale(t)), n: facing_normal(inp, [b0, b1, b2], &v), v, weights: [b0, b1, b2] }
}

/// A polynomial `c + k·(b + k·q)` in the pixel offset `k` along a row.
#[derive(Debug, Clone, Copy)]
struct RowPolynomial {
    c: f32,
    b: f32,
    q: f32,
}

impl RowPolynomial {
    /// The product of two affine functions `(u + k·du)·(v + k·dv)`, each a dot
    /// product of vectors affine in `k`.
    fn dot(u: Vec3, du: Vec3, v: Vec3, dv: Vec3) -> Self {
        RowPolynomial { c: u.dot(v), b: du.dot(v) + u.dot(dv), q: du.dot(dv) }
    }
    #[inline(always)]
    fn at(&self, k: F) -> F {
        k.mul_add(k.mul_add(F::splat(self.q), F::splat(self.b)), F::splat(self.c))
    }
}

/// One triangle seen along a run of one row, with the ray/plane intersection
/// done once for the whole run.
///
/// Along a row the rays are `o(k) + s·d(k)` with `o` and `d` affine in the pixel
/// offset `k` (a perspective camera moves `d`, an orthographic one `o`). In
/// Möller–Trumbore's solution every term is then a product of two affine
/// functions: with `p = d × e2`, `t = o − a`, `q = t × e1`, the barycentric
/// weights are `b1 = (t·p) / (e1·p)` and `b2 = (d·q) / (e1·p)`, ratios of
/// polynomials in `k` of degree ≤ 2 (the quadratic terms vanish for both
/// cameras; they are kept so the statement is exact for any affine rays). So a
/// pixel costs three polynomial evaluations and one division, and the point is
/// `a + b1·e1 + b2·e2`; this is perspective-correct interpolation.
#[derive(Debug, Clone, Copy)]
struct TriangleRow {
    /// `t·p`, `d·q` and `e1·p` along the row.
    weights: [RowPolynomial; 3],
    /// The unnormalised ray direction at the run's start and per pixel.
    dir: (Vec3, Vec3),
}

impl TriangleRow {
    fn new(g: &TriangleGeometry, line: &RayLine) -> Self {
        let (a, e1, e2) = (g.a, g.e1, g.e2);
        let (p, dp) = (line.dir.cross(e2), line.dir_step.cross(e2));
        let (t, dt) = (line.origin - a, line.origin_step);
        let (q, dq) = (t.cross(e1), dt.cross(e1));
        let weights = [
            RowPolynomial::dot(t, dt, p, dp),
            RowPolynomial::dot(line.dir, line.dir_step, q, dq),
            RowPolynomial::dot(e1, Vec3::ZERO, p, dp),
        ];
        TriangleRow { weights, dir: (line.dir, line.dir_step) }
    }

    /// The surface seen by the eight pixels from offset `k0` of the run.
    #[inline(always)]
    fn surface(&self, inp: &LaneInputs, k0: usize) -> LaneSurface {
        const STEPS: F = F::new([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        let k = F::splat(k0 as f32) + STEPS;
        let det = self.weights[2].at(k);
        let det = det.abs().simd_lt(F::splat(f32::MIN_POSITIVE)).select(F::splat(f32::MIN_POSITIVE), det);
        let inv = F::ONE / det;
        let (b1, b2) = (self.weights[0].at(k) * inv, self.weights[1].at(k) * inv);
        let b0 = F::ONE - b1 - b2;
        let (d, dd) = (V3::splat(self.dir.0), V3::splat(self.dir.1));
        let dir = d.add(dd.scale(k));
        let v = V3 { x: -dir.x, y: -dir.y, z: -dir.z }.normalize_or(V3::splat(-self.dir.0));
        let p = inp.a.add(inp.e1.scale(b1)).add(inp.e2.scale(b2));
        LaneSurface { p, n: facing_normal(inp, [b0, b1, b2], &v), v, weights: [b0, b1, b2] }
    }
}

/// The interpolated unit normal at barycentric weights `w`, turned towards `v`.
#[inline(always)]
fn facing_normal(inp: &LaneInputs, w: [F; 3], v: &V3) -> V3 {
    let n = inp.n[0].scale(w[0]).add(inp.n[1].scale(w[1])).add(inp.n[2].scale(w[2])).normalize_or(inp.geometric);
    let facing = n.dot(*v).simd_lt(F::ZERO);
    V3::select(facing, V3 { x: -n.x, y: -n.y, z: -n.z }, n)
}

/// A light whose diffuse and specular a pass adds, with the shadow terms whose
/// mean multiplies them: one term, or an area light's jittered samples' (see
/// `passes.rs`).
pub type Direct<'a> = (&'a Light, &'a [ShadowTerm]);

/// What one shading pass adds (seed 002 eq. 4): the ambient of some lights, the
/// shadowed diffuse and specular of some lights, and perhaps emission.
#[derive(Debug, Clone)]
pub struct Lighting<'a> {
    direct: Vec<Direct<'a>>,
    ambient: Vec3,
    emission: bool,
    diffuse: f32,
    specular: f32,
    /// Each pixel's open share, which scales the ambient term (ambient
    /// occlusion found before the shading); `None`: open everywhere.
    open: Option<OpenShares<'a>>,
}

/// Each pixel's open share of ambient occlusion, in an image of the pixels
/// a visibility buffer holds (its first lane read), which scales the ambient
/// term where the pixels are shaded.
#[derive(Debug, Clone, Copy)]
pub struct OpenShares<'a> {
    shares: &'a [Vec3],
    width: usize,
    corner: (usize, usize),
}

impl<'a> OpenShares<'a> {
    /// The shares in `shares`, row by row, of the rectangle whose top-left
    /// pixel is `corner` and whose rows are `width` long.
    ///
    /// # Panics
    ///
    /// If `shares` is not a whole number of rows.
    #[must_use]
    pub fn new(shares: &'a [Vec3], width: usize, corner: (usize, usize)) -> Self {
        assert!(width > 0 && shares.len().is_multiple_of(width), "whole rows of shares");
        OpenShares { shares, width, corner }
    }

    /// The shares of the eight pixels from column `x` of row `y` (1 past
    /// the row's end).
    #[inline(always)]
    fn lanes(&self, x: usize, y: usize) -> F {
        let (x, y) = (x - self.corner.0, y - self.corner.1);
        let row = &self.shares[y * self.width..][..self.width];
        if let Some(run) = row.get(x..x + LANES) {
            return F::new(std::array::from_fn(|i| run[i].x));
        }
        let mut out = [1.0; LANES];
        for (o, s) in out.iter_mut().zip(&row[x.min(self.width)..]) {
            *o = s.x;
        }
        F::new(out)
    }
}

impl<'a> Lighting<'a> {
    /// The ambient terms of `ambient`, the diffuse and specular terms of `direct`
    /// (each multiplied by the mean of its shadow terms) and, if `emission`, Ke.
    #[must_use]
    pub fn pass(ambient: impl IntoIterator<Item = &'a Light>, direct: Vec<Direct<'a>>, emission: bool) -> Self {
        let ambient = ambient.into_iter().map(|l| l.color * l.ambient).sum();
        Lighting { direct, ambient, emission, diffuse: 1.0, specular: 1.0, open: None }
    }

    /// The same pass with its ambient term scaled by each pixel's share in
    /// `open` (the sub-pixel points of [`Lighting::shade_points`] are not).
    #[must_use]
    pub fn with_open(self, open: Option<OpenShares<'a>>) -> Self {
        Lighting { open, ..self }
    }

    /// The open shares of the eight pixels from column `x` of row `y`.
    #[inline(always)]
    fn open_lanes(&self, x: usize, y: usize) -> F {
        self.open.as_ref().map_or(F::ONE, |o| o.lanes(x, y))
    }

    /// The same pass keeping only the components in `parts` (an AOV).
    #[must_use]
    pub fn restricted(&self, parts: ComponentSet) -> Self {
        let keep = |c| f32::from(u8::from(parts.contains(c)));
        Lighting {
            direct: self.direct.clone(),
            ambient: self.ambient * keep(Component::Ambient),
            emission: self.emission && parts.contains(Component::Emission),
            diffuse: self.diffuse * keep(Component::Diffuse),
            specular: self.specular * keep(Component::Specular),
            open: self.open,
        }
    }

    /// Whether the pass adds nothing at all.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        let direct = !self.direct.is_empty() && (self.diffuse > 0.0 || self.specular > 0.0);
        !direct && self.ambient == Vec3::ZERO && !self.emission
    }

    /// Seed 002 eq. 1 summed over the pass's lights at up to eight points of
    /// any surfaces (`None`: an empty lane, left at zero), each with its
    /// material's coefficients there: the passes' arithmetic, lane for lane,
    /// for points that are not a row of pixels (sub-pixel samples).
    #[must_use]
    pub fn shade_points(&self, points: &[Option<(&Coefficients, &SurfacePoint, u32)>; LANES]) -> [Components; LANES] {
        let Some(first) = points.iter().flatten().next() else { return [Components::default(); LANES] };
        let (mut k, mut p, mut n, mut v) = (Block::default(), Gather::default(), Gather::default(), Gather::default());
        // Empty lanes repeat the first point (shaded, then dropped).
        for (i, (k_i, s, object)) in points.iter().map(|q| q.unwrap_or(*first)).enumerate() {
            k.set_coefficients(i, k_i);
            k.live[i] = true;
            k.object[i] = object;
            p.set(i, s.position);
            n.set(i, s.normal);
            v.set(i, s.to_eye);
        }
        let inputs = k.inputs();
        let zero = F::ZERO;
        let surface = LaneSurface { p: p.load(), n: n.load(), v: v.load(), weights: [zero; 3] };
        let [ambient, diffuse, specular, emission] = self.components(&inputs, &surface, F::ONE);
        std::array::from_fn(|i| {
            if points[i].is_none() {
                return Components::default();
            }
            let (ambient, diffuse, specular, emission) =
                (ambient.lane(i), diffuse.lane(i), specular.lane(i), emission.lane(i));
            Components { ambient, diffuse, specular, emission }
        })
    }

    /// Seed 002 eq. 1 summed over the pass's lights, per lane, the ambient
    /// term scaled by `open`.
    #[inline(always)]
    fn shade(&self, inp: &LaneInputs, s: &LaneSurface, open: F) -> V3 {
        let [ambient, diffuse, specular, emission] = self.components(inp, s, open);
        ambient.add(diffuse).add(specular).add(emission)
    }

    /// Seed 002 eq. 1's components summed over the pass's lights, per lane:
    /// ambient (scaled by `open`), diffuse, specular, emission.
    #[inline(always)]
    fn components(&self, inp: &LaneInputs, s: &LaneSurface, open: F) -> [V3; 4] {
        let mut diffuse = V3::splat(Vec3::ZERO);
        let mut specular = V3::splat(Vec3::ZERO);
        let direct = if self.diffuse > 0.0 || self.specular > 0.0 { self.direct.as_slice() } else { &[] };
        for &(light, terms) in direct {
            let (l, radiance) = incident(light, &s.p);
            let cos_theta = s.n.dot(l);
            let lit = cos_theta.simd_gt(F::ZERO);
            let casts = terms.iter().any(ShadowTerm::casts);
            let radiance = if casts { radiance.scale(shadow(terms, s, cos_theta, &inp.receivers())) } else { radiance };
            let r = s.n.scale(cos_theta + cos_theta).sub(l);
            let cos_alpha = r.dot(s.v).max(F::ZERO);
            let spec = power(cos_alpha, inp.shininess, inp.whole, &inp.exponents);
            diffuse = diffuse.add(radiance.scale(lit.select(cos_theta, F::ZERO)));
            specular = specular.add(radiance.scale(lit.select(spec, F::ZERO)));
        }
        let (kd, ks) = (inp.kd.scale(F::splat(self.diffuse)), inp.ks.scale(F::splat(self.specular)));
        let emission = if self.emission { inp.ke } else { V3::splat(Vec3::ZERO) };
        [inp.ka.mul(V3::splat(self.ambient)).scale(open), kd.mul(diffuse), ks.mul(specular), emission]
    }
}

/// The shadow term per lane: the mean of `terms` (where the surface faces away
/// from the light it is irrelevant: the diffuse and specular terms are zero
/// there anyway).
#[inline(always)]
fn shadow(terms: &[ShadowTerm], s: &LaneSurface, cos_theta: F, receivers: &ReceiverLanes) -> F {
    if !cos_theta.simd_gt(F::ZERO).any() {
        return F::ZERO;
    }
    ShadowTerm::mean_lit_lanes(terms, [s.p.x, s.p.y, s.p.z], cos_theta, receivers)
}

/// `x^n` per lane for x ≥ 0: by repeated squaring for the lanes whose
/// exponent is a whole number (`whole` when every lane shares it, else each
/// lane's `exponents`, 0 for none; exact, and several times faster), through
/// exp/log for the others. A lane's result does not depend on the other
/// lanes: the squaring takes the same steps for its exponent either way.
#[inline(always)]
fn power(x: F, n: F, whole: Option<u32>, exponents: &[u32; LANES]) -> F {
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
        None => {
            let general = || x.simd_gt(F::ZERO).select(x.powf_simd(n), F::ZERO);
            let most = exponents.iter().copied().max().unwrap_or(0);
            if most == 0 {
                return general();
            }
            let (mut base, mut acc, mut bit) = (x, F::ONE, 1u32);
            while bit <= most {
                let take = F::new(exponents.map(|e| if e & bit != 0 { f32::from_bits(u32::MAX) } else { 0.0 }));
                acc = take.select(acc * base, acc);
                base *= base;
                bit <<= 1;
            }
            if exponents.contains(&0) {
                let squared = F::new(exponents.map(|e| if e != 0 { f32::from_bits(u32::MAX) } else { 0.0 }));
                return squared.select(acc, general());
            }
            acc
        }
    }
}

/// Unit direction towards the light and radiance, per lane (as `Light::incident`).
#[inline(always)]
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

/// The pixel rays of one image row, with the per-row work done once.
#[derive(Debug, Clone, Copy)]
pub struct RowRays {
    /// Ray origin at the row's centre line (orthographic) or the eye.
    origin: Vec3,
    /// Direction (perspective) or origin offset (orthographic) at ndc x = 0.
    base: Vec3,
    /// Change per unit of ndc x.
    right: Vec3,
    /// Unit view direction (orthographic rays).
    forward: Vec3,
    ndc_scale: f32,
    ortho: bool,
    /// The row.
    y: usize,
    /// From this row's rays to the next row's: added to the origin
    /// (orthographic) or the direction base (perspective).
    down: Vec3,
}

/// The rays of a row from one column on, as affine functions of the pixel
/// offset `k`: origin `origin + k·origin_step`, unnormalised direction
/// `dir + k·dir_step`.
#[derive(Debug, Clone, Copy)]
struct RayLine {
    origin: Vec3,
    origin_step: Vec3,
    dir: Vec3,
    dir_step: Vec3,
}

impl RowRays {
    /// The rays of row `y`.
    #[must_use]
    pub fn new(rays: &PixelRays, y: usize) -> Self {
        let ndc_y = 1.0 - 2.0 * (y as f32 + 0.5) / rays.size.y;
        let up = rays.up * ndc_y;
        let (origin, base) = if rays.ortho { (rays.origin + up, Vec3::ZERO) } else { (rays.origin, rays.forward + up) };
        RowRays {
            origin,
            base,
            right: rays.right,
            forward: rays.forward.normalize(),
            ndc_scale: 2.0 / rays.size.x,
            ortho: rays.ortho,
            y,
            down: rays.up * (-2.0 / rays.size.y),
        }
    }

    /// The rays of the next row down.
    #[must_use]
    pub fn below(&self) -> RowRays {
        let mut r = *self;
        r.y += 1;
        if self.ortho {
            r.origin += self.down;
        } else {
            r.base += self.down;
        }
        r
    }

    /// The rays from column `x0` on.
    fn line(&self, x0: usize) -> RayLine {
        let ndc_x = (x0 as f32 + 0.5) * self.ndc_scale - 1.0;
        let offset = self.base + self.right * ndc_x;
        let step = self.right * self.ndc_scale;
        if self.ortho {
            RayLine { origin: self.origin + offset, origin_step: step, dir: self.forward, dir_step: Vec3::ZERO }
        } else {
            RayLine { origin: self.origin, origin_step: Vec3::ZERO, dir: offset, dir_step: step }
        }
    }

    /// Origins and unit directions of the rays through pixels `x0 .. x0 + 8`.
    #[inline(always)]
    fn at(&self, x0: usize) -> (V3, V3) {
        const STEPS: F = F::new([0.5, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5]);
        let ndc_x = (F::splat(x0 as f32) + STEPS) * F::splat(self.ndc_scale) - F::ONE;
        let offset = V3::splat(self.base).add(V3::splat(self.right).scale(ndc_x));
        let forward = V3::splat(self.forward);
        if self.ortho {
            (V3::splat(self.origin).add(offset), forward)
        } else {
            (V3::splat(self.origin), offset.normalize_or(forward))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Material;

    /// A block's lanes `0..n` given `material`'s coefficients.
    fn fill(block: &mut Block, n: usize, material: &Material) {
        let k = Coefficients::constant(material).expect("no maps");
        block.clear();
        for i in 0..n {
            block.set_coefficients(i, &k);
            block.live[i] = true;
        }
    }

    #[test]
    fn a_blocks_exponent_path_does_not_depend_on_what_its_empty_lanes_held() {
        let glossy = Material { shininess: 32.0, ..Material::default() };
        let mut fresh = Block::default();
        fill(&mut fresh, 5, &glossy);
        // A worker's block that shaded eight lanes before, then five.
        let mut reused = Block::default();
        fill(&mut reused, LANES, &glossy);
        fill(&mut reused, 5, &glossy);
        assert_eq!(fresh.inputs().whole, Some(32));
        assert_eq!(reused.inputs().whole, fresh.inputs().whole);
        // A lane in use with another exponent still takes the general path.
        let rough = Material { shininess: 7.5, ..Material::default() };
        reused.set_coefficients(4, &Coefficients::constant(&rough).expect("no maps"));
        assert_eq!(reused.inputs().whole, None);
    }

    #[test]
    fn a_lanes_power_does_not_depend_on_its_neighbours_exponents() {
        let x = F::new([0.9, 0.5, 0.99, 0.7, 0.95, 0.3, 0.999, 0.0]);
        for e in [1u32, 7, 32, 120, 200, 4096] {
            let alone = power(x, F::splat(e as f32), Some(e), &[e; LANES]).to_array();
            let mut exponents = [e, 3, 0, 17, e, 2000, 0, e];
            exponents[0] = e;
            let n = F::new(exponents.map(|k| if k == 0 { 7.5 } else { k as f32 }));
            let mixed = power(x, n, None, &exponents).to_array();
            for i in [0, 4, 7] {
                assert_eq!(alone[i].to_bits(), mixed[i].to_bits(), "x^{e}, lane {i}");
            }
            assert!((mixed[2] - 0.99f32.powf(7.5)).abs() < 1e-5, "a lane with no whole exponent");
        }
    }
}
