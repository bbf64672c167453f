//! Eight pixels' surfaces from one pixel's booleans: seed 003 §5.2.2's
//! coherence, taken a block at a time.
//!
//! The scanline walk reads every occupant's intervals eight pixels at a time
//! (one SIMD pass per occupant and block, `BlockSpans` in [`super::csg`]).
//! Where no occupant enters or leaves inside a block, the booleans run at its
//! first pixel only, and [`BlockOrder::spread`] hands their answer to the
//! other seven when it provably holds there.
//!
//! Why it holds. The booleans ([`crate::raytrace::csg`]) build the set of
//! ray parameters inside the solid out of the occupants' intervals, comparing
//! ends with each other, with the near plane and — a difference's cutter —
//! moved by [`TIE`]; their answer is the first end of that set beyond the
//! near plane, always one occupant's own entry or exit. Call it `E` at the
//! block's first pixel (`+∞` for a miss). Which part of the set lies before
//! and just past `E` depends only on the ends before `E` and their order. So
//! when, at every one of the eight pixels,
//! - each occupant is met, or each is missed (the same ones at all eight),
//! - the ends lying before `E` at the first pixel, the near plane and `E`
//!   itself keep the first pixel's order, each beyond the one before by more
//!   than any [`TIE`] move — or equal to it at all eight pixels, so that
//!   every comparison of the two, moved or not, comes out alike,
//! - and every other end stays beyond `E` in the same way,
//!
//! every comparison that shapes the set up to just past `E` comes out as at
//! the first pixel, and pixel `j`'s answer is the same end of the same
//! occupant read at `j` — its `t` and face there, its hole-wall bit — to the
//! bit what the booleans would give. Unlike the per-pixel reuse of
//! [`super::coherence`] (which keeps every end in order, so the booleans take
//! the same path), ends behind the surface may swap freely; a block where
//! ends before the surface come close without being equal (a cut decided
//! within the tie, a surface crossing another) is evaluated pixel by pixel.
//! The checks run lane by lane (eight pixels per comparison), once per
//! block, where the booleans ran at each of its pixels.

use crate::raytrace::csg::{Hit, IntervalLanes, TIE};

/// Whether at every pixel `b` lies beyond `a` by more than the largest move
/// a difference makes ([`TIE`] relative to `t`, on both sides) — or the two
/// are the same value at every pixel. Either way no comparison of theirs,
/// moved or not, comes out differently at one pixel than at another.
#[inline]
fn settled(a: &[f32; 8], b: &[f32; 8]) -> bool {
    let mut apart = true;
    for j in 0..8 {
        apart &= b[j] - a[j] > 4.0 * TIE * a[j].abs().max(b[j].abs()).max(1.0);
    }
    apart || a == b
}

/// Room to order a block's ends in, kept from block to block.
#[derive(Debug, Clone, Default)]
pub struct BlockOrder {
    before: Vec<[f32; 8]>,
}

impl BlockOrder {
    /// The surfaces at the eight pixels of a block where no occupant enters or
    /// leaves, given `first` — the booleans' answer at the block's first
    /// pixel, beyond the near plane at `near` — and the lanes of the
    /// occupants `ids` (`lanes`, by primitive): written into `out` (eight
    /// pixels), or `false` (`out` untouched) when the answer may not hold at
    /// every pixel (see the module's doc).
    pub fn spread<'a>(
        &mut self,
        ids: &[u32],
        lanes: impl Fn(usize) -> &'a IntervalLanes,
        near: f32,
        first: Option<Hit>,
        out: &mut [Option<Hit>],
    ) -> bool {
        // The answer's lanes and end.
        let answer = match first {
            None => None,
            Some(h) => {
                let l = lanes(h.primitive as usize);
                let end = match (h.t == l.ends(0)[0], h.t == l.ends(1)[0]) {
                    (true, false) => 0,
                    (false, true) => 1,
                    _ => return false,
                };
                Some((l, end))
            }
        };
        let e = answer.map(|(l, end)| (l.end_at(end, 0).primitive, end, l.ends(end)));
        if !self.ordered(ids.iter().map(|&i| lanes(i as usize)), near, e) {
            return false;
        }
        let cut = first.is_some_and(|h| h.cut());
        for (j, px) in out[..8].iter_mut().enumerate() {
            *px = answer.map(|(l, end)| l.end_at(end, j).with_cut(cut));
        }
        true
    }

    /// The conditions of the module's doc among the lanes of `occupants`
    /// for the answer `answer` (its primitive, end and `t`s; `None` a miss).
    fn ordered<'a>(
        &mut self,
        occupants: impl Iterator<Item = &'a IntervalLanes>,
        near: f32,
        answer: Option<(u32, usize, &[f32; 8])>,
    ) -> bool {
        self.before.clear();
        self.before.push([near; 8]);
        for l in occupants {
            match l.met() {
                0 => continue,
                u8::MAX => {}
                _ => return false, // met at some pixels only
            }
            let primitive = l.end_at(0, 0).primitive;
            for end in 0..2 {
                let t = l.ends(end);
                match answer {
                    Some((p, k, _)) if p == primitive && k == end => {}
                    // Beyond the answer: only to stay beyond it.
                    Some((_, _, e)) if t[0] > e[0] => {
                        if !settled(e, t) {
                            return false;
                        }
                    }
                    _ => self.before.push(*t),
                }
            }
        }
        self.before.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]));
        self.before.extend(answer.map(|a| *a.2));
        self.before.windows(2).all(|w| settled(&w[0], &w[1]))
    }
}
