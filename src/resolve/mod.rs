//! Resolve: the linear float accumulation buffer becomes displayable 8-bit sRGB
//! (clamp to [0, 1], then the sRGB transfer curve). Float outputs skip this stage.

use glam::Vec3;

use crate::scene::texture::linear_to_srgb;

/// A linear-light RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearImage {
    width: u32,
    height: u32,
    pixels: Vec<Vec3>,
}

impl LinearImage {
    /// A black image. The size must have been checked.
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        LinearImage { width, height, pixels: vec![Vec3::ZERO; width as usize * height as usize] }
    }

    /// Makes the image `width` × `height`, reusing its memory when it can; the
    /// contents are undefined until written.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        self.pixels.resize(width as usize * height as usize, Vec3::ZERO);
    }

    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// All pixels, row-major.
    #[must_use]
    pub fn pixels(&self) -> &[Vec3] {
        &self.pixels
    }

    /// All pixels, row-major, for writing.
    pub fn pixels_mut(&mut self) -> &mut [Vec3] {
        &mut self.pixels
    }

    /// Pixel (x, y).
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// 8-bit sRGB, RGB interleaved, rows top to bottom.
    #[must_use]
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| p.to_array())
            .map(|c| (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
            .collect()
    }
}
