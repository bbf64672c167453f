//! Soft shadows from two hard shadows (seed 001): the light's hard shadows
//! (by [`ShadowSettings::hard`], through that method's own unit) from the
//! points of [`TwoMaps`], combined per pixel of the frame.

use std::any::Any;

use glam::Vec3;

use super::{technique, Technique};
use crate::scene::{HardShadows, Light, Scene, ShadowMethod, ShadowSettings};
use crate::shadows::{LightTerm, MapPool, PixelView, Receiver, ScreenSurfaces, ShadowTerm, TwoMaps};
use crate::visibility::VisibilityBuffer;

/// The method `soft`.
pub struct TwoMapSoft;

/// The settings of a two-map soft term's hard shadows: its `hard` method,
/// one map each.
fn hard_settings(soft: &ShadowSettings) -> ShadowSettings {
    let method = match soft.hard {
        HardShadows::Map => ShadowMethod::Map,
        HardShadows::Slb => ShadowMethod::Slb,
    };
    ShadowSettings { samples: 1, ..soft.with_method(method) }
}

impl Technique for TwoMapSoft {
    fn build(&self, scene: &Scene, light: &Light, bounds: (Vec3, Vec3), pool: &mut MapPool) -> ShadowTerm {
        let shadow = hard_settings(&light.shadow);
        let hard = technique(shadow.method);
        let mut build = |l: &Light| hard.build(scene, &Light { shadow, ..l.clone() }, bounds, pool);
        match TwoMaps::build(light, bounds, &mut build) {
            Some(two) => ShadowTerm::new(two),
            // No size, or directional: the hard shadow alone.
            None => build(light),
        }
    }

    fn bytes_needed(&self, light: &Light, bounds: (Vec3, Vec3)) -> usize {
        let shadow = hard_settings(&light.shadow);
        let hard = |l: &Light| technique(shadow.method).bytes_needed(&Light { shadow, ..l.clone() }, bounds);
        match TwoMaps::hard_lights(light, bounds) {
            Some(lights) => lights.iter().map(hard).sum(),
            None => hard(light),
        }
    }

    fn per_pixel(&self) -> bool {
        true
    }
}

impl LightTerm for TwoMaps {
    fn lit(&self, p: Vec3, cos_theta: f32, receiver: &Receiver) -> f32 {
        TwoMaps::lit(self, p, cos_theta, receiver)
    }

    fn set_view(&mut self, view: Option<PixelView>) {
        TwoMaps::set_view(self, view);
    }

    fn per_pixel(&self) -> bool {
        true
    }

    fn prepare(&mut self, surfaces: &ScreenSurfaces) {
        TwoMaps::prepare(self, surfaces);
    }

    fn memory_bytes(&self) -> usize {
        TwoMaps::memory_bytes(self)
    }

    fn into_buffers(self: Box<Self>) -> Vec<VisibilityBuffer> {
        self.into_hard().into_iter().flat_map(ShadowTerm::into_buffers).collect()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}
