//! A light's shadow term `shadow_i(x, y)` as the frame uses it: one built
//! term behind [`LightTerm`], whatever method made it. What a term needs per
//! frame (the pixel rays it looks up through, [`LightTerm::set_view`]; the
//! surfaces the frame's pixels show, [`LightTerm::prepare`]) and per point
//! ([`LightTerm::lit`], eight points at a time [`LightTerm::lit_lanes`]) is
//! the whole of what shading asks of it.

use std::any::Any;
use std::fmt::Debug;

use glam::Vec3;
use wide::f32x8;

use super::footprint::{PixelView, Receiver, ReceiverLanes};
use super::map::DepthMap;
use super::screen::ScreenSurfaces;
use crate::scene::ShadowSettings;
use crate::visibility::VisibilityBuffer;

/// One light's built shadow term: per frame, per point.
pub trait LightTerm: Debug + Send + Sync + Any {
    /// `shadow_i` at world point `p` on `receiver` with N·L = `cos_theta`: 1
    /// lit, 0 in shadow (between in a penumbra or on an antialiased edge).
    fn lit(&self, p: Vec3, cos_theta: f32, receiver: &Receiver) -> f32;

    /// [`LightTerm::lit`] for eight points (x, y, z lanes) on `receivers` with
    /// N·L `cos_theta`; by default one point at a time.
    fn lit_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
        lit_each(self, p, cos_theta, receivers)
    }

    /// Sets the pixel rays of the frame its lookups are for (`None`: points
    /// are decided at their centre). Terms that do not filter over a pixel's
    /// footprint ignore it.
    fn set_view(&mut self, view: Option<PixelView>) {
        let _ = view;
    }

    /// Whether the term is computed per pixel of the frame, and needs
    /// [`LightTerm::prepare`] before its lookups.
    fn per_pixel(&self) -> bool {
        false
    }

    /// Computes a per-pixel term at every pixel whose surfaces are
    /// `surfaces`; lookups of points the frame's pixels show read the
    /// result, others (a reflection's) are decided on their own.
    fn prepare(&mut self, surfaces: &ScreenSurfaces) {
        let _ = surfaces;
    }

    /// Whether the term can shadow anything.
    fn casts(&self) -> bool {
        true
    }

    /// The one depth map the term reads, one tap a point, and the settings
    /// it reads it with, when it is that (a plain map's term without PCF):
    /// its depth bounds then decide whole screen tiles of a soft term.
    fn one_tap_map(&self) -> Option<(&DepthMap, &ShadowSettings)> {
        None
    }

    /// Bytes its maps hold.
    fn memory_bytes(&self) -> usize;

    /// Gives up the term, handing back the buffers its maps were drawn in
    /// (for the next frame's maps).
    fn into_buffers(self: Box<Self>) -> Vec<VisibilityBuffer>;

    /// The term as [`Any`], for a caller that knows its method's type.
    fn as_any(&self) -> &dyn Any;
}

/// `term`'s [`LightTerm::lit`] at each of eight points (x, y, z lanes) in
/// turn.
#[must_use]
pub fn lit_each<T: LightTerm + ?Sized>(term: &T, p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
    let (x, y, z, c) = (p[0].to_array(), p[1].to_array(), p[2].to_array(), cos_theta.to_array());
    f32x8::new(std::array::from_fn(|i| term.lit(Vec3::new(x[i], y[i], z[i]), c[i], &receivers.lane(i))))
}

/// The term of a light that shadows nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Unshadowed;

impl LightTerm for Unshadowed {
    fn lit(&self, _: Vec3, _: f32, _: &Receiver) -> f32 {
        1.0
    }

    fn lit_lanes(&self, _: [f32x8; 3], _: f32x8, _: &ReceiverLanes) -> f32x8 {
        f32x8::ONE
    }

    fn casts(&self) -> bool {
        false
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

/// How one light's shadow term is evaluated: a built [`LightTerm`] of
/// whichever method the light's settings name.
#[derive(Debug)]
pub struct ShadowTerm(Box<dyn LightTerm>);

impl ShadowTerm {
    /// The term `term`.
    #[must_use]
    pub fn new(term: impl LightTerm) -> ShadowTerm {
        ShadowTerm(Box::new(term))
    }

    /// The term of a light that shadows nothing.
    #[must_use]
    pub fn unshadowed() -> ShadowTerm {
        ShadowTerm::new(Unshadowed)
    }

    /// The method's own term, when it is a `T`.
    #[must_use]
    pub fn downcast_ref<T: LightTerm>(&self) -> Option<&T> {
        self.0.as_any().downcast_ref()
    }

    /// See [`LightTerm::set_view`].
    pub fn set_view(&mut self, view: Option<PixelView>) {
        self.0.set_view(view);
    }

    /// See [`LightTerm::per_pixel`].
    #[must_use]
    pub fn per_pixel(&self) -> bool {
        self.0.per_pixel()
    }

    /// See [`LightTerm::prepare`].
    pub fn prepare(&mut self, surfaces: &ScreenSurfaces) {
        self.0.prepare(surfaces);
    }

    /// See [`LightTerm::casts`].
    #[must_use]
    pub fn casts(&self) -> bool {
        self.0.casts()
    }

    /// See [`LightTerm::lit`].
    #[must_use]
    pub fn lit(&self, p: Vec3, cos_theta: f32, receiver: &Receiver) -> f32 {
        self.0.lit(p, cos_theta, receiver)
    }

    /// See [`LightTerm::lit_lanes`].
    #[must_use]
    pub fn lit_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
        self.0.lit_lanes(p, cos_theta, receivers)
    }

    /// See [`LightTerm::one_tap_map`].
    #[must_use]
    pub fn one_tap_map(&self) -> Option<(&DepthMap, &ShadowSettings)> {
        self.0.one_tap_map()
    }

    /// See [`LightTerm::memory_bytes`].
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }

    /// See [`LightTerm::into_buffers`].
    #[must_use]
    pub fn into_buffers(self) -> Vec<VisibilityBuffer> {
        self.0.into_buffers()
    }

    /// The mean of `terms`' [`ShadowTerm::lit`] (1 when there are none): the
    /// shadow term of an area light from its jittered samples' maps.
    #[must_use]
    pub fn mean_lit(terms: &[ShadowTerm], p: Vec3, cos_theta: f32, receiver: &Receiver) -> f32 {
        match terms {
            [] => 1.0,
            [one] => one.lit(p, cos_theta, receiver),
            _ => terms.iter().map(|t| t.lit(p, cos_theta, receiver)).sum::<f32>() / terms.len() as f32,
        }
    }

    /// [`ShadowTerm::mean_lit`] for eight points.
    #[must_use]
    pub fn mean_lit_lanes(terms: &[ShadowTerm], p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
        match terms {
            [] => f32x8::ONE,
            [one] => one.lit_lanes(p, cos_theta, receivers),
            _ => {
                let sum = terms.iter().fold(f32x8::ZERO, |acc, t| acc + t.lit_lanes(p, cos_theta, receivers));
                sum * f32x8::splat(1.0 / terms.len() as f32)
            }
        }
    }
}
