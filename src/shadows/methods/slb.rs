//! The silhouette-line buffer (seed 000): the plain method's maps, plus the
//! exact silhouette lines in the texels they cross, drawn into a view
//! `scale` times wider (the virtual projection space).

use std::any::Any;

use glam::Vec3;
use wide::f32x8;

use super::Technique;
use crate::scene::{Light, Scene, ShadowSettings};
use crate::shadows::placement::{place_maps, placed_bytes, Maps};
use crate::shadows::{lit_each, slb_bytes, LightTerm, MapPool, PixelView, Receiver, ReceiverLanes, ShadowTerm, SlbMap};
use crate::visibility::VisibilityBuffer;

/// The method `slb`.
pub struct SilhouetteLines;

impl Technique for SilhouetteLines {
    fn build(&self, scene: &Scene, light: &Light, bounds: (Vec3, Vec3), pool: &mut MapPool) -> ShadowTerm {
        let settings = light.shadow;
        let casters = pool.casters(scene);
        // The virtual projection space (seed 000 §4.4): the view `scale` times wider.
        let scale = settings.scale.max(f32::MIN_POSITIVE);
        let maps = place_maps(scene, light, bounds, pool, scale, |cam, res, pool| {
            // A cube face that sees no caster: one texel, nothing drawn.
            SlbMap::render(scene, &cam, res.unwrap_or(1), &casters, pool.workers, pool.take(), &settings)
        });
        match maps {
            Some(maps) => ShadowTerm::new(SlbTerm { maps, settings }),
            None => ShadowTerm::unshadowed(),
        }
    }

    fn bytes_needed(&self, light: &Light, bounds: (Vec3, Vec3)) -> usize {
        placed_bytes(light, bounds, |res| res * res * std::mem::size_of::<f32>() + slb_bytes(res))
    }
}

/// A light's term read from silhouette-line buffers.
#[derive(Debug)]
pub struct SlbTerm {
    maps: Maps<SlbMap>,
    settings: ShadowSettings,
}

impl SlbTerm {
    /// The buffers: one, or a cube's six.
    #[must_use]
    pub fn maps(&self) -> &[SlbMap] {
        self.maps.faces()
    }
}

impl LightTerm for SlbTerm {
    fn lit(&self, p: Vec3, cos_theta: f32, receiver: &Receiver) -> f32 {
        self.maps.at(p).lit(p, cos_theta, &self.settings, receiver)
    }

    fn lit_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
        match &self.maps {
            Maps::One(map) => map.lit_lanes(p, cos_theta, &self.settings, receivers),
            Maps::Cube(..) => lit_each(self, p, cos_theta, receivers),
        }
    }

    fn set_view(&mut self, view: Option<PixelView>) {
        self.maps.faces_mut().iter_mut().for_each(|m| m.set_view(view));
    }

    fn memory_bytes(&self) -> usize {
        self.maps.faces().iter().map(SlbMap::memory_bytes).sum()
    }

    fn into_buffers(self: Box<Self>) -> Vec<VisibilityBuffer> {
        self.maps.into_faces().into_iter().map(SlbMap::into_buffer).collect()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}
