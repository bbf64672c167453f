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
//! Antialiased, a point whose texel or a neighbour holds lines is decided at
//! 4 × 4 points of its pixel's footprint on the receiver's plane
//! ([`PixelView::footprint`]) and the share found lit is its term: the edge
//! is known exactly, so the share is the edge's true coverage of the pixel
//! up to the 16 samples' steps, where a shadow map could only blur its
//! staircase.

use glam::Vec3;
use wide::f32x8;

use super::buffer::SilhouetteLineBuffer;
use super::light::light_triangles;
use super::region::{covered, DepthLimits};
use super::solid::solid_outline;
use crate::camera::Camera;
use crate::scene::{Scene, ShadowSettings};
use crate::shadows::footprint::{PixelView, Receiver, ReceiverLanes};
use crate::shadows::map::{DepthMap, Located, LocatedLanes};
use crate::visibility::solids::draw_solids;
use crate::visibility::{VisibilityBuffer, Workers};

/// One light view's depth map and silhouette-line buffer.
#[derive(Debug, Clone)]
pub struct SlbMap {
    map: DepthMap,
    slb: SilhouetteLineBuffer,
    /// The frame's pixel rays, for antialiased lookups ([`SlbMap::set_view`]).
    view: Option<PixelView>,
}

/// Samples per side of the footprint grid an antialiased lookup averages.
const FOOTPRINT_GRID: usize = 4;

/// Widest reach, in texels, of a footprint whose texels are scanned for
/// lines; a wider one is sampled without looking.
const MAX_SCANNED_REACH: f32 = 8.0;

impl SlbMap {
    /// Renders the depth map of the casters `casters` marks through `camera`
    /// into `depth` (resized to `resolution`²) and builds the buffer of their
    /// silhouettes with `bits`-bit lines.
    #[must_use]
    pub fn render(
        scene: &Scene,
        camera: &Camera,
        resolution: u32,
        casters: &[bool],
        workers: Workers,
        depth: VisibilityBuffer,
        bits: u32,
    ) -> SlbMap {
        let mut depth = depth;
        // Which object each texel holds: a texel no outline crosses is held to
        // that object's bias (the receiver's own, or the small one of others).
        depth.keep_items(true);
        let map = DepthMap::render(scene, camera, resolution, casters, workers, depth);
        let bits = bits.clamp(4, 16);
        let mut triangles = light_triangles(scene, camera, resolution, casters);
        let mut solids = Vec::new();
        for (object, o) in scene.objects.iter().enumerate().filter(|&(i, _)| casters.get(i) == Some(&true)) {
            let Some(solid) = o.solid() else { continue };
            // The solid alone, as the map would hold it.
            let map_depth = || {
                let mut alone = VisibilityBuffer::depth_only(resolution, resolution);
                draw_solids(scene, camera, |i| i == object, &mut alone);
                alone.depths().to_vec()
            };
            let world = solid.transformed(&o.transform);
            let (outline, coverage) = solid_outline(&world, object as u32, camera, resolution, bits, map_depth);
            triangles.extend(outline);
            solids.push(coverage);
        }
        let slb = SilhouetteLineBuffer::build(resolution, resolution, bits, &triangles, &solids);
        SlbMap { map, slb, view: None }
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
            Some(footprint) => self.footprint_share(p, footprint, cos_theta, settings, receiver.object),
            None => self.lit_at(at.u, at.v, &limits(at, receiver.object)),
        }
    }

    /// [`SlbMap::lit`] for eight points, on `receivers`: located as vectors,
    /// decided lane by lane.
    #[must_use]
    pub fn lit_lanes(
        &self,
        p: [f32x8; 3],
        cos_theta: f32x8,
        settings: &ShadowSettings,
        receivers: &ReceiverLanes,
    ) -> f32x8 {
        let LocatedLanes { inside, u, v, z_limit, texel, z_other } = self.map.locate_lanes(p, cos_theta, settings, 1.0);
        let mask = inside.to_bitmask();
        let (u, v, own, other) = (u.to_array(), v.to_array(), z_limit.to_array(), z_other.to_array());
        let (x, y, z, c) = (p[0].to_array(), p[1].to_array(), p[2].to_array(), cos_theta.to_array());
        let (texel, planes) = (texel.to_array(), receivers.planes.map(|n| n.to_array()));
        f32x8::new(std::array::from_fn(|i| {
            if mask >> i & 1 == 0 {
                return 1.0;
            }
            let at = Located { u: u[i], v: v[i], z_limit: own[i], texel: texel[i], z_other: other[i] };
            let plane = Vec3::new(planes[0][i], planes[1][i], planes[2][i]);
            let receiver = Receiver { object: receivers.objects[i], plane };
            self.lit_located(Vec3::new(x[i], y[i], z[i]), &at, c[i], settings, &receiver)
        }))
    }

    /// The footprint of `p`'s pixel on its receiver's plane, when the lookup
    /// located at `at` is to be antialiased: asked for, the plane and view
    /// known, and a line in a texel the footprint reaches or next to one.
    #[inline]
    fn footprint(&self, p: Vec3, at: &Located, settings: &ShadowSettings, receiver: &Receiver) -> Option<[Vec3; 2]> {
        let view = self.view.as_ref().filter(|_| settings.antialias && receiver.plane != Vec3::ZERO)?;
        let footprint = view.footprint(p, receiver.plane);
        // The footprint's reach in texels, at most its world size over a
        // texel's (seen from the light it can only shrink).
        let reach = 0.5 * (footprint[0].length() + footprint[1].length()) / at.texel.max(f32::MIN_POSITIVE);
        if reach > MAX_SCANNED_REACH {
            return Some(footprint);
        }
        let r = reach.ceil().max(1.0) as i64;
        let (x, y) = (at.u as i64, at.v as i64);
        self.slb.any_edge((x - r, x + r), (y - r, y + r)).then_some(footprint)
    }

    /// The share of [`FOOTPRINT_GRID`]² points of the footprint
    /// `[right, down]` around `p` (a point of object `receiver`) that are lit.
    fn footprint_share(
        &self,
        p: Vec3,
        [right, down]: [Vec3; 2],
        cos_theta: f32,
        settings: &ShadowSettings,
        receiver: u32,
    ) -> f32 {
        let step = 1.0 / FOOTPRINT_GRID as f32;
        let offset = |k: usize| (k as f32 + 0.5) * step - 0.5;
        let mut lit = 0.0;
        for j in 0..FOOTPRINT_GRID {
            for i in 0..FOOTPRINT_GRID {
                let q = p + right * offset(i) + down * offset(j);
                lit += match self.map.locate(q, cos_theta, settings, 1.0) {
                    Some(at) => self.lit_at(at.u, at.v, &limits(&at, receiver)),
                    None => 1.0,
                };
            }
        }
        lit * step * step
    }

    /// The term at texel coordinates `(u, v)` (inside the map) for a receiver
    /// held to `limits`: the map where no silhouette crosses the texel, the
    /// lines where one does.
    #[inline]
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
    /// `limits` (by the bias of the object it belongs to).
    #[inline]
    fn map_hides(&self, x: u32, y: u32, limits: &DepthLimits) -> bool {
        let limit = self.map.texel_object(x, y).map_or(limits.own, |o| limits.of(o));
        self.map.texel_depth(x, y) > limit
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
        self.map.memory_bytes() + self.slb.memory_bytes()
    }
}

/// The depth limits of a point located at `at` on object `receiver`.
#[inline]
fn limits(at: &Located, receiver: u32) -> DepthLimits {
    DepthLimits { receiver, own: at.z_limit, other: at.z_other }
}
