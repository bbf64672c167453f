//! No shadows: the light reaches every point it faces.

use glam::Vec3;

use super::Technique;
use crate::scene::{Light, Scene};
use crate::shadows::{MapPool, ShadowTerm};

/// The method `none`.
pub struct NoShadows;

impl Technique for NoShadows {
    fn build(&self, _: &Scene, _: &Light, _: (Vec3, Vec3), _: &mut MapPool) -> ShadowTerm {
        ShadowTerm::unshadowed()
    }

    fn bytes_needed(&self, _: &Light, _: (Vec3, Vec3)) -> usize {
        0
    }
}
