//! Percentage-closer soft shadows (Fernando 2005): one map from the light's
//! centre ([`super::map`]'s), read by [`crate::shadows::pcss`]: a blocker
//! search sized by the light, then a filter as wide as the penumbra the
//! blockers' mean depth gives.

use std::any::Any;

use glam::Vec3;
use wide::f32x8;

use super::map::{depth_maps, PlainMaps};
use super::Technique;
use crate::scene::{Light, LightKind, Scene, ShadowMethod, ShadowSettings};
use crate::shadows::placement::Maps;
use crate::shadows::{lit_each, pcss, DepthMap, LightTerm, MapPool, PcssLight, Receiver, ReceiverLanes, ShadowTerm};
use crate::visibility::VisibilityBuffer;

/// The method `pcss`.
pub struct PercentageCloser;

/// The settings of PCSS's one hard map: no filter of its own.
fn hard_settings(pcss: &ShadowSettings) -> ShadowSettings {
    ShadowSettings { samples: 1, pcf: 1, ..pcss.with_method(ShadowMethod::Map) }
}

impl Technique for PercentageCloser {
    fn build(&self, scene: &Scene, light: &Light, bounds: (Vec3, Vec3), pool: &mut MapPool) -> ShadowTerm {
        let hard = Light { shadow: hard_settings(&light.shadow), ..light.clone() };
        let (size, at) = match light.kind {
            LightKind::Point { position } | LightKind::Spot { position, .. } => (light.size.max(0.0), position),
            // A directional light has no size: its hard shadow.
            LightKind::Directional { .. } => return PlainMaps.build(scene, &hard, bounds, pool),
        };
        let Some(maps) = depth_maps(scene, &hard, bounds, pool) else {
            return ShadowTerm::unshadowed();
        };
        // The nearest caster: the distance to the casters' bounds (a light
        // among them: a small share of the way to their centre).
        let centre = (bounds.0 + bounds.1) * 0.5;
        let outside = (bounds.0 - at).max(at - bounds.1).max(Vec3::ZERO).length();
        let nearest = outside.max(0.05 * (centre - at).length()).max(f32::MIN_POSITIVE);
        ShadowTerm::new(PcssTerm { maps, settings: hard.shadow, light: PcssLight { size, nearest } })
    }

    fn bytes_needed(&self, light: &Light, bounds: (Vec3, Vec3)) -> usize {
        PlainMaps.bytes_needed(&Light { shadow: hard_settings(&light.shadow), ..light.clone() }, bounds)
    }
}

/// A light's PCSS term.
#[derive(Debug)]
pub struct PcssTerm {
    maps: Maps<DepthMap>,
    settings: ShadowSettings,
    light: PcssLight,
}

impl LightTerm for PcssTerm {
    fn lit(&self, p: Vec3, cos_theta: f32, _: &Receiver) -> f32 {
        pcss::lit(self.maps.at(p), p, cos_theta, &self.settings, &self.light)
    }

    fn lit_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
        match self.maps.at_lanes(p) {
            Some(map) => pcss::lit_lanes(map, p, cos_theta, &self.settings, &self.light),
            None => lit_each(self, p, cos_theta, receivers),
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
