//! A scanline's intervals as seed 003's walk reads them (§5.2's per-pixel
//! interval of each occupant): each occupant's eight-pixel blocks of lanes,
//! found once per block ([`BlockSpans`]), and the readers the booleans, the
//! block spreading ([`super::block`]) and the union's z-buffer take them
//! through ([`RowSpans`]), with occupants beyond a [`Horizon`] left out;
//! and the depth below which a block's rays cannot meet a primitive's box
//! ([`BoxFloor`]), by which the z-buffer leaves blocks unsolved.

use std::cell::{Cell, RefCell};

use glam::{BVec3A, Vec3, Vec3A};

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
            // First by the primitive's least depth anywhere, then, where
            // every pixel holds a surface, by the least depth at which the
            // block's rays may enter the box around it ([`BoxFloor`]).
            let behind =
                |floor: f32| if floor > near * (1.0 + DEPTH_MARGIN) { floor * (1.0 - DEPTH_MARGIN) } else { f32::MIN };
            let primitive = (self.caster, i, &self.lines[i]);
            let (everywhere, floor) = (behind(nearest), BoxFloor::new(&self.lines[i], self.caster.unit_box(i)));
            for block in a / 8..=b / 8 {
                // Half-open: walking an inclusive range cost ex022 4%.
                let pixels = a.max(block * 8)..b.min(block * 8 + 7) + 1;
                let far = row[pixels.clone()]
                    .iter()
                    .try_fold(f32::MIN, |far, h| h.map(|h| far.max(h.t)))
                    .unwrap_or(f32::INFINITY);
                if far < everywhere || (far < f32::INFINITY && far < behind(floor.at(block * 8))) {
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

/// A lower bound of a primitive's entries along the rays of an eight-pixel
/// block (beyond the paper: the union's z-buffer leaves a block unsolved for a
/// primitive that cannot come nearer than what it shows). Each pixel's ray
/// `o + t·d(x)` enters the box `[lo, hi]` around the unit shape no sooner
/// than it crosses the near plane of each slab whose outside `o` lies on: at
/// `gap / speed(x)`, `gap` the distance from `o` to that plane and `speed(x)`
/// how fast `d(x)` approaches it. `speed` is linear in `x`, so over a block
/// its largest value is at one of the two end columns; where it is nowhere
/// positive, no ray of the block meets the box.
#[derive(Debug, Clone, Copy)]
struct BoxFloor {
    /// Per axis, the distance to the slab's near plane (zero for a slab `o`
    /// lies within: no bound).
    gap: Vec3A,
    /// Per axis, the approach at column 0 (one for a slab `o` lies within).
    speed: Vec3A,
    /// Per axis, the change of the approach per column.
    step: Vec3A,
}

impl BoxFloor {
    /// The bound for the rays of `line` and the box `(lo, hi)`: none (zero
    /// at every block) when the rays do not share an origin (an
    /// orthographic camera's row).
    fn new(line: &RowLine, (lo, hi): (Vec3A, Vec3A)) -> BoxFloor {
        let o = Vec3A::from(line.origin);
        let (above, below) = (o.cmpgt(hi), o.cmplt(lo));
        let outside = (above | below) & BVec3A::splat(line.origin_step == Vec3::ZERO);
        let toward = Vec3A::select(above, Vec3A::NEG_ONE, Vec3A::ONE);
        BoxFloor {
            gap: Vec3A::select(outside, Vec3A::select(above, o - hi, lo - o), Vec3A::ZERO),
            speed: Vec3A::select(outside, Vec3A::from(line.dir) * toward, Vec3A::ONE),
            step: Vec3A::select(outside, Vec3A::from(line.dir_step) * toward, Vec3A::ZERO),
        }
    }

    /// The least `t` at which a ray of columns `x0..x0 + 8` may enter the
    /// box (infinite if none does).
    #[inline(always)]
    fn at(&self, x0: usize) -> f32 {
        let x0 = x0 as f32;
        let speed = (self.speed + self.step * x0).max(self.speed + self.step * (x0 + 7.0));
        if speed.cmple(Vec3A::ZERO).any() {
            return f32::INFINITY;
        }
        (self.gap / speed).max_element()
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

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn vec3(range: f32) -> impl Strategy<Value = Vec3> {
        (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    /// Where the ray `o + t·d` enters the box `[lo, hi]`, by the slabs in
    /// f64 (`None` where it misses it or only behind `o`).
    fn entry(o: Vec3, d: Vec3, (lo, hi): (Vec3, Vec3)) -> Option<f64> {
        let (mut enter, mut exit) = (0.0f64, f64::INFINITY);
        for k in 0..3 {
            let (o, d, lo, hi) = (f64::from(o[k]), f64::from(d[k]), f64::from(lo[k]), f64::from(hi[k]));
            if d == 0.0 {
                if o < lo || o > hi {
                    return None;
                }
                continue;
            }
            let (a, b) = ((lo - o) / d, (hi - o) / d);
            enter = enter.max(a.min(b));
            exit = exit.min(a.max(b));
        }
        (enter <= exit).then_some(enter)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4096))]

        /// No ray of a block enters the box before the block's floor (by
        /// more than a float's rounding); an infinite floor, none at all.
        #[test]
        fn no_ray_of_a_block_enters_its_box_before_the_floor(
            corner in vec3(2.0),
            size in (0.1f32..3.0, 0.1f32..3.0, 0.1f32..3.0),
            origin in vec3(8.0),
            dir in vec3(1.0),
            dir_step in vec3(0.05),
            block in 0usize..40,
        ) {
            let bounds = (corner, corner + Vec3::new(size.0, size.1, size.2));
            let line = RowLine { origin, origin_step: Vec3::ZERO, dir, dir_step };
            let floor = BoxFloor::new(&line, (bounds.0.into(), bounds.1.into())).at(block * 8);
            for x in block * 8..block * 8 + 8 {
                let ray = line.at(x as f32);
                if let Some(t) = entry(ray.origin, ray.dir, bounds) {
                    prop_assert!(f64::from(floor) <= t * (1.0 + 1e-5) + 1e-9, "column {x}: enters at {t}, floor {floor}");
                }
            }
        }
    }

    #[test]
    fn a_block_looking_away_from_the_box_has_no_floor_and_inside_it_none_below_zero() {
        let unit = (Vec3A::ZERO, Vec3A::ONE);
        // From x = 5 looking further along +x: no ray meets the box.
        let away = RowLine {
            origin: Vec3::new(5.0, 0.5, 0.5),
            origin_step: Vec3::ZERO,
            dir: Vec3::X,
            dir_step: Vec3::Y * 0.01,
        };
        assert_eq!(BoxFloor::new(&away, unit).at(0), f32::INFINITY);
        // Looking back at it from x = 5: the near face at x = 1, four units on.
        let back = RowLine { dir: -Vec3::X, ..away };
        assert_eq!(BoxFloor::new(&back, unit).at(0), 4.0);
        // From inside, or along an orthographic row: no bound.
        let inside = RowLine { origin: Vec3::splat(0.5), ..back };
        assert_eq!(BoxFloor::new(&inside, unit).at(0), 0.0);
        let ortho = RowLine { origin_step: Vec3::Y * 0.01, ..back };
        assert_eq!(BoxFloor::new(&ortho, unit).at(0), 0.0);
    }
}
