//! Fog, done the way seed 002 §3.5 says.
//!
//! Fogging every component as it is drawn would fade a shadowed region towards
//! black: the shadow pass's black is fogged too. The paper instead renders every
//! component with BLACK fog — each scaled by 1 − f(d) — and then one more
//! component: every object in a black material with the fog colour, f(d) · fog,
//! which no shadow suppresses. Their sum is `lerp(colour, fog, f(d))` everywhere,
//! in shadow or not. Scaling is linear, so kage scales each image once after its
//! passes ([`apply`]) rather than every pass: the same sum, one sweep.
//!
//! d is the distance from the eye to the visible surface along the pixel's ray
//! (orthographic views: from the image plane), recovered from the visibility
//! buffer's depth. Pixels that see nothing keep the background.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::image::LinearImage;
use crate::scene::{Camera, Projection, Scene};
use crate::visibility::VisibilityBuffer;

/// How fog thickens with distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FogMode {
    /// f = (d − start) / (end − start), clamped to [0, 1].
    Linear {
        /// Distance where fog begins.
        start: f32,
        /// Distance where fog is complete.
        end: f32,
    },
    /// f = 1 − e^(−density · d).
    Exp {
        /// Extinction per unit distance.
        density: f32,
    },
    /// f = 1 − e^(−(density · d)²).
    Exp2 {
        /// Extinction per unit distance.
        density: f32,
    },
}

/// Fog of one colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fog {
    /// How f grows with distance.
    pub mode: FogMode,
    /// Linear RGB colour of full fog.
    pub color: Vec3,
}

impl Fog {
    /// The fog amount f(d) ∈ [0, 1] at distance `d`.
    #[must_use]
    pub fn amount(&self, d: f32) -> f32 {
        let f = match self.mode {
            FogMode::Linear { start, end } => (d - start) / (end - start).max(f32::MIN_POSITIVE),
            FogMode::Exp { density } => 1.0 - (-density * d).exp(),
            FogMode::Exp2 { density } => 1.0 - (-(density * d) * (density * d)).exp(),
        };
        f.clamp(0.0, 1.0)
    }

    /// The fog amount at world point `p` seen by `camera` (the same distance as
    /// [`fog_amounts`] measures: along the ray, or from the image plane when
    /// orthographic).
    #[must_use]
    pub fn amount_at(&self, camera: &Camera, p: Vec3) -> f32 {
        let d = match camera.projection {
            Projection::Perspective { .. } => (p - camera.eye).length(),
            Projection::Orthographic { .. } => (p - camera.eye).dot((camera.target - camera.eye).normalize()),
        };
        self.amount(d)
    }
}

/// Per pixel, the fog amount f(d) of the surface it sees (0 where it sees nothing).
#[must_use]
pub fn fog_amounts(scene: &Scene, fog: &Fog, vb: &VisibilityBuffer) -> Vec<f32> {
    let w = vb.width() as usize;
    let rays = scene.camera.pixel_rays(Vec2::new(w as f32, vb.height() as f32));
    let mut out = vec![0.0; vb.depths().len()];
    out.par_chunks_mut(w).zip(vb.depths().par_chunks(w)).enumerate().for_each(|(y, (row, depth))| {
        for (x, (f, &z)) in row.iter_mut().zip(depth).enumerate() {
            if z > 0.0 {
                let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                *f = fog.amount(scene.camera.distance_at_depth(&ray, z));
            }
        }
    });
    out
}

/// Black fog on `image` (every component scaled by 1 − f), plus `color` · f, the
/// fog component (black for an image that does not hold it).
pub fn apply(image: &mut LinearImage, amounts: &[f32], color: Vec3) {
    image.pixels_mut().par_iter_mut().zip(amounts.par_iter()).for_each(|(p, &f)| *p = *p * (1.0 - f) + color * f);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amounts_follow_their_formulas() {
        let fog = |mode| Fog { mode, color: Vec3::ONE };
        let lin = fog(FogMode::Linear { start: 2.0, end: 6.0 });
        assert_eq!((lin.amount(1.0), lin.amount(4.0), lin.amount(9.0)), (0.0, 0.5, 1.0));
        let exp = fog(FogMode::Exp { density: 0.5 });
        assert!((exp.amount(2.0) - (1.0 - (-1.0f32).exp())).abs() < 1e-6);
        let exp2 = fog(FogMode::Exp2 { density: 0.5 });
        assert!((exp2.amount(4.0) - (1.0 - (-4.0f32).exp())).abs() < 1e-6);
    }
}
