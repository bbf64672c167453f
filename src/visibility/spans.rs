//! A scanline's intervals as seed 003's walk reads them (§5.2's per-pixel
//! interval of each occupant): each occupant's eight-pixel blocks of lanes,
//! found once per block ([`BlockSpans`]), and the readers the booleans, the
//! block spreading ([`super::block`]) and the union's z-buffer take them
//! through ([`RowSpans`]), with occupants beyond a [`Horizon`] left out.

use std::cell::{Cell, RefCell};

use crate::raytrace::csg::{
    Booleans, CsgCaster, FacesOnScreen, Hit, Interval, IntervalLanes, LeafSpans, RowFaces, SpanScratch,
};
use crate::scene::camera::RowLine;
use crate::visibility::block::BlockOrder;
use crate::visibility::horizon::Horizon;

/// Relative depth by which a primitive must lie behind a pixel's surface
/// for the union's z-buffer to leave it unsolved there (far above the
/// rounding of a computed interval).
const DEPTH_MARGIN: f32 = 1e-4;

/// Each occupant's intervals at the eight-pixel block of the scanline last
/// asked of it: the first pixel of a block that needs a primitive's interval
/// gets all eight in one SIMD pass ([`CsgCaster::spans_on_eight`], each the
/// same to the bit as one pixel's), and its neighbours read theirs.
#[derive(Default)]
pub(super) struct BlockSpans {
    /// Per primitive, two slots (even blocks, odd blocks): the block
    /// (`x / 8`) its lanes hold, and the lanes — a block's and the one
    /// before it.
    cached: RefCell<Vec<[(usize, IntervalLanes); 2]>>,
    /// Per primitive: the faces the row's rays can cross (polyhedra of many
    /// planes).
    faces: Vec<RowFaces>,
}

impl BlockSpans {
    /// Room for a solid of `primitives` (what it held before is stale:
    /// [`BlockSpans::begin_row`] marks each row's occupants so).
    pub(super) fn fit(&mut self, primitives: usize) {
        self.cached.get_mut().resize(primitives, [(usize::MAX, IntervalLanes::default()); 2]);
        self.faces.resize(primitives, RowFaces::default());
    }

    /// A new scanline, its rays `lines` in each occupant's space: the
    /// occupants' lanes (of the row before) are stale, and their faces
    /// the row can cross are found (`faces` holds
    /// [`CsgCaster::faces_on_screen`] per primitive, `y` is the scanline).
    pub(super) fn begin_row(
        &mut self,
        caster: &CsgCaster,
        occupants: impl Iterator<Item = usize>,
        lines: &[RowLine],
        (faces, y): (&[Option<FacesOnScreen>], usize),
    ) {
        let cached = self.cached.get_mut();
        for i in occupants {
            cached[i].iter_mut().for_each(|c| c.0 = usize::MAX);
            let screen = faces[i].as_ref().map(|s| (s, y));
            caster.row_faces(i, &lines[i], screen, &mut self.faces[i]);
        }
    }

    /// `read` of primitive `i`'s intervals at the eight pixels of `block` of
    /// its row line `unit`.
    #[inline(always)]
    fn lanes<R>(
        &self,
        (caster, i, unit): (&CsgCaster, usize, &RowLine),
        block: usize,
        read: impl FnOnce(&IntervalLanes) -> R,
    ) -> R {
        let mut cached = self.cached.borrow_mut();
        self.fill_if_stale(&mut cached[i][block % 2], caster, i, unit, block);
        read(&cached[i][block % 2].1)
    }

    /// Primitive `i`'s interval at pixel `x` of its row line `unit`.
    #[inline(always)]
    pub(super) fn span(&self, caster: &CsgCaster, i: usize, unit: &RowLine, x: usize) -> Option<Interval> {
        let mut cached = self.cached.borrow_mut();
        let slot = &mut cached[i][x / 8 % 2];
        self.fill_if_stale(slot, caster, i, unit, x / 8);
        slot.1.get(x % 8)
    }

    /// Primitive `i`'s cache entry `cached` made to hold `block`.
    #[inline(always)]
    fn fill_if_stale(
        &self,
        (cached, lanes): &mut (usize, IntervalLanes),
        caster: &CsgCaster,
        i: usize,
        unit: &RowLine,
        block: usize,
    ) {
        if *cached != block {
            *cached = block;
            Self::fill(caster, i, unit, block, &self.faces[i], lanes);
        }
    }

    /// Primitive `i`'s lanes for `block`, into `lanes`: once per eight
    /// pixels, not inlined.
    #[inline(never)]
    fn fill(caster: &CsgCaster, i: usize, unit: &RowLine, block: usize, faces: &RowFaces, lanes: &mut IntervalLanes) {
        caster.spans_on_eight(i, unit, block, faces, lanes);
    }
}

/// A scanline's intervals as the booleans read them: each occupant's
/// eight-pixel blocks ([`BlockSpans`]) along its row line.
pub(super) struct RowSpans<'a> {
    pub(super) blocks: &'a BlockSpans,
    pub(super) caster: &'a CsgCaster,
    pub(super) lines: &'a [RowLine],
}

impl RowSpans<'_> {
    /// A union of primitives' row (the paper's Table 1): each pixel's
    /// nearest entry beyond `near` over the occupants `ends`, found occupant
    /// by occupant a block of eight pixels at a time, as a z-buffer would
    /// (seed 003 §5.2's nearest surface over the segments, each segment one
    /// primitive; what the booleans give a union, ties included:
    /// [`Hit::nearer_than`]). The occupants come nearest first, each with its
    /// least depth, so that a block already showing nearer surfaces is not
    /// solved for the ones behind. `false`, the row half written, where a ray
    /// starts inside an occupant: the union's first surface there may be an
    /// exit, which the booleans find.
    pub(super) fn nearest_entries(&self, ends: &[(usize, i64, i64, f32)], near: f32, row: &mut [Option<Hit>]) -> bool {
        let last = row.len() as i64 - 1;
        for &(i, a, b, nearest) in ends {
            let (a, b) = (a.max(0), b.min(last));
            if a > b {
                continue;
            }
            let (a, b) = (a as usize, b as usize);
            // A block whose pixels all hold a surface nearer than any point
            // of the primitive (by a margin over the lanes' rounding) keeps
            // them unread; not where the near plane may cut the primitive.
            let behind = if nearest > near * (1.0 + DEPTH_MARGIN) { nearest * (1.0 - DEPTH_MARGIN) } else { f32::MIN };
            let primitive = (self.caster, i, &self.lines[i]);
            for block in a / 8..=b / 8 {
                let pixels = a.max(block * 8)..=b.min(block * 8 + 7);
                if row[pixels.clone()].iter().all(|h| h.is_some_and(|h| h.t < behind)) {
                    continue;
                }
                let inside = self.blocks.lanes(primitive, block, |lanes| {
                    for x in pixels {
                        let Some(s) = lanes.get(x % 8) else { continue };
                        if s.enter.t > near {
                            if row[x].is_none_or(|h| s.enter.nearer_than(&h)) {
                                row[x] = Some(s.enter);
                            }
                        } else if s.exit.t > near {
                            return true;
                        }
                    }
                    false
                });
                if inside {
                    return false;
                }
            }
        }
        true
    }

    /// Primitive `i`'s interval at pixel `x`.
    #[inline(always)]
    pub(super) fn at(&self, i: usize, x: usize) -> Option<Interval> {
        self.blocks.span(self.caster, i, &self.lines[i], x)
    }

    /// The booleans' answer at pixel `x` over the tree `root` (beyond the
    /// near plane at `near`): first with the occupants beyond `horizon` left
    /// out ([`super::horizon`]), then, if one was and the answer does not
    /// clear it, with none left out.
    #[inline(always)]
    pub(super) fn first_hit<B: Booleans>(
        &self,
        root: B,
        x: usize,
        near: f32,
        horizon: Horizon,
        scratch: &mut SpanScratch,
    ) -> Option<Hit> {
        let short = ShortSpans { all: PixelSpans { row: self, x }, horizon, hid: Cell::new(false) };
        let hit = self.caster.first_hit_in_by(root, &short, near, scratch);
        // Nothing left out, or an answer that clears the horizon: the whole
        // tree's answer.
        if !short.hid.get() || hit.is_some_and(|h| horizon.clears(h.t)) {
            return hit;
        }
        self.first_hit_everywhere(root, x, near, scratch)
    }

    /// [`RowSpans::first_hit`] with no occupant left out: the rarer case,
    /// kept out of line (and read through a closure, so that the booleans
    /// over [`ShortSpans`] and [`PixelSpans`] each keep one caller and are
    /// inlined into it).
    #[cold]
    #[inline(never)]
    fn first_hit_everywhere<B: Booleans>(
        &self,
        root: B,
        x: usize,
        near: f32,
        scratch: &mut SpanScratch,
    ) -> Option<Hit> {
        self.caster.first_hit_in_by(root, &|i| self.at(i, x), near, scratch)
    }

    /// [`BlockOrder::spread`] of `first`, the answer at pixel `x`, among the
    /// occupants `ids`, over the pixels after it up to `upto` (in its block):
    /// `row`'s pixels written as far as the answer holds, the last returned.
    /// (All occupants: the answer is the whole tree's, however found.)
    pub(super) fn spread(
        &self,
        order: &mut BlockOrder,
        ids: &[u32],
        (x, first): (usize, Option<Hit>),
        near: f32,
        (row, upto): (&mut [Option<Hit>], usize),
    ) -> usize {
        let mut cached = self.blocks.cached.borrow_mut();
        for &i in ids {
            let i = i as usize;
            self.blocks.fill_if_stale(&mut cached[i][x / 8 % 2], self.caster, i, &self.lines[i], x / 8);
        }
        let (x0, slot) = (x / 8 * 8, x / 8 % 2);
        let end = (x0 + 8).min(row.len());
        let at = |i: usize| (&cached[i][slot].1, x - x0);
        let run = (x - x0 + 1, upto - x0);
        x0 + order.spread(ids, (at, |i| &cached[i][slot].1), near, first, (&mut row[x0..end], run)).unwrap_or(x - x0)
    }

    /// The answer of pixel `x − 1` (the last of the block before, found with
    /// the same occupants `ids`) carried on into `x`'s block, up to `upto`,
    /// as [`RowSpans::spread`] hands an answer on inside a block: `row`'s
    /// pixels written from `x` as far as it holds, the last returned (`None`
    /// when it does not hold at `x`, or the lanes of `x − 1` are gone).
    pub(super) fn carry(
        &self,
        order: &mut BlockOrder,
        ids: &[u32],
        x: usize,
        near: f32,
        (row, upto): (&mut [Option<Hit>], usize),
    ) -> Option<usize> {
        let (block, before) = (x / 8, x / 8 - 1);
        let mut cached = self.blocks.cached.borrow_mut();
        if ids.iter().any(|&i| cached[i as usize][before % 2].0 != before) {
            return None;
        }
        for &i in ids {
            let i = i as usize;
            self.blocks.fill_if_stale(&mut cached[i][block % 2], self.caster, i, &self.lines[i], block);
        }
        let end = (x + 8).min(row.len());
        let at = |i: usize| (&cached[i][before % 2].1, 7);
        let (first, out) = (row[x - 1], &mut row[x..end]);
        order.spread(ids, (at, |i| &cached[i][block % 2].1), near, first, (out, (0, upto - x))).map(|last| x + last)
    }
}

/// The intervals at pixel `x` of a scanline: a [`LeafSpans`] whose reading
/// is inlined into the booleans (a closure of it was not, and its answer
/// came back through memory, a fifth of a small model's walk).
pub(super) struct PixelSpans<'a> {
    pub(super) row: &'a RowSpans<'a>,
    pub(super) x: usize,
}

impl LeafSpans for PixelSpans<'_> {
    #[inline(always)]
    fn span(&self, i: usize) -> Option<Interval> {
        self.row.at(i, self.x)
    }
}

/// [`PixelSpans`] short of a horizon: the occupants whose interval starts
/// at or beyond it read as missed ([`super::horizon`]).
struct ShortSpans<'a> {
    all: PixelSpans<'a>,
    horizon: Horizon,
    /// Whether an occupant was left out.
    hid: Cell<bool>,
}

impl LeafSpans for ShortSpans<'_> {
    #[inline(always)]
    fn span(&self, i: usize) -> Option<Interval> {
        let span = self.all.span(i)?;
        if self.horizon.hides(span.enter.t) {
            self.hid.set(true);
            return None;
        }
        Some(span)
    }
}
