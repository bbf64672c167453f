//! Eight pixels' surfaces from one pixel's booleans: seed 003 §5.2.2's
//! coherence, taken a block at a time.
//!
//! The scanline walk reads every occupant's intervals eight pixels at a time
//! (one SIMD pass per occupant and block, `BlockSpans` in `spans.rs`).
//! The booleans run at a block's first pixel, and [`BlockOrder::spread`]
//! hands their answer on along the run of pixels after it that no occupant
//! enters or leaves inside of (the whole block, or up to the next left or
//! right end), as far as it provably holds; the walk goes on pixel by pixel
//! from the first pixel where it does not. The same from the first pixel
//! after an occupant entered or left inside a block, where that pays
//! (`EventSpreads` in `csg.rs`). Where the last pixel of the block
//! before was settled with the same occupants, its answer is handed on into
//! the block the same way (the walk keeps each occupant's lanes of two
//! blocks), and the booleans do not run at all.
//!
//! Why it holds. The booleans ([`crate::csg`]) build the set of
//! ray parameters inside the solid out of the occupants' intervals, comparing
//! ends with each other, with the near plane and — a difference's cutter —
//! moved by [`TIE`]; their answer is the first end of that set beyond the
//! near plane, always one occupant's own entry or exit. Call it `E` at the
//! reference pixel, where the booleans' answer is known (`+∞` for a miss).
//! Which part of the set lies before and just past `E` depends only on the
//! ends before `E` and their order. So at a pixel `j` of the run where
//! - each occupant is met if it is met at the reference pixel, missed if
//!   missed — or, where it is missed or lies wholly beyond `E` there (its
//!   entry beyond `E` by more than any [`TIE`] move), missed or wholly beyond
//!   `E` again: such an occupant changes no part of the set short of just
//!   past `E`, as an occupant beyond a [`super::horizon`] does not,
//! - the ends lying before `E` at the reference pixel, the near plane and `E`
//!   itself keep that pixel's order, each beyond the one before by more
//!   than any [`TIE`] move — or equal to it at both pixels, so that every
//!   comparison of the two, moved or not, comes out alike,
//! - and every other end stays beyond `E` in the same way,
//!
//! every comparison that shapes the set up to just past `E` comes out as at
//! the reference pixel, and pixel `j`'s answer is the same end of the same
//! occupant read at `j` — its `t` and face there, its hole-wall bit — to the
//! bit what the booleans would give. Unlike the per-pixel reuse of
//! [`super::coherence`] (which keeps every end in order, so the booleans take
//! the same path), ends behind the surface may swap freely; where ends
//! before the surface come close without being equal (a cut decided within
//! the tie, a surface crossing another) or an occupant's edge passes, the
//! run stops. The checks run lane by lane (eight pixels per comparison), once
//! per block, where the booleans ran at each of its pixels.

use wide::f32x8;

use crate::csg::{Hit, IntervalLanes, TIE};

/// The pixels (bits of lanes) where `b` and `a` compare as they do at the
/// reference pixel, where they are `rb` and `ra`: where `b` lies beyond `a`
/// by more than the largest move a difference makes ([`TIE`] relative to
/// `t`, on both sides), if it does there; where the two are the same value,
/// if they are there; none otherwise. At those pixels no comparison of
/// theirs, moved or not, comes out differently from the reference pixel's.
#[inline]
fn settled(a: &[f32; 8], ra: f32, b: &[f32; 8], rb: f32) -> u8 {
    if clear(ra, rb) {
        clear_lanes(a, b)
    } else if ra == rb {
        f32x8::new(*a).simd_eq(f32x8::new(*b)).to_bitmask() as u8
    } else {
        0
    }
}

/// How far apart (relative to the larger `t`, at least absolute) two ends
/// must lie to stand clear of each other: beyond the largest move a
/// difference makes ([`TIE`] on both sides), with room for rounding.
const CLEARANCE: f32 = 4.0 * TIE;

/// Whether `b` lies beyond `a` by more than [`CLEARANCE`].
#[inline]
fn clear(a: f32, b: f32) -> bool {
    b - a > CLEARANCE * a.abs().max(b.abs()).max(1.0)
}

/// The pixels (bits of lanes) where `b` lies beyond `a` as [`clear`] says.
#[inline]
fn clear_lanes(a: &[f32; 8], b: &[f32; 8]) -> u8 {
    let (a, b) = (f32x8::new(*a), f32x8::new(*b));
    let margin = f32x8::splat(CLEARANCE) * a.abs().max(b.abs()).max(f32x8::splat(1.0));
    (b - a).simd_gt(margin).to_bitmask() as u8
}

/// An end's lanes in the run's block, and its value at the reference pixel.
type End = ([f32; 8], f32);

/// The occupants' lanes a spread reads, by primitive: at the reference pixel
/// with that pixel's lane (`reference`), and over the block (`target`).
pub struct BlockLanes<R, T> {
    /// A primitive's lanes holding the reference pixel, and its lane there.
    pub reference: R,
    /// A primitive's lanes over the block.
    pub target: T,
}

/// The pixels of a block a spread may settle.
pub struct BlockRun<'o> {
    /// The block's pixels (eight, fewer at the row's end).
    pub out: &'o mut [Option<Hit>],
    /// The first pixel (index into `out`) to settle.
    pub from: usize,
    /// The last pixel (index into `out`) that may be settled.
    pub upto: usize,
}

/// Room to order a block's ends in, kept from block to block.
#[derive(Debug, Clone, Default)]
pub struct BlockOrder {
    before: Vec<End>,
}

impl BlockOrder {
    /// The surfaces at a block's pixels `run.from..=run.upto`, where no
    /// occupant enters or leaves, given `first` — the booleans' answer at a
    /// reference pixel (in the block, before `from`, or the last of the block
    /// before), beyond the near plane at `near` — and the occupants' lanes
    /// (`lanes`): written into `run.out` from `from` to the last pixel where it
    /// provably holds (see the module's doc), which is returned; `None` when
    /// it does not hold at `from`.
    pub fn spread<'a, R, T>(
        &mut self,
        ids: &[u32],
        lanes: &BlockLanes<R, T>,
        near: f32,
        first: Option<Hit>,
        run: BlockRun,
    ) -> Option<usize>
    where
        R: Fn(usize) -> (&'a IntervalLanes, usize),
        T: Fn(usize) -> &'a IntervalLanes,
    {
        let BlockLanes { reference, target } = lanes;
        let BlockRun { out, from, upto } = run;
        // The answer: its primitive, end, reference value and lanes.
        let answer = match first {
            None => None,
            Some(h) => {
                let (l, j) = reference(h.primitive as usize);
                let end = match (h.t == l.ends(0)[j], h.t == l.ends(1)[j]) {
                    (true, false) => 0,
                    (false, true) => 1,
                    _ => return None,
                };
                Some((h.primitive, end, l.ends(end)[j], target(h.primitive as usize)))
            }
        };
        let occupants = ids.iter().map(|&i| {
            let (r, j) = reference(i as usize);
            (r.met() >> j & 1 != 0, [r.ends(0)[j], r.ends(1)[j]], target(i as usize))
        });
        let held = self.ordered(occupants, near, answer.map(|(p, end, r, l)| (p, end, r, l.ends(end))), from);
        if held >> from & 1 == 0 {
            return None;
        }
        // The run of pixels from `from` where the answer holds.
        let last = (from + (held >> from).trailing_ones() as usize - 1).min(upto);
        let cut = first.is_some_and(|h| h.cut());
        for (px, j) in out[from..=last].iter_mut().zip(from..) {
            *px = answer.map(|(_, end, _, l)| l.end_at(end, j).with_cut(cut));
        }
        Some(last)
    }

    /// The pixels (bits) where the conditions of the module's doc hold among
    /// the `occupants` (each: whether met at the reference pixel, its ends
    /// there, its lanes) for the answer `answer` (its primitive, end,
    /// reference value and lanes; `None` a miss): none once pixel `from`'s
    /// own bit is lost.
    fn ordered<'a>(
        &mut self,
        occupants: impl Iterator<Item = (bool, [f32; 2], &'a IntervalLanes)>,
        near: f32,
        answer: Option<(u32, usize, f32, &[f32; 8])>,
        from: usize,
    ) -> u8 {
        self.before.clear();
        self.before.push(([near; 8], near));
        let mut held = u8::MAX;
        // The pixels where an occupant is missed or lies wholly beyond the
        // answer, and whether it did at the reference pixel.
        let aside = |was_met: bool, was: [f32; 2], l: &IntervalLanes| {
            let Some((_, _, re, e)) = answer else { return (!was_met, !l.met()) };
            (!was_met || clear(re, was[0]), !l.met() | clear_lanes(e, l.ends(0)))
        };
        for (was_met, was, l) in occupants {
            // Missed or wholly beyond the answer where it was, met with its
            // ends in order where it was not.
            let (was_aside, now_aside) = aside(was_met, was, l);
            if was_aside {
                held &= now_aside;
                continue;
            }
            held &= l.met();
            let primitive = l.end_at(0, 0).primitive;
            for (end, r) in was.into_iter().enumerate() {
                let t = l.ends(end);
                match answer {
                    Some((p, k, _, _)) if p == primitive && k == end => {}
                    // Beyond the answer: only to stay beyond it.
                    Some((_, _, re, e)) if r > re => held &= settled(e, re, t, r),
                    _ => self.before.push((*t, r)),
                }
            }
            if held >> from & 1 == 0 {
                return 0;
            }
        }
        self.before.sort_unstable_by(|a, b| a.1.total_cmp(&b.1));
        self.before.extend(answer.map(|(_, _, r, e)| (*e, r)));
        for w in self.before.windows(2) {
            held &= settled(&w[0].0, w[0].1, &w[1].0, w[1].1);
        }
        held
    }
}
