//! The booleans of CSG along a ray (seed 003 §5.2's per-pixel interval
//! intersection, in tree form): each primitive's interval, combined up the
//! tree by union, intersection and difference into the spans the ray spends
//! inside the solid. Shared by the scanline walk and the ray caster.
//!
//! Coplanar faces (a cutter flush with the face it cuts, which real models are
//! full of) are decided one way: a difference removes its cutter's closed interval
//! widened by a hair ([`TIE`]), so a cut face exactly on a solid face removes it
//! instead of speckling.

use super::hit::{Hit, Interval};
use crate::csg::occupancy::Occupied;
use crate::csg::CsgTree;

/// Relative width (of `t`) within which a cutter's boundary counts as reaching a
/// solid's boundary.
pub const TIE: f32 = 1e-5;

/// A cutter's entry `t` as a difference compares it: moved [`TIE`] nearer
/// (relative to `t`, at least absolute).
#[inline]
#[must_use]
pub fn below(t: f32) -> f32 {
    t - TIE * t.abs().max(1.0)
}

/// A cutter's exit `t` as a difference compares it: moved [`TIE`] farther.
#[inline]
#[must_use]
pub fn above(t: f32) -> f32 {
    t + TIE * t.abs().max(1.0)
}

/// Each leaf's interval along the ray at hand, as the booleans read it: a
/// closure `Fn(usize) -> Option<Interval>`, or a reader the compiler is
/// made to inline (the scanline walk's eight-pixel blocks: a closure of it
/// was left as a call whose 28-byte answer came back through memory).
pub trait LeafSpans {
    /// Primitive `i`'s interval, if the ray meets it.
    fn span(&self, i: usize) -> Option<Interval>;

    /// A bound below which primitive `i`'s interval cannot start (where the
    /// ray enters its box): a union's first hit reads its operands nearest
    /// bound first and stops at one beyond the nearest hit found. Minus
    /// infinity (the default) when not known.
    #[inline(always)]
    fn entry_bound(&self, _i: usize) -> f32 {
        f32::NEG_INFINITY
    }
}

impl<F: Fn(usize) -> Option<Interval>> LeafSpans for F {
    #[inline(always)]
    fn span(&self, i: usize) -> Option<Interval> {
        self(i)
    }
}

/// Reusable buffers for combining spans along a tree, so a pixel allocates
/// nothing: each node leaves its spans on top of `stack`.
#[derive(Debug, Clone, Default)]
pub struct SpanScratch {
    pub(super) stack: Vec<Interval>,
    pub(super) out: Vec<Interval>,
    /// Sort keys of a union's many spans ([`union`]).
    pub(super) keys: Vec<u64>,
    /// The primitives whose boxes the ray crosses.
    pub(super) met: Vec<u32>,
    /// The same as flags (all false between rays).
    pub(super) crossed: Vec<bool>,
    /// The same as counts in the tree (empty between rays).
    pub(super) counts: Occupied,
    /// Every primitive's interval (the baseline ray caster's).
    pub(super) intervals: Vec<Option<Interval>>,
}

/// What a node of a tree of booleans does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Operation {
    /// A primitive (its index).
    Leaf(usize),
    /// Inside any operand.
    Union,
    /// Inside every operand.
    Intersection,
    /// Inside the first operand, outside the others.
    Difference,
}

/// A node of a tree of booleans, taken apart for the span combiner.
#[derive(Debug, Clone, Copy)]
pub struct Parts<B, I> {
    /// What the node does.
    pub operation: Operation,
    /// An intersection's or a difference's first operand (what the others
    /// narrow or cut); `None` for unions and leaves.
    pub first: Option<B>,
    /// The other operands the combiner reads: all of them, or (a view) those
    /// that can change the result.
    pub others: I,
}

/// A tree of booleans the span combiner ([`combine`]) walks: a [`CsgTree`], or
/// a view of one that leaves out what cannot matter at a pixel
/// (`csg/occupancy.rs`).
pub trait Booleans: Copy {
    /// The node's operation and operands.
    fn parts(self) -> Parts<Self, impl Iterator<Item = Self> + Clone>;

    /// The primitive, if the node is a leaf (what `parts` says, more cheaply).
    fn leaf(self) -> Option<usize>;
}

impl Booleans for &CsgTree {
    #[inline(always)]
    fn parts(self) -> Parts<Self, impl Iterator<Item = Self> + Clone> {
        let (operation, first, others): (_, _, &[CsgTree]) = match self {
            CsgTree::Leaf(i) => (Operation::Leaf(*i), None, &[]),
            CsgTree::Union(kids) => (Operation::Union, None, kids),
            CsgTree::Intersection(kids) => match kids.split_first() {
                Some((first, others)) => (Operation::Intersection, Some(first), others),
                None => (Operation::Intersection, None, &[]),
            },
            CsgTree::Difference(a, kids) => (Operation::Difference, Some(&**a), kids),
        };
        Parts { operation, first, others: others.iter() }
    }

    #[inline(always)]
    fn leaf(self) -> Option<usize> {
        match self {
            CsgTree::Leaf(i) => Some(*i),
            _ => None,
        }
    }
}

impl SpanScratch {
    /// The intervals on the stack: after one [`combine`] from empty, the tree's.
    #[must_use]
    pub fn spans(&self) -> &[Interval] {
        &self.stack
    }
}

/// The intervals of the subtree `tree`, given each leaf's interval (at most
/// one: a primitive is convex), left on top of `scratch.stack`; returns where
/// they start.
pub fn combine<B: Booleans>(tree: B, leaf: &impl LeafSpans, scratch: &mut SpanScratch) -> usize {
    let base = scratch.stack.len();
    let Parts { operation, first, others } = tree.parts();
    match operation {
        Operation::Leaf(i) => scratch.stack.extend(leaf.span(i)),
        Operation::Union => union_of(others, leaf, |_| true, scratch),
        op @ (Operation::Intersection | Operation::Difference) => {
            let Some(first) = first else { return base };
            if let Some(i) = first.leaf() {
                // One span or none: read directly (nothing for a window to drop).
                scratch.stack.extend(leaf.span(i));
            } else if op == Operation::Intersection {
                let Some(window) = Window::of_leaves(others.clone(), leaf) else { return base };
                combine_within(first, leaf, window, scratch);
            } else {
                combine(first, leaf, scratch);
            }
            for k in others {
                if scratch.stack.len() == base {
                    break; // nothing left to intersect with or cut from
                }
                if let Some(i) = k.leaf() {
                    // One interval or none: narrow or cut in place.
                    match (leaf.span(i), op) {
                        (Some(y), Operation::Difference) => cut(&mut scratch.stack, base, &y),
                        (Some(y), _) => clip(&mut scratch.stack, base, &y),
                        (None, Operation::Difference) => {}
                        (None, _) => scratch.stack.truncate(base),
                    }
                    continue;
                }
                let mid = combine(k, leaf, scratch);
                if op == Operation::Difference && scratch.stack.len() <= mid + 1 {
                    // No span (the ray misses this cutter) or one: cut in place.
                    if scratch.stack.len() == mid + 1 {
                        let y = scratch.stack.pop().expect("the cutter's span");
                        cut(&mut scratch.stack, base, &y);
                    }
                    continue;
                }
                let SpanScratch { stack, out, .. } = scratch;
                out.clear();
                let (a, b) = stack[base..].split_at(mid - base);
                if op == Operation::Difference {
                    difference(a, b, out);
                } else {
                    intersection(a, b, out);
                }
                stack.truncate(base);
                stack.extend_from_slice(out);
            }
        }
    }
    base
}

/// The union of the subtrees `operands` on top of `scratch.stack`, the spans
/// of leaves among them that `keep` refuses left out.
#[inline(always)]
fn union_of<B: Booleans>(
    operands: impl Iterator<Item = B>,
    leaf: &impl LeafSpans,
    keep: impl Fn(&Interval) -> bool,
    scratch: &mut SpanScratch,
) {
    let base = scratch.stack.len();
    let mut parts = 0;
    for k in operands {
        match k.leaf() {
            Some(i) => scratch.stack.extend(leaf.span(i).filter(&keep)),
            None => _ = combine(k, leaf, scratch),
        }
        parts += 1;
    }
    // One operand's spans are already sorted and disjoint.
    if parts > 1 {
        union(scratch, base);
    }
}

/// Where the spans of a subtree can still matter: an intersection's result
/// lies within every one of its leaf operands' intervals, so its first
/// operand's spans are needed only there.
#[derive(Debug, Clone, Copy)]
struct Window {
    lo: f32,
    hi: f32,
}

impl Window {
    /// Whether span `s` lies wholly outside, strictly: one a union may drop
    /// before merging. (What it would change — the ends of a merged span —
    /// lies strictly outside too, where the intersection's clipping replaces
    /// them by its leaves' ends, ties included, as it would have anyway.)
    #[inline]
    fn excludes(self, s: &Interval) -> bool {
        s.exit.t < self.lo || s.enter.t > self.hi
    }

    /// The window of an intersection whose other operands are `others`: the
    /// common part of the leaves' intervals (the others stay unread), or
    /// `None` when a leaf is missed (the intersection is then empty).
    fn of_leaves<B: Booleans>(others: impl Iterator<Item = B>, leaf: &impl LeafSpans) -> Option<Window> {
        let mut w = Window { lo: f32::NEG_INFINITY, hi: f32::INFINITY };
        for i in others.filter_map(B::leaf) {
            let s = leaf.span(i)?;
            w = Window { lo: w.lo.max(s.enter.t), hi: w.hi.min(s.exit.t) };
        }
        Some(w)
    }
}

/// [`combine`] of an intersection's first operand `tree`, of whose result
/// only the part within `window` matters: a union drops its leaves' spans
/// that lie wholly outside it (a bevel gear's hundreds of teeth, intersected
/// with its envelope). The result within the window is [`combine`]'s, to the
/// bit.
fn combine_within<B: Booleans>(tree: B, leaf: &impl LeafSpans, window: Window, scratch: &mut SpanScratch) {
    match tree.parts() {
        Parts { operation: Operation::Union, others, .. } => {
            union_of(others, leaf, |s: &Interval| !window.excludes(s), scratch);
        }
        _ => _ = combine(tree, leaf, scratch),
    }
}

/// `t_min` lies inside a part of the solid.
pub(super) struct Inside;

/// The first crossing beyond `t_min` of the subtree `tree` if it is an entry
/// (`None` if there is none); [`Inside`] if it is an exit.
pub(super) fn first_entry<B: Booleans>(
    tree: B,
    leaf: &impl LeafSpans,
    t_min: f32,
    scratch: &mut SpanScratch,
) -> Result<Option<Hit>, Inside> {
    // A leaf's one span is read where it is (not pushed and read back).
    if let Some(i) = tree.leaf() {
        return leaf.span(i).map_or(Ok(None), |s| entry_beyond(&[s], t_min));
    }
    scratch.stack.clear();
    combine(tree, leaf, scratch);
    entry_beyond(&scratch.stack, t_min)
}

/// [`first_entry`] of sorted disjoint `spans`.
#[inline]
fn entry_beyond(spans: &[Interval], t_min: f32) -> Result<Option<Hit>, Inside> {
    for s in spans {
        if s.enter.t > t_min {
            return Ok(Some(s.enter));
        }
        if s.exit.t > t_min {
            return Err(Inside);
        }
    }
    Ok(None)
}

/// The first crossing beyond `t_min` of the spans of the whole of `tree`.
pub(super) fn first_of_all<B: Booleans>(
    tree: B,
    leaf: &impl LeafSpans,
    t_min: f32,
    scratch: &mut SpanScratch,
) -> Option<Hit> {
    scratch.stack.clear();
    combine(tree, leaf, scratch);
    first_crossing(&scratch.stack, t_min)
}

/// The first end beyond `t_min` of sorted disjoint `spans`: each span's entry,
/// then its exit. (A plain loop: pairs built to be searched were stored and
/// read back, a stall a pixel.)
#[inline]
pub(super) fn first_crossing(spans: &[Interval], t_min: f32) -> Option<Hit> {
    for s in spans {
        if s.enter.t > t_min {
            return Some(s.enter);
        }
        if s.exit.t > t_min {
            return Some(s.exit);
        }
    }
    None
}

/// Merges the spans on `scratch.stack` from `base` into sorted disjoint spans
/// covering their union.
pub(super) fn union(scratch: &mut SpanScratch, base: usize) {
    let SpanScratch { stack, out, keys, .. } = scratch;
    sort_by_entry(&mut stack[base..], keys, out);
    let mut last = base;
    for k in base..stack.len() {
        let s = stack[k];
        if k > base && s.enter.t <= stack[last].exit.t {
            if s.exit.t > stack[last].exit.t {
                stack[last].exit = s.exit;
            }
        } else {
            if k > base {
                last += 1;
            }
            stack[last] = s;
        }
    }
    stack.truncate(last + 1);
}

/// Spans a union sorts one way and many another ([`sort_by_entry`]).
const MANY_SPANS: usize = 12;

/// Sorts `spans` by entry `t` (as [`f32::total_cmp`] orders). Many spans
/// (a gear's teeth) are sorted as 8-byte keys, the order-keeping bits of `t`
/// above each span's index, then moved into place through `out`: cheaper to
/// compare and to move than the 24-byte spans; equal entries keep their
/// order.
fn sort_by_entry(spans: &mut [Interval], keys: &mut Vec<u64>, out: &mut Vec<Interval>) {
    if spans.len() <= MANY_SPANS {
        spans.sort_unstable_by(|x, y| x.enter.t.total_cmp(&y.enter.t));
        return;
    }
    keys.clear();
    keys.extend(spans.iter().enumerate().map(|(k, s)| u64::from(ordered_bits(s.enter.t)) << 32 | k as u64));
    keys.sort_unstable();
    out.clear();
    out.extend(keys.iter().map(|&k| spans[(k & u64::from(u32::MAX)) as usize]));
    spans.copy_from_slice(out);
}

/// The bits of `t` as an integer that orders as [`f32::total_cmp`] does: the
/// sign bit set on non-negatives, every bit flipped on negatives.
fn ordered_bits(t: f32) -> u32 {
    let b = t.to_bits();
    b ^ (((b as i32 >> 31) as u32) | 0x8000_0000)
}

/// Sorted disjoint spans covering `a ∩ b`, into `out`.
fn intersection(a: &[Interval], b: &[Interval], out: &mut Vec<Interval>) {
    for x in a {
        for y in b {
            let enter = if x.enter.t >= y.enter.t { x.enter } else { y.enter };
            let exit = if x.exit.t <= y.exit.t { x.exit } else { y.exit };
            if enter.t < exit.t {
                out.push(Interval { enter, exit });
            }
        }
    }
    out.sort_unstable_by(|p, q| p.enter.t.total_cmp(&q.enter.t));
}

/// Sorted disjoint spans covering `a` minus `b`, `b` widened by [`TIE`], into
/// `out`: where the ray leaves a cutter it enters the remaining solid through the
/// cutter's wall, whose outward normal (for the solid) is the cutter's, reversed.
pub(super) fn difference(a: &[Interval], b: &[Interval], out: &mut Vec<Interval>) {
    for x in a {
        // `b` is sorted and disjoint: walk it once, cutting `x` from the left.
        let mut rest = Some(*x);
        for y in b {
            let Some(p) = rest else { break };
            let (lo, hi) = (below(y.enter.t), above(y.exit.t));
            if hi <= p.enter.t {
                continue;
            }
            if lo >= p.exit.t {
                break;
            }
            if p.enter.t < lo {
                out.push(Interval { enter: p.enter, exit: wall(y.enter) });
            }
            rest = (p.exit.t > hi).then(|| Interval { enter: wall(y.exit), exit: p.exit });
        }
        out.extend(rest);
    }
}

/// [`intersection`] with one interval `y`, in place on the sorted disjoint
/// spans of `stack` from `base`: each span narrowed to `y`, the empty ones
/// dropped.
#[inline]
fn clip(stack: &mut Vec<Interval>, base: usize, y: &Interval) {
    let mut kept = base;
    for k in base..stack.len() {
        let x = stack[k];
        let enter = if x.enter.t >= y.enter.t { x.enter } else { y.enter };
        let exit = if x.exit.t <= y.exit.t { x.exit } else { y.exit };
        if enter.t < exit.t {
            stack[kept] = Interval { enter, exit };
            kept += 1;
        }
    }
    stack.truncate(kept);
}

/// [`difference`] by one interval `y`, in place on the sorted disjoint spans
/// of `stack` from `base`: the run of spans it overlaps gives way to what is
/// left of the first before it and of the last after it.
#[inline]
fn cut(stack: &mut Vec<Interval>, base: usize, y: &Interval) {
    let (lo, hi) = (below(y.enter.t), above(y.exit.t));
    let mut i = base;
    while i < stack.len() && stack[i].exit.t <= lo {
        i += 1;
    }
    if i == stack.len() || stack[i].enter.t >= hi {
        return; // between spans, or past them all
    }
    let mut j = i + 1;
    while j < stack.len() && stack[j].enter.t < hi {
        j += 1;
    }
    let (first, last) = (stack[i], stack[j - 1]);
    let mut k = i;
    if first.enter.t < lo {
        stack[k] = Interval { enter: first.enter, exit: wall(y.enter) };
        k += 1;
    }
    if last.exit.t > hi {
        let right = Interval { enter: wall(y.exit), exit: last.exit };
        if k < j {
            stack[k] = right;
        } else {
            stack.insert(k, right);
        }
        k += 1;
    }
    if k < j {
        stack.drain(k..j);
    }
}

/// A cutter's crossing seen as the wall of the hole it makes (its normal
/// will be the cutter's, reversed).
fn wall(c: Hit) -> Hit {
    Hit { face: c.face ^ Hit::CUT, ..c }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// Sorted disjoint spans from cut points (sorted, made distinct) of
    /// primitive 0, every other gap a span.
    fn spans(mut ts: Vec<f32>) -> Vec<Interval> {
        ts.sort_by(f32::total_cmp);
        ts.dedup();
        ts.chunks_exact(2).map(|p| Interval { enter: Hit::new(p[0], 0, 0), exit: Hit::new(p[1], 0, 1) }).collect()
    }

    /// A point where spans start or end, within `±r`, often a whole number
    /// (so that ends meet and tie).
    fn cut_point(r: f32) -> impl Strategy<Value = f32> {
        prop_oneof![-r..r, (-5i32..5).prop_map(|k| k as f32)]
    }

    /// A span `(start, length)` within `±4`, its ends mostly whole numbers
    /// (so that they meet other spans' ends).
    fn whole_span() -> impl Strategy<Value = (f32, f32)> {
        let whole = |lo: i32, hi: i32| (lo..hi).prop_map(|k| k as f32);
        (prop_oneof![3 => whole(-3, 3), 1 => -3.0f32..3.0], prop_oneof![3 => whole(0, 3), 1 => 0.0f32..3.0])
    }

    /// The spans `a` combined with the interval `(start, length)` of another
    /// primitive by `in_place` on a stack where `kept` spans of an operand
    /// further down lie below them, and what `general` leaves after those.
    fn by_one_interval(
        a: Vec<Interval>,
        (start, length): (f32, f32),
        kept: usize,
        in_place: fn(&mut Vec<Interval>, usize, &Interval),
        general: fn(&[Interval], &[Interval], &mut Vec<Interval>),
    ) -> (Vec<Interval>, Vec<Interval>) {
        let y = Interval { enter: Hit::new(start, 1, 2), exit: Hit::new(start + length, 1, 3) };
        let below: Vec<Interval> = (0..kept)
            .map(|k| Interval { enter: Hit::new(-100.0 + k as f32, 2, 0), exit: Hit::new(-99.5 + k as f32, 2, 1) })
            .collect();
        let mut expected = below.clone();
        general(&a, &[y], &mut expected);
        let mut stack = below;
        stack.extend_from_slice(&a);
        in_place(&mut stack, kept, &y);
        (stack, expected)
    }

    proptest! {
        /// Cutting by one interval in place leaves what [`difference`] by it
        /// leaves: the same spans, the same crossings, walls included.
        #[test]
        fn a_cut_in_place_is_the_difference_by_one_interval(
            ts in prop::collection::vec(cut_point(5.0), 0..12),
            other in (cut_point(6.0), 0.0f32..6.0),
            kept in 0usize..3,
        ) {
            let (in_place, expected) = by_one_interval(spans(ts), other, kept, cut, difference);
            prop_assert_eq!(in_place, expected);
        }

        /// Narrowing to one interval in place leaves what [`intersection`]
        /// with it leaves: the same spans with the same crossings.
        #[test]
        fn a_clip_in_place_is_the_intersection_with_one_interval(
            ts in prop::collection::vec(cut_point(5.0), 0..12),
            other in (cut_point(6.0), 0.0f32..6.0),
            kept in 0usize..3,
        ) {
            let (in_place, expected) = by_one_interval(spans(ts), other, kept, clip, intersection);
            prop_assert_eq!(in_place, expected);
        }

        /// The keys of many spans order them as `f32::total_cmp` orders their
        /// entries (signed zeros, infinities and ties included), equal
        /// entries kept in their order.
        #[test]
        fn many_spans_sort_by_key_as_by_entry(
            ts in prop::collection::vec(prop_oneof![
                cut_point(5.0),
                Just(-0.0f32),
                Just(f32::INFINITY),
                Just(f32::NEG_INFINITY),
                -1e30f32..1e30,
            ], 0..40),
        ) {
            let spans: Vec<Interval> = ts
                .iter()
                .enumerate()
                .map(|(k, &t)| Interval { enter: Hit::new(t, k, 0), exit: Hit::new(f32::INFINITY, k, 1) })
                .collect();
            let mut expected = spans.clone();
            expected.sort_by(|x, y| x.enter.t.total_cmp(&y.enter.t));
            let mut sorted = spans;
            sort_by_entry(&mut sorted, &mut Vec::new(), &mut Vec::new());
            if sorted.len() > MANY_SPANS {
                prop_assert_eq!(sorted, expected);
            } else {
                let entries = |v: &[Interval]| v.iter().map(|s| s.enter.t.to_bits()).collect::<Vec<_>>();
                prop_assert_eq!(entries(&sorted), entries(&expected));
            }
        }
    }

    proptest! {
        // Ends meeting the window's ends exactly are what can go wrong: more
        // cases than the default find them every run.
        #![proptest_config(ProptestConfig::with_cases(2048))]

        /// An intersection's union of many leaves, which drops the spans
        /// wholly outside the other leaves' intervals ([`Window`]), gives what
        /// the same union gives unnarrowed (nested in a one-operand union,
        /// which narrows only leaves): the same spans, the same crossings,
        /// ends that meet the window's included.
        #[test]
        fn an_intersection_narrows_its_union_without_changing_it(
            members in prop::collection::vec(prop::option::of(whole_span()), 0..24),
            window in prop::collection::vec(prop::option::of(whole_span()), 1..3),
        ) {
            let all: Vec<Option<Interval>> = members
                .iter()
                .chain(&window)
                .enumerate()
                .map(|(i, m)| m.map(|(t, len)| Interval { enter: Hit::new(t, i, 0), exit: Hit::new(t + len, i, 1) }))
                .collect();
            let leaves = |range: std::ops::Range<usize>| range.map(CsgTree::Leaf).collect::<Vec<_>>();
            let n = members.len();
            let union = CsgTree::Union(leaves(0..n));
            let with = |first: CsgTree| CsgTree::Intersection([vec![first], leaves(n..all.len())].concat());
            let result = |tree: &CsgTree| {
                let mut scratch = SpanScratch::default();
                combine(tree, &|i: usize| all[i], &mut scratch);
                scratch.stack
            };
            prop_assert_eq!(result(&with(union.clone())), result(&with(CsgTree::Union(vec![union]))));
        }
    }
}
