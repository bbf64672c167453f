//! What both edge walkers find and the plan reads: one blend of a crossed
//! pixel towards the pixel across, and a set of pixels as bits.

use glam::Vec2;

/// One blend of the edge pass: pixel `c` moves towards pixel `o` by `alpha`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeBlend {
    /// The pixel the edge crosses: its index among the pixels the frame's
    /// visibility buffer holds ([`crate::visibility::VisibilityBuffer::index`]).
    pub c: u32,
    /// The pixel across the edge.
    pub o: u32,
    /// How far `c` moves: under the coverage filter the share of `c`'s area on
    /// `o`'s side of the edge (≤ ½); under the paper's, its Wu weight (≤ 1).
    pub alpha: f32,
    /// Whether `c` shows the edge's own surface (else what lies behind the edge).
    pub inside: bool,
    /// The edge: object index (high 32 bits) and edge index within its mesh.
    pub source: u64,
    /// Where in `c` the part on `o`'s side of the edge has its centroid, from
    /// `c`'s centre (pixels, y down).
    pub far: Vec2,
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
