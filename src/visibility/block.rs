//! Eight pixels' surfaces from one pixel's booleans: seed 003 §5.2.2's
//! coherence, taken a block at a time.
//!
//! The scanline walk reads every occupant's intervals eight pixels at a time
//! (one SIMD pass per occupant and block, `BlockSpans` in [`super::csg`]).
//! The booleans run at a block's first pixel, and [`BlockOrder::spread`]
//! hands their answer on along the run of pixels after it that no occupant
//! enters or leaves inside of (the whole block, or up to the next left or
//! right end), as far as it provably holds; the walk goes on pixel by pixel
//! from the first pixel where it does not.
//!
//! Why it holds. The booleans ([`crate::raytrace::csg`]) build the set of
//! ray parameters inside the solid out of the occupants' intervals, comparing
//! ends with each other, with the near plane and — a difference's cutter —
//! moved by [`TIE`]; their answer is the first end of that set beyond the
//! near plane, always one occupant's own entry or exit. Call it `E` at the
//! block's first pixel (`+∞` for a miss). Which part of the set lies before
//! and just past `E` depends only on the ends before `E` and their order. So
//! at a pixel `j` of the run where
//! - each occupant is met if it is met at the first pixel, missed if missed,
//! - the ends lying before `E` at the first pixel, the near plane and `E`
//!   itself keep the first pixel's order, each beyond the one before by more
//!   than any [`TIE`] move — or equal to it at both pixels, so that every
//!   comparison of the two, moved or not, comes out alike,
//! - and every other end stays beyond `E` in the same way,
//!
//! every comparison that shapes the set up to just past `E` comes out as at
//! the first pixel, and pixel `j`'s answer is the same end of the same
//! occupant read at `j` — its `t` and face there, its hole-wall bit — to the
//! bit what the booleans would give. Unlike the per-pixel reuse of
//! [`super::coherence`] (which keeps every end in order, so the booleans take
//! the same path), ends behind the surface may swap freely; where ends
//! before the surface come close without being equal (a cut decided within
//! the tie, a surface crossing another) or an occupant's edge passes, the
//! run stops. The checks run lane by lane (eight pixels per comparison), once
//! per block, where the booleans ran at each of its pixels.

use wide::f32x8;

use crate::raytrace::csg::{Hit, IntervalLanes, TIE};

/// The pixels (bits of lanes) where `b` and `a` compare as they do at pixel
/// `j0`: where `b` lies beyond `a` by more than the largest move a difference
/// makes ([`TIE`] relative to `t`, on both sides), if it does at `j0`; where
/// the two are the same value, if they are at `j0`; none otherwise. At those
/// pixels no comparison of theirs, moved or not, comes out differently from
/// pixel `j0`'s.
#[inline]
fn settled(a: &[f32; 8], b: &[f32; 8], j0: usize) -> u8 {
    let (a, b) = (f32x8::new(*a), f32x8::new(*b));
    let margin = f32x8::splat(4.0 * TIE) * a.abs().max(b.abs()).max(f32x8::splat(1.0));
    let apart = (b - a).simd_gt(margin).to_bitmask() as u8;
    if apart >> j0 & 1 != 0 {
        return apart;
    }
    let equal = a.simd_eq(b).to_bitmask() as u8;
    if equal >> j0 & 1 != 0 {
        equal
    } else {
        0
    }
}

/// Room to order a block's ends in, kept from block to block.
#[derive(Debug, Clone, Default)]
pub struct BlockOrder {
    before: Vec<[f32; 8]>,
}

impl BlockOrder {
    /// The surfaces at pixels `j0 + 1..=upto` of a block (`out`, its eight
    /// pixels, fewer at the row's end), where no occupant enters or leaves,
    /// given `first` — the booleans' answer at pixel `j0`, beyond the near
    /// plane at `near` — and the lanes of the occupants `ids` (`lanes`, by
    /// primitive): written into `out` up to the last pixel of the run from
    /// `j0` where it provably holds (see the module's doc), which is
    /// returned (`j0` when none).
    pub fn spread<'a>(
        &mut self,
        ids: &[u32],
        lanes: impl Fn(usize) -> &'a IntervalLanes,
        near: f32,
        (j0, first): (usize, Option<Hit>),
        (out, upto): (&mut [Option<Hit>], usize),
    ) -> usize {
        // The answer's lanes and end.
        let answer = match first {
            None => None,
            Some(h) => {
                let l = lanes(h.primitive as usize);
                let end = match (h.t == l.ends(0)[j0], h.t == l.ends(1)[j0]) {
                    (true, false) => 0,
                    (false, true) => 1,
                    _ => return j0,
                };
                Some((l, end))
            }
        };
        let e = answer.map(|(l, end)| (l.end_at(end, j0).primitive, end, l.ends(end)));
        let held = self.ordered(ids.iter().map(|&i| lanes(i as usize)), near, e, j0);
        // The run of pixels from `j0` where the answer holds.
        let last = (j0 + (held >> j0).trailing_ones() as usize).saturating_sub(1).clamp(j0, upto);
        let cut = first.is_some_and(|h| h.cut());
        for (px, j) in out[j0 + 1..=last].iter_mut().zip(j0 + 1..) {
            *px = answer.map(|(l, end)| l.end_at(end, j).with_cut(cut));
        }
        last
    }

    /// The pixels (bits) where the conditions of the module's doc hold among
    /// the lanes of `occupants` for the answer `answer` at pixel `j0` (its
    /// primitive, end and `t`s; `None` a miss): none once pixel `j0`'s own
    /// bit is lost.
    fn ordered<'a>(
        &mut self,
        occupants: impl Iterator<Item = &'a IntervalLanes>,
        near: f32,
        answer: Option<(u32, usize, &[f32; 8])>,
        j0: usize,
    ) -> u8 {
        self.before.clear();
        self.before.push([near; 8]);
        let mut held = u8::MAX;
        for l in occupants {
            // Missed where it is missed at `j0`, met where it is met there.
            let met = l.met();
            if met >> j0 & 1 == 0 {
                held &= !met;
                continue;
            }
            held &= met;
            let primitive = l.end_at(0, j0).primitive;
            for end in 0..2 {
                let t = l.ends(end);
                match answer {
                    Some((p, k, _)) if p == primitive && k == end => {}
                    // Beyond the answer: only to stay beyond it.
                    Some((_, _, e)) if t[j0] > e[j0] => held &= settled(e, t, j0),
                    _ => self.before.push(*t),
                }
            }
            if held >> j0 & 1 == 0 {
                return 0;
            }
        }
        self.before.sort_unstable_by(|a, b| a[j0].total_cmp(&b[j0]));
        self.before.extend(answer.map(|a| *a.2));
        for w in self.before.windows(2) {
            held &= settled(&w[0], &w[1], j0);
        }
        held
    }
}
