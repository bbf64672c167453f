//! Coherence along a scanline (seed 003 §5.2.2): a pixel whose occupants are
//! those of the pixel before it, their interval ends in the same depth order,
//! has the same visible surface — the same end of the same primitive — so the
//! walk reads that end's depth at the new pixel instead of combining the
//! intervals again.
//!
//! "The same order" is made exact. The booleans ([`crate::csg`])
//! decide only by comparing `t` values: interval ends with each other, with
//! the near plane, and — in a difference — with a cutter's ends moved by
//! [`crate::csg::TIE`] ([`below`], [`above`]). At a pixel the
//! booleans evaluate, every value they could compare is listed and sorted
//! ([`PixelCoherence::learn`]); at the next pixel the same list, read in the
//! same order, must still rise strictly (a tie or a NaN breaks the run), and
//! the same occupants must be missed by the ray
//! ([`PixelCoherence::reused`]). Then every comparison the booleans make
//! comes out as it did, they take the same path, and their answer is the same
//! end of the same primitive (its hole-wall bit too): what is reused is what a
//! full evaluation gives, to the bit. Entering or leaving occupants end the run
//! ([`PixelCoherence::forget`]).
//!
//! A run costs one pass over the list per pixel, however deep the tree; a
//! broken run costs a sort on top of the booleans. Measured on the corpus
//! (`docs/benchmarks.md`), the booleans of the few primitives at a pixel are
//! cheap beside that pass, and the order of many primitives' ends breaks too
//! often (any two ends swapping, however far behind the surface): the walk
//! uses it only when asked ([`super::super::CsgMethod::SegmentsCoherent`]).

use crate::csg::occupancy::PlacedSet;
#[cfg(doc)]
use crate::csg::{above, below};
use crate::csg::{CsgTree, Hit, Interval, TIE};

/// How a value is made from an end's `t`: `t + k·max(|t|, 1)`, where `k` is
/// 0 (the end itself), `−TIE` ([`below`]) or `+TIE` ([`above`]) — the same
/// sums to the bit. A cutter's span may start or stop at either end of a
/// primitive under it, so such a primitive's ends are listed all three ways.
const PLAIN: [f32; 1] = [0.0];

/// The moves of a primitive under a difference's cutter ([`PLAIN`]).
const WIDENED: [f32; 3] = [0.0, -TIE, TIE];

/// One compared value: end `end` (0 entry, 1 exit) of the occupant at
/// `place` (the near plane has the place after the last occupant), moved by
/// `k` ([`PLAIN`]).
#[derive(Debug, Clone, Copy)]
struct Key {
    place: u32,
    end: u32,
    k: f32,
}

impl Key {
    /// The value at a pixel whose ends are `ends`.
    #[inline(always)]
    fn value(self, ends: &[[f32; 2]]) -> f32 {
        let t = ends[self.place as usize][self.end as usize];
        t + self.k * t.abs().max(1.0)
    }
}

/// The last evaluated pixel's answer, by role.
#[derive(Debug, Clone, Copy)]
enum Answer {
    /// The ray missed the solid.
    Miss,
    /// One end of one occupant's interval, as a hole's wall or not.
    End { place: u32, exit: bool, cut: bool },
}

/// A scanline's reusable answer and the depth order it holds for (one per
/// worker, kept between rows).
#[derive(Debug, Clone, Default)]
pub struct PixelCoherence {
    /// The occupants' intervals at the current pixel, by place.
    spans: Vec<Option<Interval>>,
    /// Their ends' `t` (NaN where the ray misses), then the near plane's.
    ends: Vec<[f32; 2]>,
    /// How many of them the ray met where the answer was found.
    met: usize,
    /// Every value the booleans could compare there, nearest first.
    order: Vec<Key>,
    /// The answer found there (`None`: nothing to reuse).
    answer: Option<Answer>,
    /// Room to sort in.
    sorting: Vec<(f32, Key)>,
}

impl PixelCoherence {
    /// An occupant entered or left: the next pixel is evaluated in full.
    pub fn forget(&mut self) {
        self.answer = None;
    }

    /// Reads the intervals of the pixel's `occupants` (the booleans read
    /// them back with [`PixelCoherence::span`]); the near plane lies at `near`.
    pub fn look(&mut self, occupants: &PlacedSet, near: f32, span: impl Fn(usize) -> Option<Interval>) {
        self.spans.clear();
        self.ends.clear();
        for &i in occupants.ids() {
            let s = span(i as usize);
            self.spans.push(s);
            self.ends.push(s.map_or([f32::NAN; 2], |s| [s.enter.t, s.exit.t]));
        }
        self.ends.push([near; 2]);
    }

    /// Primitive `i`'s interval at the pixel looked at (`None` when it is not
    /// an occupant).
    #[inline]
    #[must_use]
    pub fn span(&self, occupants: &PlacedSet, i: usize) -> Option<Interval> {
        self.spans[occupants.place(i)?]
    }

    /// The answer of the last pixel evaluated, when it holds at the pixel
    /// looked at: `Some(None)` a miss again, `Some(Some(hit))` the same end.
    #[must_use]
    pub fn reused(&self) -> Option<Option<Hit>> {
        let answer = self.answer?;
        if self.spans.iter().flatten().count() != self.met {
            return None;
        }
        let mut last = f32::NEG_INFINITY;
        for &key in &self.order {
            let v = key.value(&self.ends);
            // A NaN (a missed occupant) is not greater either.
            if v.partial_cmp(&last) != Some(std::cmp::Ordering::Greater) {
                return None;
            }
            last = v;
        }
        Some(match answer {
            Answer::Miss => None,
            Answer::End { place, exit, cut } => {
                let s = self.spans[place as usize]?;
                Some(if exit { s.exit } else { s.enter }.with_cut(cut))
            }
        })
    }

    /// Keeps `answer`, found by the booleans from the intervals looked at,
    /// with the order of every value they could compare there; `widened`
    /// says, per primitive, whether a difference cuts with it. Ties (or NaNs)
    /// among the values leave nothing to reuse.
    pub fn learn(&mut self, occupants: &PlacedSet, widened: &[bool], answer: Option<Hit>) {
        self.answer = None;
        self.sorting.clear();
        for (place, &i) in occupants.ids().iter().enumerate() {
            if self.spans[place].is_none() {
                continue;
            }
            let moves: &[f32] = if widened[i as usize] { &WIDENED } else { &PLAIN };
            for &k in moves {
                for end in [0, 1] {
                    let key = Key { place: place as u32, end, k };
                    self.sorting.push((key.value(&self.ends), key));
                }
            }
        }
        let near = Key { place: occupants.ids().len() as u32, end: 0, k: 0.0 };
        self.sorting.push((near.value(&self.ends), near));
        self.sorting.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        if self.sorting.windows(2).any(|w| w[0].0.partial_cmp(&w[1].0) != Some(std::cmp::Ordering::Less)) {
            return;
        }
        self.order.clear();
        self.order.extend(self.sorting.iter().map(|&(_, key)| key));
        self.met = self.spans.iter().flatten().count();
        self.answer = match answer {
            None => Some(Answer::Miss),
            Some(hit) => self.role(occupants, hit),
        };
    }

    /// Which end of which occupant `hit` is.
    fn role(&self, occupants: &PlacedSet, hit: Hit) -> Option<Answer> {
        let place = occupants.place(hit.primitive as usize)?;
        let s = self.spans[place]?;
        let exit = if hit.t == s.enter.t {
            false
        } else if hit.t == s.exit.t {
            true
        } else {
            return None;
        };
        Some(Answer::End { place: place as u32, exit, cut: hit.cut() })
    }
}

/// Per primitive of a solid of `primitives`, whether it lies under a
/// difference's cutter in `tree` (its ends are then compared widened too).
#[must_use]
pub fn cut_with(tree: &CsgTree, primitives: usize) -> Vec<bool> {
    fn mark(tree: &CsgTree, cutter: bool, out: &mut [bool]) {
        match tree {
            CsgTree::Leaf(i) => out[*i] |= cutter,
            CsgTree::Union(kids) | CsgTree::Intersection(kids) => kids.iter().for_each(|k| mark(k, cutter, out)),
            CsgTree::Difference(a, cutters) => {
                mark(a, cutter, out);
                cutters.iter().for_each(|k| mark(k, true, out));
            }
        }
    }
    let mut out = vec![false; primitives];
    mark(tree, false, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const fn span(enter: f32, exit: f32, primitive: usize) -> Interval {
        Interval { enter: Hit::new(enter, primitive, 0), exit: Hit::new(exit, primitive, 1) }
    }

    /// Occupants 0 and 1, learnt at a pixel where they span `first` (the
    /// answer: 0's entry), then looked at the next pixel, where they span
    /// `next`.
    fn after(first: [Option<Interval>; 2], next: [Option<Interval>; 2]) -> Option<Option<Hit>> {
        let mut occupants = PlacedSet::new(2);
        occupants.insert(0);
        occupants.insert(1);
        let mut c = PixelCoherence::default();
        c.look(&occupants, 0.5, |i| first[i]);
        c.learn(&occupants, &[false, false], first[0].map(|s| s.enter));
        c.look(&occupants, 0.5, |i| next[i]);
        c.reused()
    }

    const FIRST: [Option<Interval>; 2] = [Some(span(1.0, 3.0, 0)), Some(span(2.0, 4.0, 1))];

    #[test]
    fn the_same_order_keeps_the_answer_and_reads_its_new_depth() {
        let hit = after(FIRST, [Some(span(1.5, 3.5, 0)), Some(span(2.5, 4.5, 1))]);
        assert_eq!(hit.flatten().map(|h| (h.t, h.primitive)), Some((1.5, 0)));
    }

    #[test]
    fn a_swap_a_tie_or_a_miss_breaks_the_run() {
        // 1's entry passes 0's exit; 1's entry meets 0's exit; 1 is missed;
        // 0's entry meets the near plane.
        for next in [
            [Some(span(1.0, 3.0, 0)), Some(span(3.5, 4.0, 1))],
            [Some(span(1.0, 3.0, 0)), Some(span(3.0, 4.0, 1))],
            [Some(span(1.0, 3.0, 0)), None],
            [Some(span(0.5, 3.0, 0)), Some(span(2.0, 4.0, 1))],
        ] {
            assert_eq!(after(FIRST, next), None, "{next:?}");
        }
        // An occupant missed where the answer was found is met.
        assert_eq!(after([FIRST[0], None], FIRST), None);
    }
}
