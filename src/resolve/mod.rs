//! Resolve: the linear float accumulation buffer becomes displayable 8-bit sRGB
//! (exposure, clamp to [0, 1], then the sRGB transfer curve). Float outputs skip
//! this stage and keep the buffer's values.

mod dda;
pub mod edges;
mod intersections;
pub mod jitter;
mod parts;
pub mod solid_edges;

use glam::Vec3;

pub use jitter::Antialias;

use crate::scene::texture::linear_to_srgb;

/// How bright the 8-bit image is made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Exposure {
    /// Multiply by 2^stops (0: the buffer as it is).
    Stops(f32),
    /// Scale so the brightest 5% of pixels just reach white (for scenes lit in
    /// physical units, such as glTF lights in candela).
    Auto,
}

impl Default for Exposure {
    fn default() -> Self {
        Exposure::Stops(0.0)
    }
}

impl Exposure {
    /// The linear multiplier this exposure applies to `image`.
    #[must_use]
    pub fn scale(self, image: &LinearImage) -> f32 {
        match self {
            Exposure::Stops(ev) => ev.exp2(),
            Exposure::Auto => {
                let mut lum: Vec<f32> =
                    image.pixels().iter().map(|p| p.dot(glam::Vec3::new(0.2126, 0.7152, 0.0722))).collect();
                if lum.is_empty() {
                    return 1.0;
                }
                let k = (lum.len() * 95 / 100).min(lum.len() - 1);
                let (_, p95, _) = lum.select_nth_unstable_by(k, f32::total_cmp);
                if *p95 > 0.0 && p95.is_finite() {
                    (0.9 / *p95).clamp(1.0 / 4096.0, 4096.0)
                } else {
                    1.0
                }
            }
        }
    }
}

/// A linear-light RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Default)]
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

    /// 8-bit sRGB of the image times `scale` (the exposure), RGB interleaved, rows
    /// top to bottom.
    #[must_use]
    pub fn to_srgb8(&self, scale: f32) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| p.to_array())
            .map(|c| (linear_to_srgb((c * scale).clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
            .collect()
    }
}

/// A set of pixels (row-major indices, or any small integers) as one bit each.
pub(crate) struct PixelSet {
    words: Vec<u64>,
}

impl PixelSet {
    /// An empty set of pixels below `len`.
    pub(crate) fn new(len: u32) -> PixelSet {
        PixelSet { words: vec![0; (len as usize).div_ceil(64)] }
    }

    /// Adds `i`.
    pub(crate) fn insert(&mut self, i: u32) {
        self.words[i as usize / 64] |= 1 << (i % 64);
    }

    /// Whether `i` is in the set.
    pub(crate) fn contains(&self, i: u32) -> bool {
        self.words.get(i as usize / 64).is_some_and(|w| w & (1 << (i % 64)) != 0)
    }
}
