//! A frame of a solid's visible surfaces kept from scan to scan, as a viewer
//! keeps its buffer while the camera moves ([`super::scan_solid_into`]).
//!
//! A scan writes only the columns its scanline walk may cover (the occupants'
//! ends, procedure 2 of seed 003 §5); every other pixel must read `None`. The
//! frame remembers, per row, the columns the last scan wrote, so the next one
//! clears only those it does not write again instead of the whole image: at
//! 1280x720 a frame is 22 MB of surfaces, and clearing all of it was a tenth
//! to a fifth of a small model's scan.

use std::ops::Range;

use rayon::prelude::*;

use crate::csg::Crossing;

/// Each pixel's visible surface (rows top to bottom, `None` where the ray
/// misses), and per row the columns that may hold one.
#[derive(Debug, Clone, Default)]
pub struct SurfaceFrame {
    width: usize,
    pixels: Vec<Option<Crossing>>,
    /// Per row, the columns outside which every pixel is `None`.
    written: Vec<Range<usize>>,
}

impl SurfaceFrame {
    /// An empty frame (it takes its size from the first scan).
    #[must_use]
    pub fn new() -> SurfaceFrame {
        SurfaceFrame::default()
    }

    /// The pixels, rows top to bottom.
    #[must_use]
    pub fn pixels(&self) -> &[Option<Crossing>] {
        &self.pixels
    }

    /// The pixels, rows top to bottom, the frame given up.
    #[must_use]
    pub fn into_pixels(self) -> Vec<Option<Crossing>> {
        self.pixels
    }

    /// Made `width` x `height`: all `None` if its size changes.
    pub(super) fn fit(&mut self, width: usize, height: usize) {
        if self.width != width || self.written.len() != height {
            *self = SurfaceFrame { width, pixels: vec![None; width * height], written: vec![0..0; height] };
        }
    }

    /// Every pixel `None`.
    pub(super) fn clear(&mut self) {
        let w = self.width;
        for (row, written) in self.pixels.chunks_mut(w.max(1)).zip(&mut self.written) {
            row[written.clone()].fill(None);
            *written = 0..0;
        }
    }

    /// The frame in bands of `rows` rows, in parallel: each band's pixels
    /// and its rows' written columns (for [`row_to_write`]).
    pub(super) fn bands_mut(
        &mut self,
        rows: usize,
    ) -> impl IndexedParallelIterator<Item = (&mut [Option<Crossing>], &mut [Range<usize>])> {
        self.pixels.par_chunks_mut(self.width * rows).zip(self.written.par_chunks_mut(rows))
    }
}

/// A row's pixels about to be written over `columns`: those the last scan
/// wrote outside them cleared, and `columns` remembered.
pub(super) fn row_to_write<'a>(
    pixels: &'a mut [Option<Crossing>],
    written: &mut Range<usize>,
    columns: Range<usize>,
) -> &'a mut [Option<Crossing>] {
    let last = written.clone();
    pixels[last.start..columns.start.clamp(last.start, last.end)].fill(None);
    pixels[columns.end.clamp(last.start, last.end)..last.end].fill(None);
    *written = columns;
    pixels
}
