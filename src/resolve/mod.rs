//! Resolve: the linear float accumulation buffer becomes displayable 8-bit sRGB
//! (exposure, clamp to [0, 1], then the sRGB transfer curve). Float outputs skip
//! this stage and keep the buffer's values.

mod dda;
pub mod edges;
mod intersections;
mod parts;
pub mod solid_edges;

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
