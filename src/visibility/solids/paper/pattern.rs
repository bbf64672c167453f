//! Seed 003 as the paper states it (§5.2.1): the solid expanded into a pattern
//! matrix — a union of segments, each the intersection of some positive and some
//! negative primitives — with reference counts per segment.
//!
//! Expansion (the paper's sum of products): a leaf is one segment `{+i}`; a union
//! concatenates its children's segments; an intersection takes every combination
//! of one segment per child; a difference `A − B` is `A ∩ ¬B`, where `¬B` of a
//! union of segments is, by De Morgan, the intersection over B's segments of
//! "outside one of its primitives" (a positive one turned negative, or a negative
//! one turned positive) — so cutters that are themselves unions, intersections or
//! differences expand too. Segments that hold a primitive both ways are empty and
//! dropped. The number of segments can explode (the paper names it; OpenSCAD stops
//! at 100,000 terms): [`PatternMatrix::expand`] stops at a limit and says so.
//!
//! Per scanline the y-occupancy list gives each segment's RCy (positive
//! primitives not on this scanline; recounted per scanline); only segments with
//! RCy = 0 take part. Along the scanline, RCx counts the positive primitives not
//! yet entered: a primitive entering the x-occupancy list decrements the count of
//! every segment it is a positive member of, leaving increments it, and a segment
//! whose count is 0 is in the visible-segment list. Negative primitives do not
//! count; they only raise a flag that they occupy the pixel (absent ones are
//! skipped). Per pixel, each visible segment's depth interval is the intersection
//! of its positive primitives' intervals minus its flagged negative ones', and the
//! pixel's surface is the nearest over the visible segments.

use crate::csg::occupancy::PlacedSet;
use crate::csg::{CsgCaster, CsgTree, Hit, Interval, SpanScratch};
use crate::visibility::solids::XOrder;

/// One segment: an intersection of positive primitives and complements of
/// negative ones (indices into the solid's primitives, sorted).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Segment {
    /// Primitives the segment lies inside.
    pub positive: Vec<usize>,
    /// Primitives the segment lies outside (seed 003's negative flag).
    pub negative: Vec<usize>,
}

/// The expansion would exceed the limit on segments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TooManySegments {
    /// The limit that was passed.
    pub limit: usize,
}

/// A solid as a union of segments, with, per primitive, the segments it is a
/// positive or a negative member of.
#[derive(Debug, Clone)]
pub struct PatternMatrix {
    /// The segments.
    pub segments: Vec<Segment>,
    /// Per primitive: the segments it is positive in.
    positive_in: Vec<Vec<u32>>,
    /// Per primitive: whether some segment holds it negatively.
    negative_somewhere: Vec<bool>,
}

impl PatternMatrix {
    /// Expands `tree` over `primitives` primitives, giving up past `limit`
    /// segments.
    ///
    /// # Errors
    ///
    /// [`TooManySegments`] past `limit` segments.
    pub fn expand(tree: &CsgTree, primitives: usize, limit: usize) -> Result<PatternMatrix, TooManySegments> {
        let segments = sum_of_products(tree, limit)?;
        let mut positive_in = vec![Vec::new(); primitives];
        let mut negative_somewhere = vec![false; primitives];
        for (s, seg) in segments.iter().enumerate() {
            seg.positive.iter().for_each(|&i| positive_in[i].push(s as u32));
            seg.negative.iter().for_each(|&i| negative_somewhere[i] = true);
        }
        Ok(PatternMatrix { segments, positive_in, negative_somewhere })
    }

    /// One scanline, given each occupant's left and right ends (`ends`): RCy,
    /// then the x-walk with RCx and the visible-segment list; writes each
    /// covered pixel's nearest surface into `row`.
    pub(crate) fn walk_row(
        &self,
        caster: &CsgCaster,
        ends: &[(usize, i64, i64)],
        span: &impl Fn(usize, usize) -> Option<Interval>,
        near: f32,
        row: &mut [Option<Hit>],
    ) {
        let n = self.positive_in.len();
        // RCy: positive members not on this scanline.
        let mut on_row = vec![false; n];
        ends.iter().for_each(|&(i, _, _)| on_row[i] = true);
        let live: Vec<bool> =
            self.segments.iter().map(|s| s.positive.iter().all(|&i| on_row[i]) && !s.positive.is_empty()).collect();
        // Only positive members of live segments, and negative members of any,
        // need walking.
        let wanted = |i: usize| self.positive_in[i].iter().any(|&s| live[s as usize]) || self.negative_somewhere[i];
        let mut tables = XOrder::default();
        let XOrder { entry, exit } = tables.sort(ends.iter().copied().filter(|&(i, _, _)| wanted(i)));
        let mut rcx: Vec<usize> = self.segments.iter().map(|s| s.positive.len()).collect();
        // The visible-segment list (seed 003 §5.2.1).
        let mut visible = PlacedSet::new(self.segments.len());
        let mut flagged = vec![false; n];
        let (mut next_in, mut next_out) = (0, 0);
        let mut spans = SpanCache::new(n);
        let mut scratch = SpanScratch::default();
        let Some(first) = entry.first().map(|e| e.1.max(0) as usize) else { return };
        for (x, px) in row.iter_mut().enumerate().skip(first) {
            while next_in < entry.len() && entry[next_in].1 <= x as i64 {
                let i = entry[next_in].0;
                flagged[i] = true;
                for &s in &self.positive_in[i] {
                    let s = s as usize;
                    rcx[s] -= 1;
                    if rcx[s] == 0 && live[s] {
                        visible.insert(s);
                    }
                }
                next_in += 1;
            }
            if !visible.ids().is_empty() {
                spans.next_pixel();
                *px = caster.first_hit_of_segments(
                    visible
                        .ids()
                        .iter()
                        .map(|&s| &self.segments[s as usize])
                        .map(|s| (&s.positive[..], &s.negative[..])),
                    &|i| flagged[i],
                    &mut |i| spans.get(i, || span(i, x)),
                    near,
                    &mut scratch,
                );
            }
            while next_out < exit.len() && exit[next_out].2 <= x as i64 {
                let i = exit[next_out].0;
                flagged[i] = false;
                for &s in &self.positive_in[i] {
                    let s = s as usize;
                    if rcx[s] == 0 && live[s] {
                        visible.remove(s);
                    }
                    rcx[s] += 1;
                }
                next_out += 1;
            }
            if next_out == exit.len() {
                break;
            }
        }
    }
}

/// Each primitive's span at the current pixel, computed once however many
/// segments hold the primitive (the pattern matrix repeats primitives: the
/// paper's own named defect, paid for here by a per-pixel cache).
struct SpanCache {
    stamp: Vec<u32>,
    spans: Vec<Option<Interval>>,
    pixel: u32,
}

impl SpanCache {
    fn new(n: usize) -> Self {
        SpanCache { stamp: vec![0; n], spans: vec![None; n], pixel: 0 }
    }

    fn next_pixel(&mut self) {
        self.pixel += 1;
    }

    fn get(&mut self, i: usize, span: impl FnOnce() -> Option<Interval>) -> Option<Interval> {
        if self.stamp[i] != self.pixel {
            // Handed on as computed, not read back from where it is kept.
            let s = span();
            self.stamp[i] = self.pixel;
            self.spans[i] = s;
            return s;
        }
        self.spans[i]
    }
}

/// The segments of `tree`, at most `limit` of them.
fn sum_of_products(tree: &CsgTree, limit: usize) -> Result<Vec<Segment>, TooManySegments> {
    let too_many = |n: usize| if n > limit { Err(TooManySegments { limit }) } else { Ok(()) };
    Ok(match tree {
        CsgTree::Leaf(i) => vec![Segment { positive: vec![*i], negative: Vec::new() }],
        CsgTree::Union(kids) => {
            let mut out = Vec::new();
            for k in kids {
                out.extend(sum_of_products(k, limit)?);
                too_many(out.len())?;
            }
            out
        }
        CsgTree::Intersection(kids) => {
            let mut out = vec![Segment { positive: Vec::new(), negative: Vec::new() }];
            for k in kids {
                out = meet(&out, &sum_of_products(k, limit)?, limit)?;
            }
            out
        }
        CsgTree::Difference(a, cutters) => {
            let mut out = sum_of_products(a, limit)?;
            for c in cutters {
                for seg in sum_of_products(c, limit)? {
                    // Outside this segment: outside one of its members.
                    let outside: Vec<Segment> = seg
                        .positive
                        .iter()
                        .map(|&i| Segment { positive: Vec::new(), negative: vec![i] })
                        .chain(seg.negative.iter().map(|&i| Segment { positive: vec![i], negative: Vec::new() }))
                        .collect();
                    out = meet(&out, &outside, limit)?;
                }
            }
            out
        }
    })
}

/// Every intersection of one segment of `a` with one of `b`, empty ones
/// (a primitive both inside and outside) dropped.
fn meet(a: &[Segment], b: &[Segment], limit: usize) -> Result<Vec<Segment>, TooManySegments> {
    let mut out = Vec::new();
    for x in a {
        for y in b {
            let mut positive: Vec<usize> = x.positive.iter().chain(&y.positive).copied().collect();
            let mut negative: Vec<usize> = x.negative.iter().chain(&y.negative).copied().collect();
            positive.sort_unstable();
            positive.dedup();
            negative.sort_unstable();
            negative.dedup();
            if positive.iter().any(|i| negative.binary_search(i).is_ok()) {
                continue;
            }
            out.push(Segment { positive, negative });
            if out.len() > limit {
                return Err(TooManySegments { limit });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leaf(i: usize) -> CsgTree {
        CsgTree::Leaf(i)
    }

    #[test]
    fn differences_become_negative_members_and_de_morgan_expands_cutters() {
        // (0 ∪ 1) − 2 = 0¬2 + 1¬2.
        let t = CsgTree::Difference(Box::new(CsgTree::Union(vec![leaf(0), leaf(1)])), vec![leaf(2)]);
        let m = PatternMatrix::expand(&t, 3, 100).unwrap();
        let seg = |p: &[usize], n: &[usize]| Segment { positive: p.to_vec(), negative: n.to_vec() };
        assert_eq!(m.segments, vec![seg(&[0], &[2]), seg(&[1], &[2])]);
        // 0 − (1 − 2) = 0 ∩ (¬1 ∪ 2) = 0¬1 + 0·2.
        let t = CsgTree::Difference(Box::new(leaf(0)), vec![CsgTree::Difference(Box::new(leaf(1)), vec![leaf(2)])]);
        let m = PatternMatrix::expand(&t, 3, 100).unwrap();
        assert_eq!(m.segments, vec![seg(&[0], &[1]), seg(&[0, 2], &[])]);
        // 0 − 0 is empty.
        let t = CsgTree::Difference(Box::new(leaf(0)), vec![leaf(0)]);
        assert!(PatternMatrix::expand(&t, 1, 100).unwrap().segments.is_empty());
    }

    #[test]
    fn the_expansion_stops_at_its_limit() {
        // (0 ∪ 1) ∩ (2 ∪ 3) ∩ ... : 2^k segments.
        let t = CsgTree::Intersection((0..12).map(|k| CsgTree::Union(vec![leaf(2 * k), leaf(2 * k + 1)])).collect());
        assert_eq!(PatternMatrix::expand(&t, 24, 1000).unwrap_err(), TooManySegments { limit: 1000 });
        assert_eq!(PatternMatrix::expand(&t, 24, 5000).unwrap().segments.len(), 4096);
    }
}
