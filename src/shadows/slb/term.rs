//! A light's shadow term by the silhouette-line buffer: the depth map decides
//! every texel no silhouette crosses (seed 000 Table 4: not an edge texel, the
//! plain map lookup), the buffer's lines the rest, at the point's position
//! inside the texel — so only texels with the edge bit cost more than a plain
//! map lookup. The map keeps which object each texel holds (the paper's ID
//! buffer): the receiver's own surface is held to the full depth bias,
//! another object's to the small bias of the lines. (With the full bias
//! everywhere, a grid of boxes under a 12° sun lost its shadows in the texels
//! no line crosses once the view was 16 times wider: 3.2% of its lit tests
//! wrong, 0.026% with the ids; `kage-bench slb`.)
//!
//! A CSG solid's lines follow where it covers the map, not where one of its
//! parts lies in front of another (a step of its depth): the light pass
//! marks the texels round the steps and sharp creases of each solid's depth
//! at the texel centres, and there a point of the solid whose neighbouring
//! centres show the solid in front of the point's plane is decided by a ray
//! through that solid (the lines and the map decide for the other objects).
//! On OpenSCAD's printer part `mk3_x_end.csg` at 1024² this takes the
//! misclassified points from 15 to 2 at scale 1 and from 1,213 to 36 at
//! scale 64, for 35 ms more shading at 1920×1080 (`kage-bench slb`).
//!
//! Most points never reach the lines: eight at a time, a point whose
//! pixel's footprint stays within a texel of its own is decided by one look
//! at what the 3 × 3 texels round its texel hold ([`Neighbourhood`]) — the
//! map where no line lies there, lit where no surface there comes nearer
//! the light than the point's limit — and only the rest, beside a shadow's
//! edge, take the line test one at a time. On the 1920×1080 demo with every
//! light a point this took the eye pass from 217 to 138 ms (2 threads,
//! `kage-bench slb --only demo`), the same image to the bit.
//!
//! Antialiased, a point whose pixel's footprint on the receiver's plane
//! ([`PixelView::footprint`]) has a stored line passing through it (its
//! bounding box in texels) is decided at 4 × 4 points of the footprint and
//! the share found lit is its term: the edge is known exactly, so the share
//! is the edge's true coverage of the pixel up to the 16 samples' steps,
//! where a shadow map could only blur its staircase. With one line under the
//! footprint, each point takes the decision of its side of that line, found
//! at one point per side: two lookups instead of sixteen, the same term
//! (the demo's boundary RMSE is unchanged to four places) and, with the
//! lines tested against the footprint rather than the texels near it, the
//! 1920×1080 demo's shading 1.8× faster at scale 16 and 64 (`kage-bench
//! slb`).

use glam::Vec3;
use wide::f32x8;

use super::buffer::SilhouetteLineBuffer;
use super::light::light_triangles;
use super::line::{Facing, SilhouetteLine};
use super::neighbourhood::Neighbourhood;
use super::region::{covered, DepthLimits};
use super::solid::{solid_outlines, solid_steps};
use crate::camera::Camera;
use crate::camera::Ray;
use crate::csg::CsgCaster;
use crate::scene::{Scene, ShadowSettings};
use crate::shadows::footprint::{PixelView, Receiver, ReceiverLanes};
use crate::shadows::map::{other_bias, DepthMap, Located, LocatedLanes};
use crate::visibility::{VisibilityBuffer, Workers};

/// One light view's depth map and silhouette-line buffer.
#[derive(Debug, Clone)]
pub struct SlbMap {
    map: DepthMap,
    slb: SilhouetteLineBuffer,
    /// The CSG solids among the casters, in world space, with their objects:
    /// a solid's outline is traced into lines, but not where one part of it
    /// lies nearer the light than another that covers the map beside it (its
    /// steps), so a point of a solid next to such a step is decided by a ray
    /// through that solid.
    solids: Vec<(u32, CsgCaster)>,
    /// One bit per texel: a step or a sharp crease of a solid's depth lies
    /// between texel centres within one texel of it ([`solid_steps`](super::solid::solid_steps)).
    steps: Vec<u64>,
    /// What the 3 × 3 texels round each texel hold: most points are decided
    /// by one look at it ([`Neighbourhood`]).
    near: Neighbourhood,
    /// The frame's pixel rays, for antialiased lookups ([`SlbMap::set_view`]).
    view: Option<PixelView>,
}

/// A pixel's footprint on its receiver's plane, to be averaged over.
struct Footprint {
    /// Its sides, a pixel right and a pixel down.
    axes: [Vec3; 2],
    /// The one line under it, when only one is.
    one_line: Option<OneLine>,
}

/// A line under a footprint, with the texel it is stored in and the
/// footprint's corners (texel coordinates: −½ right −½ down, +½ −½, −½ +½,
/// +½ +½).
struct OneLine {
    line: SilhouetteLine,
    texel: (f32, f32),
    corners: [(f32, f32); 4],
}

/// The lines under a footprint.
enum Under {
    Nothing,
    One(OneLine),
    Many,
}

/// Samples per side of the footprint grid an antialiased lookup averages.
const FOOTPRINT_GRID: usize = 4;

/// Widest reach, in texels, of a footprint whose texels are scanned for
/// lines; a wider one is sampled without looking.
const MAX_SCANNED_REACH: f32 = 8.0;

impl SlbMap {
    /// Renders the depth map of the casters `casters` marks through `camera`
    /// into `depth` (resized to `resolution`²) and builds the buffer of their
    /// silhouettes with the lines and bias `settings` give.
    #[must_use]
    pub fn render(
        scene: &Scene,
        camera: &Camera,
        resolution: u32,
        casters: &[bool],
        workers: Workers,
        depth: VisibilityBuffer,
        settings: &ShadowSettings,
    ) -> SlbMap {
        let mut depth = depth;
        // Which object each texel holds: a texel no outline crosses is held to
        // that object's bias (the receiver's own, or the small one of others).
        depth.keep_items(true);
        let map = DepthMap::render(scene, camera, resolution, casters, workers, depth);
        let bits = settings.bits.clamp(4, 16);
        let mut triangles = light_triangles(scene, camera, resolution, casters);
        let solids = solid_outlines(scene, camera, resolution, casters, bits);
        triangles.extend(solids.triangles);
        let slb = SilhouetteLineBuffer::build(resolution, resolution, bits, &triangles, &solids.coverages);
        let steps = solid_steps(&map, &solids.coverages, other_bias(settings));
        let near = Neighbourhood::build(&map, &slb, &steps, workers);
        SlbMap { map, slb, solids: solids.casters, steps, near, view: None }
    }

    /// Sets the pixel rays of the frame the lookups are for: antialiased
    /// lookups need them for the pixels' footprints (`None`: every lookup is
    /// decided at its point).
    pub fn set_view(&mut self, view: Option<PixelView>) {
        self.view = view;
    }

    /// `shadow_i` at `p` on `receiver` with N·L = `cos_theta`: 1 lit, 0 in
    /// shadow, and between where `settings` asks for antialiasing, the
    /// receiver's plane and the view are known and a shadow's edge passes
    /// near. Another object's silhouette is held to a depth bias that does
    /// not grow with the texel; the receiver's own, and the map, to the full
    /// bias.
    #[must_use]
    pub fn lit(&self, p: Vec3, cos_theta: f32, settings: &ShadowSettings, receiver: &Receiver) -> f32 {
        match self.map.locate(p, cos_theta, settings, 1.0) {
            Some(at) => self.lit_located(p, &at, cos_theta, settings, receiver),
            None => 1.0,
        }
    }

    /// [`SlbMap::lit`] of `p`, located at `at`.
    #[inline]
    fn lit_located(
        &self,
        p: Vec3,
        at: &Located,
        cos_theta: f32,
        settings: &ShadowSettings,
        receiver: &Receiver,
    ) -> f32 {
        match self.footprint(p, at, settings, receiver) {
            Some(footprint) => self.footprint_share(p, footprint, cos_theta, settings, receiver),
            None => {
                let facing = Facing::of(receiver.plane, self.map.towards_light(p));
                self.lit_point(p, receiver.plane, at, &limits(at, receiver.object, facing), settings)
            }
        }
    }

    /// [`SlbMap::lit`] for eight points, on `receivers`: located as vectors;
    /// a point whose footprint stays within a texel of its own is decided by
    /// one look at its texel's [`Neighbourhood`] (the map where no line lies
    /// near, lit where no surface near is nearer the light than its limit),
    /// the rest one at a time.
    #[must_use]
    pub fn lit_lanes(
        &self,
        p: [f32x8; 3],
        cos_theta: f32x8,
        settings: &ShadowSettings,
        receivers: &ReceiverLanes,
    ) -> f32x8 {
        let LocatedLanes { inside, u, v, z_limit, texel, z_other, .. } =
            self.map.locate_lanes(p, cos_theta, settings, 1.0);
        let mask = inside.to_bitmask();
        if mask == 0 {
            return f32x8::ONE;
        }
        // Which lanes are averaged over a footprint, and which of those
        // footprints reach at most a texel.
        let (footprinted, small) = match self.view.as_ref().filter(|_| settings.antialias) {
            Some(view) => {
                let reach = f32x8::splat(0.5) * view.footprint_span_lanes(p, receivers.planes) / texel;
                let known = receivers.planes.iter().fold(f32x8::ZERO, |a, c| a + *c * *c).simd_gt(f32x8::ZERO);
                (known.to_bitmask(), reach.simd_le(f32x8::ONE).to_bitmask())
            }
            None => (0, 0),
        };
        let (u, v, own, other) = (u.to_array(), v.to_array(), z_limit.to_array(), z_other.to_array());
        let n = self.map.resolution() as usize;
        let mut slow = 0u32;
        let mut out = [1.0f32; 8];
        for i in (0..8).filter(|i| mask >> i & 1 == 1) {
            let (x, y) = (u[i] as u32, v[i] as u32);
            let t = y as usize * n + x as usize;
            // Decided at the point alone: by its texel, as `lit_point` does.
            let plain = if footprinted >> i & 1 == 0 {
                !(self.slb.is_edge(x, y) || self.near_step(t))
            } else if small >> i & 1 == 0 {
                false
            } else if !self.near.busy(t) {
                true
            } else {
                // Lit: nothing round it is nearer the light than its limit.
                if self.near.nearest(t) > other[i] {
                    slow |= 1 << i;
                }
                continue;
            };
            if plain {
                let limits = DepthLimits {
                    receiver: receivers.objects[i],
                    facing: Facing::Unknown,
                    own: own[i],
                    other: other[i],
                };
                out[i] = if self.map_hides(x, y, &limits) { 0.0 } else { 1.0 };
            } else {
                slow |= 1 << i;
            }
        }
        if slow != 0 {
            let (x, y, z, c) = (p[0].to_array(), p[1].to_array(), p[2].to_array(), cos_theta.to_array());
            let (texel, planes) = (texel.to_array(), receivers.planes.map(|n| n.to_array()));
            for i in (0..8).filter(|i| slow >> i & 1 == 1) {
                let at = Located { u: u[i], v: v[i], z_limit: own[i], texel: texel[i], z_other: other[i] };
                let plane = Vec3::new(planes[0][i], planes[1][i], planes[2][i]);
                let receiver = Receiver { object: receivers.objects[i], plane };
                out[i] = self.lit_located(Vec3::new(x[i], y[i], z[i]), &at, c[i], settings, &receiver);
            }
        }
        f32x8::new(out)
    }

    /// The footprint of `p`'s pixel on its receiver's plane, when the lookup
    /// located at `at` is to be antialiased: asked for, the plane and view
    /// known, and a line under the footprint.
    #[inline]
    fn footprint(&self, p: Vec3, at: &Located, settings: &ShadowSettings, receiver: &Receiver) -> Option<Footprint> {
        let view = self.view.as_ref().filter(|_| settings.antialias && receiver.plane != Vec3::ZERO)?;
        let axes = view.footprint(p, receiver.plane);
        // The footprint's reach in texels, at most its world size over a
        // texel's (seen from the light it can only shrink).
        let reach = 0.5 * (axes[0].length() + axes[1].length()) / at.texel.max(f32::MIN_POSITIVE);
        if reach > MAX_SCANNED_REACH {
            return Some(Footprint { axes, one_line: None });
        }
        let r = reach.ceil().max(1.0) as i64;
        let (x, y) = (at.u as i64, at.v as i64);
        if !self.slb.any_edge((x - r, x + r), (y - r, y + r)) {
            return None;
        }
        match self.lines_under(p, axes) {
            Under::Nothing => None,
            Under::One(line) => Some(Footprint { axes, one_line: Some(line) }),
            Under::Many => Some(Footprint { axes, one_line: None }),
        }
    }

    /// The stored lines that pass through the bounding box, in texels, of the
    /// footprint `[right, down]` around `p` (many, too, where the footprint
    /// leaves the map): where none does, every footprint point is decided
    /// as `p` is, up to the receiver's depth crossing a caster's inside the
    /// footprint.
    fn lines_under(&self, p: Vec3, [right, down]: [Vec3; 2]) -> Under {
        let mut corners = [(0.0, 0.0); 4];
        for (k, (i, j)) in [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)].into_iter().enumerate() {
            let Some((u, v, _)) = self.map.project(p + right * i + down * j) else { return Under::Many };
            corners[k] = (u, v);
        }
        let lo = corners.iter().fold((f32::INFINITY, f32::INFINITY), |m, c| (m.0.min(c.0), m.1.min(c.1)));
        let hi = corners.iter().fold((f32::NEG_INFINITY, f32::NEG_INFINITY), |m, c| (m.0.max(c.0), m.1.max(c.1)));
        let bits = self.slb.bits();
        let mut found = None;
        for ty in lo.1 as u32..=hi.1 as u32 {
            for tx in lo.0 as u32..=hi.0 as u32 {
                let Some(entry) = self.slb.entry(tx, ty) else { continue };
                let (x0, y0, x1, y1) = (lo.0 - tx as f32, lo.1 - ty as f32, hi.0 - tx as f32, hi.1 - ty as f32);
                for line in entry.lines {
                    let f = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)].map(|(mx, my)| line.offset(mx, my, bits));
                    if f.iter().any(|&v| v > 0.0) && f.iter().any(|&v| v <= 0.0) {
                        if found.is_some() {
                            return Under::Many;
                        }
                        found = Some(OneLine { line: *line, texel: (tx as f32, ty as f32), corners });
                    }
                }
            }
        }
        found.map_or(Under::Nothing, Under::One)
    }

    /// The lit share of the footprint around `p` (a point of `receiver`):
    /// [`FOOTPRINT_GRID`]² points of it, each decided — or, with one line
    /// under it, each given the decision of its side of the line, found at
    /// one point of each side.
    #[inline(never)]
    fn footprint_share(
        &self,
        p: Vec3,
        footprint: Footprint,
        cos_theta: f32,
        settings: &ShadowSettings,
        receiver: &Receiver,
    ) -> f32 {
        let facing = Facing::of(receiver.plane, self.map.towards_light(p));
        let [right, down] = footprint.axes;
        let step = 1.0 / FOOTPRINT_GRID as f32;
        let offset = |k: usize| (k as f32 + 0.5) * step - 0.5;
        let decide = |i: usize, j: usize| {
            let q = p + right * offset(i) + down * offset(j);
            match self.map.locate(q, cos_theta, settings, 1.0) {
                Some(at) => self.lit_point(q, receiver.plane, &at, &limits(&at, receiver.object, facing), settings),
                None => 1.0,
            }
        };
        let points = (0..FOOTPRINT_GRID).flat_map(|j| (0..FOOTPRINT_GRID).map(move |i| (i, j)));
        let Some(one) = footprint.one_line else {
            return points.map(|(i, j)| decide(i, j)).sum::<f32>() * step * step;
        };
        // Each point's side, where the footprint's corners put it.
        let [c00, c10, c01, c11] = one.corners;
        let bits = self.slb.bits();
        let mut sides = [None::<f32>; 2];
        let mut lit = 0.0;
        for (i, j) in points {
            let (s, t) = (offset(i) + 0.5, offset(j) + 0.5);
            let mix =
                |a: f32, b: f32, c: f32, d: f32| (a * (1.0 - s) + b * s) * (1.0 - t) + (c * (1.0 - s) + d * s) * t;
            let (u, v) = (mix(c00.0, c10.0, c01.0, c11.0), mix(c00.1, c10.1, c01.1, c11.1));
            let side = usize::from(one.line.offset(u - one.texel.0, v - one.texel.1, bits) > 0.0);
            lit += *sides[side].get_or_insert_with(|| decide(i, j));
        }
        lit * step * step
    }

    /// The term at `p` on a receiver with plane normal `plane` (zero: not
    /// known), located at `at`, held to `limits`: [`SlbMap::lit_at`], or next
    /// to a step of a CSG solid over itself, [`SlbMap::lit_past_step`].
    #[inline(always)]
    fn lit_point(&self, p: Vec3, plane: Vec3, at: &Located, limits: &DepthLimits, settings: &ShadowSettings) -> f32 {
        let t = at.v as usize * self.map.resolution() as usize + at.u as usize;
        if self.near_step(t) {
            if let Some(lit) = self.lit_past_step(p, plane, at, limits, settings) {
                return lit;
            }
        }
        self.lit_at(at.u, at.v, limits)
    }

    /// Whether a step or sharp crease of a solid lies within a texel of texel
    /// `t` (its index, row by row).
    #[inline]
    fn near_step(&self, t: usize) -> bool {
        self.steps.get(t / 64).is_some_and(|w| w >> (t % 64) & 1 == 1)
    }

    /// Where the receiver is a CSG solid that one of the four texel centres
    /// round `p` shows in front of the receiver's plane (a step of the solid
    /// over itself, which no line records): the solid's own part of the term
    /// by a ray from `p` through it, the lines and the map deciding for the
    /// other objects alone. `None` elsewhere.
    #[cold]
    #[inline(never)]
    fn lit_past_step(
        &self,
        p: Vec3,
        plane: Vec3,
        at: &Located,
        limits: &DepthLimits,
        settings: &ShadowSettings,
    ) -> Option<f32> {
        let (_, solid) = self.solids.iter().find(|(o, _)| *o == limits.receiver)?;
        // Past the small bias, as another object's surface is held to it.
        let bias = at.texel * other_bias(settings);
        if !self.own_step_near(p, plane, at, limits, bias) {
            return None;
        }
        let others = DepthLimits { own: f32::INFINITY, ..*limits };
        if self.lit_at(at.u, at.v, &others) == 0.0 {
            return Some(0.0);
        }
        let (dir, distance) = self.map.ray_to_light(p);
        Some(if solid.first_hit(&Ray { origin: p, dir }, bias, distance).is_some() { 0.0 } else { 1.0 })
    }

    /// Whether one of the four texel centres round `p` (located at `at`)
    /// shows the receiver's own object nearer the light than `bias` in front
    /// of the receiver's plane through `p` (its normal `plane`; not known,
    /// nearer than the small limit of `limits`).
    fn own_step_near(&self, p: Vec3, plane: Vec3, at: &Located, limits: &DepthLimits, bias: f32) -> bool {
        let n = self.map.resolution();
        let (x0, y0) = ((at.u - 0.5).floor().max(0.0) as u32, (at.v - 0.5).floor().max(0.0) as u32);
        let in_front = |x: u32, y: u32| {
            let z = self.map.texel_depth(x, y);
            if z <= limits.other || self.map.texel_object(x, y) != Some(limits.receiver) {
                return false;
            }
            plane == Vec3::ZERO || self.map.plane_limit(p, plane, (x, y), bias).is_none_or(|limit| z > limit)
        };
        (y0..(y0 + 2).min(n)).any(|y| (x0..(x0 + 2).min(n)).any(|x| in_front(x, y)))
    }

    /// The term at texel coordinates `(u, v)` (inside the map) for a receiver
    /// held to `limits`: the map where no silhouette crosses the texel, the
    /// lines where one does.
    #[inline(always)]
    fn lit_at(&self, u: f32, v: f32, limits: &DepthLimits) -> f32 {
        let (x, y) = (u as u32, v as u32);
        let hidden = match self.slb.entry(x, y) {
            Some(entry) => covered(&entry, u - x as f32, v - y as f32, limits, self.slb.bits()),
            None => self.map_hides(x, y, limits),
        };
        if hidden {
            0.0
        } else {
            1.0
        }
    }

    /// Whether the map's surface at texel `(x, y)` hides a receiver held to
    /// `limits` (by the bias of the object it belongs to). The texel's object
    /// is read only where its depth lies between the two limits, which alone
    /// it decides (the item buffer is twice the depth map's size).
    #[inline]
    fn map_hides(&self, x: u32, y: u32, limits: &DepthLimits) -> bool {
        let z = self.map.texel_depth(x, y);
        if z <= limits.own.min(limits.other) {
            return false;
        }
        if z > limits.own.max(limits.other) {
            return true;
        }
        let limit = self.map.texel_object(x, y).map_or(limits.own, |o| limits.of(o));
        z > limit
    }

    /// The depth map.
    #[must_use]
    pub fn map(&self) -> &DepthMap {
        &self.map
    }

    /// The silhouette-line buffer.
    #[must_use]
    pub fn buffer(&self) -> &SilhouetteLineBuffer {
        &self.slb
    }

    /// Gives the map's buffer back.
    #[must_use]
    pub fn into_buffer(self) -> VisibilityBuffer {
        let mut buffer = self.map.into_buffer();
        buffer.keep_items(false);
        buffer
    }

    /// Bytes held by the map and the buffer.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.map.memory_bytes() + self.slb.memory_bytes() + self.steps.len() * 8 + self.near.memory_bytes()
    }
}

/// The depth limits of a point located at `at` on object `receiver`, its
/// triangle facing the light as `facing` says.
#[inline]
fn limits(at: &Located, receiver: u32, facing: Facing) -> DepthLimits {
    DepthLimits { receiver, facing, own: at.z_limit, other: at.z_other }
}

#[cfg(test)]
mod tests {
    use glam::{Affine3A, Quat, Vec3};
    use rand::{Rng, SeedableRng};

    use glam::{DVec2, Vec2};

    use super::*;
    use crate::camera::Projection;
    use crate::csg::{ConvexPolyhedron, CsgCaster, CsgSolid, CsgTree, Primitive, Shape};
    use crate::shadows::slb::solid::{depth_at, solid_outline};

    /// Two random primitives joined, intersected or one cut from the other,
    /// within about a unit of the origin.
    fn random_solid(rng: &mut rand::rngs::StdRng) -> CsgSolid {
        let mut primitive = || {
            let shape = match rng.gen_range(0..3) {
                0 => Shape::Sphere,
                1 => Shape::Frustum { bottom: 1.0, top: rng.gen_range(0.0..1.0) },
                _ => Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
            };
            let s = Vec3::new(rng.gen_range(0.3..0.9), rng.gen_range(0.3..0.9), rng.gen_range(0.3..0.9));
            let r = Quat::from_euler(glam::EulerRot::XYZ, rng.gen_range(0.0..3.0), rng.gen_range(0.0..3.0), 0.0);
            let t = Vec3::new(rng.gen_range(-0.4..0.4), rng.gen_range(-0.4..0.4), rng.gen_range(-0.4..0.4));
            let transform = Affine3A::from_scale_rotation_translation(s, r, t);
            Primitive { shape, transform, color: None, source: 0..0 }
        };
        let primitives = vec![primitive(), primitive()];
        let (a, b) = (CsgTree::Leaf(0), CsgTree::Leaf(1));
        let tree = match rng.gen_range(0..3) {
            0 => CsgTree::Union(vec![a, b]),
            1 => CsgTree::Intersection(vec![a, b]),
            _ => CsgTree::Difference(Box::new(a), vec![b]),
        };
        CsgSolid { primitives, tree: Some(tree) }
    }

    /// A light looking at the origin from a random side, the solid taking
    /// `share` of its view's height.
    fn light(rng: &mut rand::rngs::StdRng, share: f32) -> Camera {
        let from = Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(0.5..1.0), rng.gen_range(-1.0..1.0)).normalize();
        let ortho = rng.gen_bool(0.5);
        let eye = from * 6.0;
        let projection = if ortho {
            Projection::Orthographic { height: 2.5 / share }
        } else {
            Projection::Perspective { fov_y_deg: (2.0 * (1.25 / share / 6.0f32).atan()).to_degrees() }
        };
        Camera { eye, target: Vec3::ZERO, up: Vec3::Y, near: 0.5, far: 20.0, projection, shift: Vec2::ZERO }
    }

    /// A CSG solid's outline band and layers decide coverage at random points of the
    /// map as a ray through each point does, on random two-primitive
    /// solids large (texel-centre lattice) and small (a finer one) in the
    /// map: points within 2^-8 texel of a decision change along x are not
    /// judged.
    #[test]
    fn the_outline_covers_what_rays_through_the_solid_meet() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let (n, bits) = (128u32, 12);
        for share in [0.9, 0.05] {
            let (mut wrong, mut judged) = (0, 0);
            for _ in 0..12 {
                let (solid, camera) = (random_solid(&mut rng), light(&mut rng, share));
                let rays = camera.pixel_rays(Vec2::splat(n as f32));
                let caster = CsgCaster::new(&solid);
                let meets = |p: DVec2| depth_at(&caster, &rays, &camera, p).is_some();
                let map = || {
                    let centre = |k: usize| DVec2::new((k % n as usize) as f64 + 0.5, (k / n as usize) as f64 + 0.5);
                    (0..(n * n) as usize)
                        .map(|k| depth_at(&caster, &rays, &camera, centre(k)).map_or(0.0, |z| z as f32))
                        .collect()
                };
                let (triangles, coverage, _) = solid_outline(&solid, 0, &camera, n, bits, map);
                let slb = SilhouetteLineBuffer::build(n, n, bits, &triangles, std::slice::from_ref(&coverage));
                let (x0, y0, w, h) = coverage.texels;
                for _ in 0..4000 {
                    let p = DVec2::new(
                        rng.gen_range(x0 as f64..(x0 + w) as f64),
                        rng.gen_range(y0 as f64..(y0 + h) as f64),
                    );
                    let near = 1.0 / 256.0;
                    let truth = meets(p);
                    if meets(p - DVec2::X * near) != truth || meets(p + DVec2::X * near) != truth {
                        continue;
                    }
                    let (x, y) = (p.x as u32, p.y as u32);
                    let decided = match slb.entry(x, y) {
                        Some(e) => covered(
                            &e,
                            (p.x - f64::from(x)) as f32,
                            (p.y - f64::from(y)) as f32,
                            &DepthLimits::uniform(0.0),
                            bits,
                        ),
                        None => coverage.depth[(y as usize - y0) * w + x as usize - x0] > 0.0,
                    };
                    judged += 1;
                    wrong += usize::from(decided != truth);
                }
            }
            assert!(judged > 20_000, "share {share}: only {judged} points");
            eprintln!("share {share}: {wrong} of {judged}");
            assert!(wrong * 1000 <= judged, "share {share}: {wrong} of {judged} points decided unlike the rays");
        }
    }
}
