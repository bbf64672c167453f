//! A light's shadow term by the silhouette-line buffer: the depth map decides
//! every texel no silhouette crosses (seed 000 Table 4: not an edge texel, the
//! plain map lookup), the buffer's lines the rest, at the point's position
//! inside the texel — so only texels with the edge bit cost more than a plain
//! map lookup.

use glam::Vec3;
use wide::f32x8;

use super::buffer::SilhouetteLineBuffer;
use super::light::light_triangles;
use super::region::covered;
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

    /// `shadow_i` at `p` with N·L = `cos_theta`: 1 lit, 0 in shadow.
    #[must_use]
    pub fn lit(&self, p: Vec3, cos_theta: f32, settings: &ShadowSettings) -> f32 {
        match self.map.locate(p, cos_theta, settings, 1.0) {
            Some(Located { u, v, z_limit }) => self.lit_at(u, v, z_limit),
            None => 1.0,
        }
    }

    /// [`SlbMap::lit`] for eight points: located as vectors, decided lane by
    /// lane.
    #[must_use]
    pub fn lit_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, settings: &ShadowSettings) -> f32x8 {
        let LocatedLanes { inside, u, v, z_limit } = self.map.locate_lanes(p, cos_theta, settings, 1.0);
        let mask = inside.to_bitmask();
        let (u, v, z) = (u.to_array(), v.to_array(), z_limit.to_array());
        f32x8::new(std::array::from_fn(|i| if mask >> i & 1 == 1 { self.lit_at(u[i], v[i], z[i]) } else { 1.0 }))
    }

    /// The term at texel coordinates `(u, v)` (inside the map) for a receiver
    /// whose depth limit is `z_limit`: the map where no silhouette crosses the
    /// texel, the lines where one does.
    #[inline]
    fn lit_at(&self, u: f32, v: f32, z_limit: f32) -> f32 {
        let (x, y) = (u as u32, v as u32);
        let hidden = match self.slb.entry(x, y) {
            Some(entry) => {
                covered(&entry, u - x as f32, v - y as f32, z_limit, self.slb.bits())
                    || (self.solids && self.map.texel_depth(x, y) > z_limit)
            }
            None => self.map.texel_depth(x, y) > z_limit,
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
