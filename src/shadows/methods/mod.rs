//! The shadow methods, each one unit behind one interface: [`Technique`]
//! builds a light's term (its maps, per light) and says what they need in
//! memory before they are built; the term it builds answers per frame and per
//! point ([`super::LightTerm`]). The light's settings name the method
//! ([`ShadowMethod`], the scene's list of methods with the settings each
//! reads); [`technique`] is the one place a name becomes its unit.

mod map;
mod none;
mod pcss;
mod slb;
mod soft;

#[cfg(test)]
mod half_lit;

use glam::Vec3;

pub use map::MapTerm;
pub use pcss::PcssTerm;
pub use slb::SlbTerm;

use super::{MapPool, ShadowTerm};
use crate::scene::{Light, Scene, ShadowMethod};

/// One shadow method: what it builds per light.
pub trait Technique: Sync {
    /// `light`'s term over casters within `bounds`, its maps drawn in
    /// buffers taken from `pool`.
    fn build(&self, scene: &Scene, light: &Light, bounds: (Vec3, Vec3), pool: &mut MapPool) -> ShadowTerm;

    /// Bytes `light`'s maps hold at most (before they are built) with casters
    /// within `bounds`; screen images of a per-pixel term are the frame's
    /// and not counted.
    fn bytes_needed(&self, light: &Light, bounds: (Vec3, Vec3)) -> usize;

    /// Whether its terms are computed per pixel of the frame from the
    /// surfaces every pixel shows ([`super::LightTerm::prepare`]), so that
    /// a pixel's term may depend on pixels far from it: a tile of the frame
    /// then needs the whole frame drawn.
    fn per_pixel(&self) -> bool {
        false
    }
}

/// The unit that computes `method`'s terms.
#[must_use]
pub fn technique(method: ShadowMethod) -> &'static dyn Technique {
    match method {
        ShadowMethod::None => &none::NoShadows,
        ShadowMethod::Map => &map::PlainMaps,
        ShadowMethod::Slb => &slb::SilhouetteLines,
        ShadowMethod::Soft => &soft::TwoMapSoft,
        ShadowMethod::Pcss => &pcss::PercentageCloser,
        #[cfg(test)]
        ShadowMethod::HalfLit => &half_lit::HalfLit,
    }
}
