//! A union of primitives' scanline as a z-buffer, a block of eight pixels at
//! a time (seed 003 §5.2's nearest surface over the segments, where each
//! segment is one primitive: the paper's Table 1 of random spheres).
//!
//! Every pixel of a union shows the nearest entry of its occupants beyond
//! the near plane (ties to the primitive earlier in the file:
//! [`Hit::nearer_than`], what the booleans give a union). The row is walked
//! block by block; each block keeps its eight pixels' nearest entry so far in
//! SIMD lanes and meets the occupants that cover it nearest first (by each
//! one's least depth anywhere), so that
//! - an occupant whose least depth lies behind every pixel of the block (by
//!   [`DEPTH_MARGIN`] over the lanes' rounding) ends the block: every later
//!   one lies further still;
//! - an occupant that cannot enter the block's rays nearer than what each of
//!   its pixels shows ([`BoxFloor`]: the box around it) is left unsolved;
//! - the others' intervals are found in lanes
//!   ([`CsgCaster::spans_on_eight`]) and merged lane by lane;
//! - a block that one occupant alone covers takes its entries as they are.
//!
//! Where a ray starts inside an occupant the union's first surface may be an
//! exit, which the booleans find: the walk gives the row up to them.

use glam::{BVec3A, Vec3, Vec3A};
use wide::{f32x8, i32x8, u32x8};

use crate::camera::RowLine;
#[cfg(doc)]
use crate::csg::CsgCaster;
use crate::csg::{Hit, IntervalLanes};
use crate::visibility::solids::spans::RowSpans;

/// Relative depth by which a primitive must lie behind a pixel's surface
/// for the z-buffer to leave it unsolved there (far above the rounding of a
/// computed interval).
const DEPTH_MARGIN: f32 = 1e-4;

/// Words of 64 bits, one bit per occupant, a row may need: beyond 256
/// occupants on one row, the booleans find it.
const MOST_WORDS: usize = 4;

/// An occupant of a union's scanline with its least depth: primitive, left
/// end, right end (columns), least depth along the view axis.
pub(super) type DepthEnds = (usize, i64, i64, f32);

/// A depth beyond which everything lies, as a bound a pixel's surface must
/// lie short of to hide it: `depth` less the margin, or none (`f32::MIN`)
/// where the near plane at `near` may cut it.
fn hidden_short_of(depth: f32, near: f32) -> f32 {
    if depth > near * (1.0 + DEPTH_MARGIN) {
        depth * (1.0 - DEPTH_MARGIN)
    } else {
        f32::MIN
    }
}

/// One occupant of the row as the blocks meet it.
#[derive(Debug, Clone, Copy)]
struct Occupant {
    primitive: usize,
    /// Its columns, clipped to the row.
    columns: (usize, usize),
    /// [`hidden_short_of`] its least depth anywhere.
    hidden_short_of: f32,
    /// The least depth at which a block's rays may meet it.
    floor: BoxFloor,
}

impl Occupant {
    /// Its first and last block.
    fn blocks(&self) -> (usize, usize) {
        (self.columns.0 / 8, self.columns.1 / 8)
    }

    /// The pixels (bits) it covers of the block from column `x0`, which it
    /// covers some of.
    #[inline(always)]
    fn pixels(&self, x0: usize) -> u8 {
        let (a, b) = (self.columns.0.saturating_sub(x0), self.columns.1 - x0);
        (0xff << a.min(7)) & (0xff >> (7 - b.min(7)))
    }
}

/// A worker's buffers for the z-buffer's rows, kept from row to row.
#[derive(Debug, Default)]
pub(super) struct UnionRow {
    /// The row's occupants, nearest first.
    occupants: Vec<Occupant>,
    /// Per block from the row's first, a bit per occupant (by its place in
    /// `occupants`) whose first block it is.
    first: Vec<u64>,
    /// The same for those whose last block it is.
    last: Vec<u64>,
}

impl RowSpans<'_> {
    /// The union's row: each pixel's nearest entry beyond `near` over the
    /// occupants `ends` (nearest first), into `row` (all `None` before).
    /// `false`, the row half written, where a ray starts inside an occupant
    /// (or more than 256 occupants share the row). Kept out of line, so that
    /// the booleans' row walk beside it compiles as it did without it.
    #[inline(never)]
    pub(super) fn nearest_entries(
        &self,
        ends: &[DepthEnds],
        near: f32,
        row: &mut [Option<Hit>],
        buffers: &mut UnionRow,
    ) -> bool {
        let last = row.len() as i64 - 1;
        buffers.occupants.clear();
        buffers.occupants.extend(ends.iter().filter_map(|&(i, a, b, nearest)| {
            let (a, b) = (a.max(0), b.min(last));
            (a <= b).then(|| Occupant {
                primitive: i,
                columns: (a as usize, b as usize),
                hidden_short_of: hidden_short_of(nearest, near),
                floor: BoxFloor::new(&self.lines[i], self.caster.unit_box(i)),
            })
        }));
        match buffers.occupants.len().div_ceil(64) {
            0 => true,
            1 => self.blocks_nearest_first::<1>(buffers, near, row),
            2 => self.blocks_nearest_first::<2>(buffers, near, row),
            3..=MOST_WORDS => self.blocks_nearest_first::<MOST_WORDS>(buffers, near, row),
            _ => false,
        }
    }

    /// The row's blocks in turn, each meeting the occupants that cover it
    /// (`W` words of bits, kept up to date by each occupant's first and last
    /// block).
    #[inline(always)]
    fn blocks_nearest_first<const W: usize>(
        &self,
        UnionRow { occupants, first, last }: &mut UnionRow,
        near: f32,
        row: &mut [Option<Hit>],
    ) -> bool {
        let start = occupants.iter().map(|o| o.blocks().0).min().unwrap_or(0);
        let end = occupants.iter().map(|o| o.blocks().1).max().unwrap_or(0);
        for bits in [&mut *first, &mut *last] {
            bits.clear();
            bits.resize((end + 1 - start) * W, 0);
        }
        let (first, last) = (first.as_chunks_mut::<W>().0, last.as_chunks_mut::<W>().0);
        for (k, o) in occupants.iter().enumerate() {
            first[o.blocks().0 - start][k / 64] |= 1 << (k % 64);
            last[o.blocks().1 - start][k / 64] |= 1 << (k % 64);
        }
        let (width, mut live, mut lanes) = (row.len(), [0u64; W], IntervalLanes::default());
        for block in start..=end {
            live.iter_mut().zip(first[block - start]).for_each(|(l, f)| *l |= f);
            let x0 = block * 8;
            let out = &mut row[x0..(x0 + 8).min(width)];
            let held = match live.iter().map(|l| l.count_ones()).sum::<u32>() {
                0 => true,
                // One occupant: its entries as they are.
                1 => {
                    let (w, bits) = live.iter().enumerate().find(|(_, &l)| l != 0).unwrap_or((0, &0));
                    let o = &occupants[w * 64 + bits.trailing_zeros() as usize];
                    self.blocks.solve(self.source(), o.primitive, &self.lines[o.primitive], block, &mut lanes);
                    entries_ahead(&lanes, lanes.met() & o.pixels(x0), near, out)
                }
                _ => self.nearest_in_block(occupants, &live, (block, near), &mut lanes).map(|n| n.write(out)).is_some(),
            };
            if !held {
                return false;
            }
            live.iter_mut().zip(last[block - start]).for_each(|(l, f)| *l &= !f);
        }
        true
    }

    /// The nearest entries beyond `near` at `block` of the occupants `live`
    /// (bits of `occupants`, nearest first), each solved into `lanes` unless
    /// the block's surfaces so far hide it: `None` where a ray starts inside
    /// one.
    #[inline(always)]
    fn nearest_in_block<const W: usize>(
        &self,
        occupants: &[Occupant],
        live: &[u64; W],
        (block, near): (usize, f32),
        lanes: &mut IntervalLanes,
    ) -> Option<Nearest> {
        let mut nearest = Nearest::default();
        for (w, &bits) in live.iter().enumerate() {
            let mut bits = bits;
            while bits != 0 {
                let o = &occupants[w * 64 + bits.trailing_zeros() as usize];
                bits &= bits - 1;
                let pixels = o.pixels(block * 8);
                if nearest.shown() & pixels == pixels {
                    let hidden = nearest.t.simd_lt(f32x8::splat(o.hidden_short_of)).to_bitmask();
                    // Every later occupant lies further still.
                    if hidden == 0xff {
                        break;
                    }
                    // Each pixel it covers hidden by its least depth, or by
                    // the least at which the block's rays may meet it.
                    let hidden = hidden as u8 & pixels;
                    if hidden == pixels {
                        continue;
                    }
                    let floor = hidden_short_of(o.floor.at(block * 8), near);
                    let under = nearest.t.simd_lt(f32x8::splat(floor)).to_bitmask() as u8;
                    if (hidden | under) & pixels == pixels {
                        continue;
                    }
                }
                let i = o.primitive;
                self.blocks.solve(self.source(), i, &self.lines[i], block, lanes);
                let met = lane_mask(lanes.met() & pixels);
                let (enter, exit) = (f32x8::new(*lanes.ends(0)), f32x8::new(*lanes.ends(1)));
                let ahead = enter.simd_gt(f32x8::splat(near));
                if (met & !ahead & exit.simd_gt(f32x8::splat(near))).any() {
                    return None;
                }
                nearest.take(met & ahead, (enter, f32x8::new(lanes.faces(0).map(f32::from_bits))), i);
            }
        }
        Some(nearest)
    }
}

/// The entries of `lanes` beyond `near` at the pixels `met` (bits) into
/// `out`; `false` where a ray starts inside.
#[inline(always)]
fn entries_ahead(lanes: &IntervalLanes, met: u8, near: f32, out: &mut [Option<Hit>]) -> bool {
    for (j, o) in out.iter_mut().enumerate().filter(|(j, _)| met >> j & 1 != 0) {
        let (enter, exit) = (lanes.end_at(0, j), lanes.end_at(1, j));
        if enter.t > near {
            *o = Some(enter);
        } else if exit.t > near {
            return false;
        }
    }
    true
}

/// The lanes of the bits of `bits` (bit `j`, lane `j`) as a mask.
#[inline(always)]
fn lane_mask(bits: u8) -> f32x8 {
    let bit = (i32x8::splat(i32::from(bits)) >> u32x8::new([0, 1, 2, 3, 4, 5, 6, 7])) & i32x8::ONE;
    bit.round_float().simd_eq(f32x8::ONE)
}

/// A block's nearest entries so far, in lanes: `t` (infinite where none),
/// face (its bits) and primitive (as a float).
#[derive(Debug, Clone, Copy)]
struct Nearest {
    t: f32x8,
    face: f32x8,
    primitive: f32x8,
}

impl Default for Nearest {
    fn default() -> Self {
        Nearest { t: f32x8::splat(f32::INFINITY), face: f32x8::ZERO, primitive: f32x8::splat(f32::INFINITY) }
    }
}

impl Nearest {
    /// The lanes (bits) that hold an entry.
    #[inline(always)]
    fn shown(&self) -> u8 {
        self.t.simd_lt(f32x8::splat(f32::INFINITY)).to_bitmask() as u8
    }

    /// Primitive `i`'s entries `(t, face)` in the lanes of `candidates`, where
    /// they come before what the lanes hold ([`Hit::nearer_than`]).
    #[inline(always)]
    fn take(&mut self, candidates: f32x8, (t, face): (f32x8, f32x8), i: usize) {
        let p = f32x8::splat(i as f32);
        let nearer = t.simd_lt(self.t) | (t.simd_eq(self.t) & p.simd_lt(self.primitive));
        let take = candidates & nearer;
        self.t = take.select(t, self.t);
        self.face = take.select(face, self.face);
        self.primitive = take.select(p, self.primitive);
    }

    /// The lanes that hold an entry, as hits into `out` (the block's pixels).
    #[inline(always)]
    fn write(&self, out: &mut [Option<Hit>]) {
        let shown = self.shown();
        if shown == 0 {
            return;
        }
        // Small whole numbers, converted in lanes (a saturating `as` per
        // pixel costs more than the merge).
        let (t, face, primitive) = (self.t.to_array(), self.face.to_array(), self.primitive.trunc_int().to_array());
        let hit = |j: usize| Some(Hit::new(t[j], primitive[j] as usize, face[j].to_bits()));
        if shown == 0xff && out.len() == 8 {
            out.iter_mut().enumerate().for_each(|(j, o)| *o = hit(j));
        } else {
            out.iter_mut().enumerate().filter(|(j, _)| shown >> j & 1 != 0).for_each(|(j, o)| *o = hit(j));
        }
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
