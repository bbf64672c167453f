//! Resolve: the linear float accumulation buffer becomes displayable 8-bit sRGB
//! (exposure, clamp to [0, 1], then the sRGB transfer curve). Float outputs skip
//! this stage and keep the buffer's values.

mod dda;
pub mod edges;
mod intersections;
pub mod jitter;
mod parts;
pub mod solid_edges;

pub use jitter::Antialias;

use crate::image::LinearImage;

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
