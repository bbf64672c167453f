//! The environment: an equirectangular (latitude–longitude) image around the
//! scene, used as seed 002 eq. 4's reflection map Mape — looked up along the mirror
//! direction of the view at each surface and scaled by the material's Km — and,
//! optionally, as the background that rays leaving the scene see.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::Texture;

/// An image surrounding the scene at infinity.
#[derive(Debug, Clone)]
pub struct Environment {
    /// Equirectangular image: u = longitude (0 at −z, increasing towards +x),
    /// v = 0 straight up (+y) to 1 straight down.
    pub map: Arc<Texture>,
    /// Multiplies the image.
    pub intensity: f32,
    /// Rotation about +y, radians.
    pub rotation: f32,
    /// Whether pixels and rays that meet nothing see the environment (otherwise
    /// they see the flat background colour; reflections still use the map).
    pub visible: bool,
}

impl Environment {
    /// Light arriving from direction `dir` (need not be unit length).
    #[must_use]
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        self.map.sample(Self::uv(dir, self.rotation)) * self.intensity
    }

    /// The image position of direction `dir` turned by `rotation` about +y.
    #[must_use]
    pub fn uv(dir: Vec3, rotation: f32) -> Vec2 {
        let d = dir.normalize_or(Vec3::NEG_Z);
        let longitude = d.x.atan2(-d.z) - rotation;
        let u = 0.5 + longitude / std::f32::consts::TAU;
        let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        Vec2::new(u.rem_euclid(1.0), v.clamp(0.0, 1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_map_to_the_expected_image_positions() {
        let uv = |d: Vec3| Environment::uv(d, 0.0);
        assert!((uv(Vec3::NEG_Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((uv(Vec3::X) - Vec2::new(0.75, 0.5)).length() < 1e-6);
        assert!((uv(Vec3::NEG_X) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!(uv(Vec3::Y).y < 1e-6 && (uv(Vec3::NEG_Y).y - 1.0).abs() < 1e-6);
        // A quarter turn moves +x to where −z was.
        assert!((Environment::uv(Vec3::X, std::f32::consts::FRAC_PI_2) - Vec2::new(0.5, 0.5)).length() < 1e-6);
    }
}
