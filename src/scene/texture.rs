//! Colour textures, decoded once to linear RGB and sampled bilinearly with repeat.

use glam::{Vec2, Vec3};

/// A decoded texture in linear RGB.
#[derive(Debug, Clone)]
pub struct Texture {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
}

impl Texture {
    /// Decodes an encoded image (PNG or JPEG). `srgb` says whether its values are
    /// sRGB-encoded colours (true for colour maps) or already linear.
    pub fn decode(bytes: &[u8], srgb: bool) -> Result<Texture, String> {
        let img = image::load_from_memory(bytes).map_err(|e| e.to_string())?.into_rgb32f();
        let (width, height) = img.dimensions();
        if width == 0 || height == 0 {
            return Err("the image has no pixels".into());
        }
        let decode = |c: f32| if srgb { srgb_to_linear(c) } else { c };
        let texels = img.pixels().map(|p| Vec3::new(decode(p[0]), decode(p[1]), decode(p[2]))).collect();
        Ok(Texture { width, height, texels })
    }

    /// A texture from linear texels, row 0 at the top. Panics if the sizes disagree.
    #[must_use]
    pub fn from_texels(width: u32, height: u32, texels: Vec<Vec3>) -> Texture {
        assert_eq!(texels.len(), (width * height) as usize, "texel count");
        Texture { width, height, texels }
    }

    /// Bilinear sample at `uv` (origin top-left, texel centres at +0.5), repeating.
    #[must_use]
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return self.texels[0];
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let at = |i: i64, j: i64| self.texels[(j.rem_euclid(h) * w + i.rem_euclid(w)) as usize];
        let (i, j) = (x0 as i64, y0 as i64);
        let top = at(i, j).lerp(at(i + 1, j), fx);
        let bottom = at(i, j + 1).lerp(at(i + 1, j + 1), fx);
        top.lerp(bottom, fy)
    }
}

/// sRGB transfer function, decoding direction.
#[must_use]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB transfer function, encoding direction.
#[must_use]
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_repeats_and_interpolates() {
        let t = Texture::from_texels(2, 1, vec![Vec3::ZERO, Vec3::ONE]);
        assert_eq!(t.sample(Vec2::new(0.25, 0.5)), Vec3::ZERO);
        assert_eq!(t.sample(Vec2::new(0.75, 0.5)), Vec3::ONE);
        assert!((t.sample(Vec2::new(0.5, 0.5)).x - 0.5).abs() < 1e-6);
        // u = 0 lies halfway between the last texel (wrapped) and the first.
        assert!((t.sample(Vec2::new(0.0, 0.5)).x - 0.5).abs() < 1e-6);
        assert_eq!(t.sample(Vec2::new(1.25, 0.5)), Vec3::ZERO);
    }

    #[test]
    fn srgb_round_trip() {
        for c in [0.0, 0.001, 0.2, 0.5, 1.0] {
            assert!((srgb_to_linear(linear_to_srgb(c)) - c).abs() < 1e-5);
        }
    }
}
