//! The environment: an equirectangular (latitude–longitude) image around the
//! scene, used as seed 002 eq. 4's reflection map Mape — looked up along the mirror
//! direction of the view at each surface and scaled by the material's Km — and,
//! optionally, as the background that rays leaving the scene see.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::texture::Wrap;
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
    /// The environment of equirectangular image `map` (its wrap mode set to
    /// [`Wrap::Longitude`]), scaled by `intensity`, turned by `rotation`
    /// radians about +y, `visible` as the background or not.
    #[must_use]
    pub fn new(map: Arc<Texture>, intensity: f32, rotation: f32, visible: bool) -> Environment {
        let mut map = Arc::unwrap_or_clone(map);
        map.wrap = Wrap::Longitude;
        Environment { map: Arc::new(map), intensity, rotation, visible }
    }

    /// Light arriving from direction `dir` (need not be unit length).
    #[must_use]
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        self.map.sample(Self::uv(dir, self.rotation)) * self.intensity
    }

    /// A photo studio around the scene, for metals to mirror when a model
    /// comes without an environment: a bright overhead softbox fading to a
    /// mid-grey horizon, two tall strip lights left and right in front, a dark
    /// floor below. Not visible as the background.
    #[must_use]
    pub fn studio() -> Environment {
        let (w, h) = (256u32, 128u32);
        let texels = (0..w * h)
            .map(|i| {
                let (u, v) = (((i % w) as f32 + 0.5) / w as f32, ((i / w) as f32 + 0.5) / h as f32);
                let elevation = (0.5 - v) * std::f32::consts::PI; // +π/2 up
                                                                  // Degrees round from the front (+z), which is u = 0.
                let azimuth = (u - 0.5).abs() * 360.0 - 180.0;
                let sky = if elevation > 0.0 {
                    let e = elevation.sin();
                    0.5 + 1.1 * smoothstep(0.75, 0.9, e)
                } else {
                    0.18 - 0.06 * (-elevation).sin()
                };
                let strip = (azimuth.abs() - 60.0).abs() < 9.0 && (0.0..0.75).contains(&elevation);
                Vec3::splat(if strip { 2.0 } else { sky })
            })
            .collect();
        Environment::new(Arc::new(Texture::from_texels(w, h, texels)), 1.0, 0.0, false)
    }

    /// Light arriving from around direction `dir`, filtered over the
    /// directions `right` and `down` that the neighbouring pixels see (the
    /// image level whose texels match that spread, so that a curved mirror
    /// seen small does not alias the map into moiré).
    #[must_use]
    pub fn radiance_over(&self, dir: Vec3, right: Vec3, down: Vec3) -> Vec3 {
        let unit = |d: Vec3| d.normalize_or(Vec3::NEG_Z);
        let d = unit(dir);
        // The spread: the larger angle to a neighbour's direction (the chord,
        // which is the angle for the small spreads of neighbouring pixels).
        // An angle θ spans θ/2π of the image across at the equator and θ/π
        // down; across, rows near the poles hold the same texels for fewer
        // directions, which must not pick a coarser level: the equator's
        // width is the one taken.
        let angle = (unit(right) - d).length().max((unit(down) - d).length());
        let duv = [Vec2::new(angle / std::f32::consts::TAU, 0.0), Vec2::new(0.0, angle / std::f32::consts::PI)];
        self.map.sample_footprint(Self::uv(d, self.rotation), duv) * self.intensity
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

fn smoothstep(lo: f32, hi: f32, x: f32) -> f32 {
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_studio_is_bright_above_grey_at_the_horizon_dark_below() {
        let s = Environment::studio();
        let (up, side, down) =
            (s.radiance(Vec3::Y).x, s.radiance(Vec3::new(0.0, 0.05, -1.0)).x, s.radiance(Vec3::NEG_Y).x);
        assert!(up > 1.4 && (0.4..0.7).contains(&side) && down < 0.2, "up {up}, horizon {side}, down {down}");
        // The strip lights stand 60° either side of the front (+z).
        let strip = |deg: f32| s.radiance(Vec3::new(deg.to_radians().sin(), 0.3, deg.to_radians().cos())).x;
        assert!(
            strip(60.0) > 1.5 && strip(-60.0) > 1.5 && strip(0.0) < 1.0,
            "{} {} {}",
            strip(60.0),
            strip(-60.0),
            strip(0.0)
        );
        assert!(!s.visible);
    }

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
