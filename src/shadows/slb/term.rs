//! A light's shadow term by the silhouette-line buffer: the depth map decides
//! every texel no silhouette crosses (seed 000 Table 4: not an edge texel, the
//! plain map lookup), the buffer's lines the rest, at the point's position
//! inside the texel — so only texels with the edge bit cost more than a plain
//! map lookup.

use glam::Vec3;
use wide::f32x8;

use super::buffer::SilhouetteLineBuffer;
use super::light::light_triangles;
use super::region::{covered, DepthLimits};
use crate::camera::Camera;
use crate::scene::{Scene, ShadowSettings};
use crate::shadows::map::{DepthMap, Located, LocatedLanes};
use crate::visibility::{VisibilityBuffer, Workers};

/// One light view's depth map and silhouette-line buffer.
#[derive(Debug, Clone)]
pub struct SlbMap {
    map: DepthMap,
    slb: SilhouetteLineBuffer,
    /// CSG solids cast into the map: they have no lines, so a texel the lines
    /// cross also asks the map (their shadows stay; such a texel's edge is the
    /// map's again where a solid or a mesh covers its centre).
    solids: bool,
}

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
        let map = DepthMap::render(scene, camera, resolution, casters, workers, depth);
        let triangles = light_triangles(scene, camera, resolution, casters);
        let slb = SilhouetteLineBuffer::build(resolution, resolution, bits.clamp(4, 16), &triangles);
        let solids = scene.objects.iter().zip(casters).any(|(o, &c)| c && o.triangles().is_none());
        SlbMap { map, slb, solids }
    }

    /// `shadow_i` at `p`, a point of object `receiver` (an index into the
    /// scene's objects; [`UNKNOWN_RECEIVER`] when not known), with N·L =
    /// `cos_theta`: 1 lit, 0 in shadow. Another object's silhouette is held
    /// to a depth bias that does not grow with the texel; the receiver's own,
    /// and the map, to the full bias.
    ///
    /// [`UNKNOWN_RECEIVER`]: super::region::UNKNOWN_RECEIVER
    #[must_use]
    pub fn lit(&self, p: Vec3, cos_theta: f32, settings: &ShadowSettings, receiver: u32) -> f32 {
        match self.map.locate(p, cos_theta, settings, 1.0) {
            Some(Located { u, v, z_limit, z_other }) => {
                self.lit_at(u, v, &DepthLimits { receiver, own: z_limit, other: z_other })
            }
            None => 1.0,
        }
    }

    /// [`SlbMap::lit`] for eight points, of objects `receivers`: located as
    /// vectors, decided lane by lane.
    #[must_use]
    pub fn lit_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, settings: &ShadowSettings, receivers: &[u32; 8]) -> f32x8 {
        let LocatedLanes { inside, u, v, z_limit, z_other } = self.map.locate_lanes(p, cos_theta, settings, 1.0);
        let mask = inside.to_bitmask();
        let (u, v, own, other) = (u.to_array(), v.to_array(), z_limit.to_array(), z_other.to_array());
        f32x8::new(std::array::from_fn(|i| {
            if mask >> i & 1 == 1 {
                self.lit_at(u[i], v[i], &DepthLimits { receiver: receivers[i], own: own[i], other: other[i] })
            } else {
                1.0
            }
        }))
    }

    /// The term at texel coordinates `(u, v)` (inside the map) for a receiver
    /// held to `limits`: the map where no silhouette crosses the texel, the
    /// lines where one does.
    #[inline]
    fn lit_at(&self, u: f32, v: f32, limits: &DepthLimits) -> f32 {
        let (x, y) = (u as u32, v as u32);
        let hidden = match self.slb.entry(x, y) {
            Some(entry) => {
                covered(&entry, u - x as f32, v - y as f32, limits, self.slb.bits())
                    || (self.solids && self.map.texel_depth(x, y) > limits.own)
            }
            None => self.map.texel_depth(x, y) > limits.own,
        };
        if hidden {
            0.0
        } else {
            1.0
        }
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
        self.map.into_buffer()
    }

    /// Bytes held by the map and the buffer.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.map.memory_bytes() + self.slb.memory_bytes()
    }
}
