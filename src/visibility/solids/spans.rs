//! A scanline's intervals as seed 003's walk reads them (§5.2's per-pixel
//! interval of each occupant): each occupant's eight-pixel blocks of lanes,
//! found once per block ([`BlockSpans`]), and the readers the booleans and
//! the block spreading ([`super::block`]) take them through ([`RowSpans`]),
//! with occupants beyond a [`Horizon`] left out. (A union's z-buffer solves
//! each occupant's block once, uncached: [`BlockSpans::solve`], read by
//! [`super::zbuffer`].)

use std::cell::{Cell, RefCell};

use super::block::{BlockLanes, BlockOrder, BlockRun};
use super::horizon::Horizon;
use super::layers::MeshLayers;
use crate::camera::RowLine;
use crate::csg::{Booleans, CsgCaster, FacesOnScreen, Hit, Interval, IntervalLanes, LeafSpans, RowFaces, SpanScratch};

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
        faces: &[Option<FacesOnScreen>],
        y: usize,
    ) {
        let cached = self.cached.get_mut();
        for i in occupants {
            cached[i].iter_mut().for_each(|c| c.0 = usize::MAX);
            let screen = faces[i].as_ref().map(|s| (s, y));
            caster.row_faces(i, &lines[i], screen, &mut self.faces[i]);
        }
    }

    /// Primitive `i`'s lanes for `block` of its row line `unit` into
    /// `lanes`, not kept (the union's z-buffer reads each block once).
    #[inline(always)]
    pub(super) fn solve(&self, source: Source, i: usize, unit: &RowLine, block: usize, lanes: &mut IntervalLanes) {
        Self::fill(source, i, unit, block, &self.faces[i], lanes);
    }

    /// Primitive `i`'s interval at pixel `x` of its row line `unit`.
    #[inline(always)]
    pub(super) fn span(&self, source: Source, i: usize, unit: &RowLine, x: usize) -> Option<Interval> {
        let mut cached = self.cached.borrow_mut();
        let slot = &mut cached[i][x / 8 % 2];
        self.fill_if_stale(slot, source, i, unit, x / 8);
        slot.1.get(x % 8)
    }

    /// Primitive `i`'s cache entry `cached` made to hold `block`.
    #[inline(always)]
    fn fill_if_stale(
        &self,
        (cached, lanes): &mut (usize, IntervalLanes),
        source: Source,
        i: usize,
        unit: &RowLine,
        block: usize,
    ) {
        if *cached != block {
            *cached = block;
            Self::fill(source, i, unit, block, &self.faces[i], lanes);
        }
    }

    /// Primitive `i`'s lanes for `block`, into `lanes`: once per eight
    /// pixels, not inlined. A closed mesh's layer comes from the frame's
    /// rasterized layers where it has them.
    #[inline(never)]
    fn fill(source: Source, i: usize, unit: &RowLine, block: usize, faces: &RowFaces, lanes: &mut IntervalLanes) {
        let Source { caster, layers, y } = source;
        if !layers.fill(i, y, block, lanes) {
            caster.spans_on_eight(i, unit, block, faces, lanes);
        }
    }
}

/// Where a scanline's lanes come from: the caster, or for a closed mesh's
/// layers the frame's rasterized layers, on row `y`.
#[derive(Clone, Copy)]
pub(super) struct Source<'a> {
    pub(super) caster: &'a CsgCaster,
    pub(super) layers: &'a MeshLayers,
    pub(super) y: usize,
}

/// A scanline's intervals as the booleans read them: each occupant's
/// eight-pixel blocks ([`BlockSpans`]) along its row line.
pub(super) struct RowSpans<'a> {
    pub(super) blocks: &'a BlockSpans,
    pub(super) caster: &'a CsgCaster,
    pub(super) lines: &'a [RowLine],
    /// The frame's rasterized mesh layers, and the row.
    pub(super) layers: &'a MeshLayers,
    pub(super) y: usize,
}

impl RowSpans<'_> {
    /// Primitive `i`'s interval at pixel `x`.
    #[inline(always)]
    pub(super) fn at(&self, i: usize, x: usize) -> Option<Interval> {
        self.blocks.span(self.source(), i, &self.lines[i], x)
    }

    /// Where this row's lanes come from.
    #[inline(always)]
    pub(super) fn source(&self) -> Source<'_> {
        Source { caster: self.caster, layers: self.layers, y: self.y }
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
    /// occupants `ids`, over the pixels after it up to `run.upto` (in its
    /// block): `run.row`'s pixels written as far as the answer holds, the last
    /// returned. (All occupants: the answer is the whole tree's, however found.)
    pub(super) fn spread(
        &self,
        order: &mut BlockOrder,
        ids: &[u32],
        x: usize,
        first: Option<Hit>,
        near: f32,
        run: RowRun,
    ) -> usize {
        let RowRun { row, upto } = run;
        let mut cached = self.blocks.cached.borrow_mut();
        for &i in ids {
            let i = i as usize;
            self.blocks.fill_if_stale(&mut cached[i][x / 8 % 2], self.source(), i, &self.lines[i], x / 8);
        }
        let (x0, slot) = (x / 8 * 8, x / 8 % 2);
        let end = (x0 + 8).min(row.len());
        let lanes =
            BlockLanes { reference: |i: usize| (&cached[i][slot].1, x - x0), target: |i: usize| &cached[i][slot].1 };
        let run = BlockRun { out: &mut row[x0..end], from: x - x0 + 1, upto: upto - x0 };
        x0 + order.spread(ids, &lanes, near, first, run).unwrap_or(x - x0)
    }

    /// The answer of pixel `x − 1` (the last of the block before, found with
    /// the same occupants `ids`) carried on into `x`'s block, up to
    /// `run.upto`, as [`RowSpans::spread`] hands an answer on inside a block:
    /// `run.row`'s pixels written from `x` as far as it holds, the last
    /// returned (`None` when it does not hold at `x`, or the lanes of `x − 1`
    /// are gone).
    pub(super) fn carry(&self, order: &mut BlockOrder, ids: &[u32], x: usize, near: f32, run: RowRun) -> Option<usize> {
        let RowRun { row, upto } = run;
        let (block, before) = (x / 8, x / 8 - 1);
        let mut cached = self.blocks.cached.borrow_mut();
        if ids.iter().any(|&i| cached[i as usize][before % 2].0 != before) {
            return None;
        }
        for &i in ids {
            let i = i as usize;
            self.blocks.fill_if_stale(&mut cached[i][block % 2], self.source(), i, &self.lines[i], block);
        }
        let end = (x + 8).min(row.len());
        let lanes = BlockLanes {
            reference: |i: usize| (&cached[i][before % 2].1, 7),
            target: |i: usize| &cached[i][block % 2].1,
        };
        let first = row[x - 1];
        let run = BlockRun { out: &mut row[x..end], from: 0, upto: upto - x };
        order.spread(ids, &lanes, near, first, run).map(|last| x + last)
    }
}

/// The pixels of a row an answer may be handed on to: `row`, up to `upto`.
pub(super) struct RowRun<'r> {
    pub(super) row: &'r mut [Option<Hit>],
    pub(super) upto: usize,
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
