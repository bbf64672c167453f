//! Plain shadow maps: a depth map rendered from the light, placed by the
//! light's type ([`place_maps`]), read with a slope-scaled bias and
//! optional percentage-closer filtering.

use std::any::Any;

use glam::Vec3;
use wide::f32x8;

use super::Technique;
use crate::scene::{Light, Scene, ShadowSettings};
use crate::shadows::placement::{place_maps, placed_bytes, Maps};
use crate::shadows::{lit_each, DepthMap, LightTerm, MapPool, Receiver, ReceiverLanes, ShadowTerm};
use crate::visibility::VisibilityBuffer;

/// The method `map`.
pub struct PlainMaps;

impl Technique for PlainMaps {
    fn build(&self, scene: &Scene, light: &Light, bounds: (Vec3, Vec3), pool: &mut MapPool) -> ShadowTerm {
        match depth_maps(scene, light, bounds, pool) {
            Some(maps) => ShadowTerm::new(MapTerm { maps, settings: light.shadow }),
            None => ShadowTerm::unshadowed(),
        }
    }

    fn bytes_needed(&self, light: &Light, bounds: (Vec3, Vec3)) -> usize {
        placed_bytes(light, bounds, |res| res * res * std::mem::size_of::<f32>())
    }
}

/// `light`'s depth maps, placed and drawn (a cube face that sees no caster
/// left empty); `None` when it casts no shadows.
pub(super) fn depth_maps(
    scene: &Scene,
    light: &Light,
    bounds: (Vec3, Vec3),
    pool: &mut MapPool,
) -> Option<Maps<DepthMap>> {
    let casters = pool.casters(scene);
    place_maps(scene, light, bounds, pool, 1.0, |cam, res, pool| match res {
        Some(res) => DepthMap::render(scene, &cam, res, &casters, pool.workers, pool.take()),
        None => DepthMap::empty(&cam, pool.take()),
    })
}

/// A light's term read from plain depth maps.
#[derive(Debug)]
pub struct MapTerm {
    maps: Maps<DepthMap>,
    settings: ShadowSettings,
}

impl MapTerm {
    /// The maps: one, or a cube's six.
    #[must_use]
    pub fn maps(&self) -> &[DepthMap] {
        self.maps.faces()
    }
}

impl LightTerm for MapTerm {
    fn lit(&self, p: Vec3, cos_theta: f32, _: &Receiver) -> f32 {
        self.maps.at(p).lit(p, cos_theta, &self.settings)
    }

    fn lit_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
        match self.maps.at_lanes(p) {
            Some(map) => map.lit_lanes(p, cos_theta, &self.settings),
            None => lit_each(self, p, cos_theta, receivers),
        }
    }

    fn one_tap_map(&self) -> Option<(&DepthMap, &ShadowSettings)> {
        match &self.maps {
            Maps::One(map) if self.settings.pcf <= 1 => Some((map, &self.settings)),
            _ => None,
        }
    }

    fn memory_bytes(&self) -> usize {
        self.maps.memory_bytes()
    }

    fn into_buffers(self: Box<Self>) -> Vec<VisibilityBuffer> {
        self.maps.into_buffers()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}
