//! A method added by a test: every point half lit. It is a unit of its own
//! behind [`Technique`] and an entry in the scene's list of methods
//! (`ShadowMethod::HalfLit`), and nothing else of the renderer changes for
//! it: the light's terms are built, kept by the pool and looked up as any
//! method's.

use std::any::Any;

use glam::Vec3;

use super::Technique;
use crate::scene::{Light, Scene};
use crate::shadows::{LightTerm, MapPool, Receiver, ShadowTerm};
use crate::visibility::VisibilityBuffer;

/// The method `half-lit`.
pub struct HalfLit;

impl Technique for HalfLit {
    fn build(&self, _: &Scene, _: &Light, _: (Vec3, Vec3), _: &mut MapPool) -> ShadowTerm {
        ShadowTerm::new(Half)
    }

    fn bytes_needed(&self, _: &Light, _: (Vec3, Vec3)) -> usize {
        0
    }
}

/// The term: a half everywhere.
#[derive(Debug)]
struct Half;

impl LightTerm for Half {
    fn lit(&self, _: Vec3, _: f32, _: &Receiver) -> f32 {
        0.5
    }

    fn memory_bytes(&self) -> usize {
        0
    }

    fn into_buffers(self: Box<Self>) -> Vec<VisibilityBuffer> {
        Vec::new()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use wide::f32x8;

    use crate::scene::{demo::demo_scene, ShadowMethod};
    use crate::shadows::{MapPool, Receiver, ReceiverLanes, ShadowTerm};

    /// Named in a scene file, the method is read and its terms come from the
    /// pool the frame's passes use, one point or eight at a time.
    #[test]
    fn a_method_in_the_list_is_named_built_and_looked_up() {
        let mut scene = demo_scene().expect("the demo loads");
        assert_eq!(ShadowMethod::named("Half-Lit"), Some(ShadowMethod::HalfLit));
        for light in &mut scene.lights {
            light.shadow = light.shadow.with_method(ShadowMethod::HalfLit);
            light.size = 0.0;
        }
        assert!(!scene.lights[0].shadow.applies("resolution"), "it reads no map's settings");
        let bounds = scene.caster_bounds().expect("the demo casts");
        let mut pool = MapPool::default();
        pool.begin_frame(&scene);
        let terms = pool.terms(&scene, &scene.lights, bounds);
        assert_eq!(terms.len(), scene.lights.len());
        for term in &terms {
            assert!(term.casts());
            assert_eq!(ShadowTerm::bytes_needed(&scene.lights[0], bounds), 0);
            assert_eq!(term.lit(Vec3::new(0.3, 0.0, -1.0), 0.8, &Receiver::UNKNOWN), 0.5);
            let p = [f32x8::splat(0.3), f32x8::ZERO, f32x8::splat(-1.0)];
            assert_eq!(term.lit_lanes(p, f32x8::splat(0.8), &ReceiverLanes::UNKNOWN).to_array(), [0.5; 8]);
        }
        terms.into_iter().for_each(|t| pool.recycle(t));
    }
}
