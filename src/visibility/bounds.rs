//! Where a primitive can change a CSG solid: within the outlines of the
//! leaves that bound its intersections and differences (beyond seed 003,
//! whose y- and x-occupancy lists take each primitive's whole projection).
//! Two clips, one per frame and one per scanline: [`narrow`] cuts each
//! primitive's box of pixels to the boxes of the nodes that bound it (a
//! union's box joins its members'), and [`BoundingLeaves`] names the leaves
//! whose own ends clip a primitive's ends on every scanline.
//!
//! Along any ray the booleans decide point by point, so a primitive `p`
//! changes a node's result only at points inside `p`. Inside an intersection
//! `A ∩ B` (with `p` in `A`), that result lies within `B`; inside a
//! difference `A − C` (with `p` in a cutter `C`), within `A`. So wherever the
//! ray misses a leaf `q` that bounds `B` (or `A`) — `B` is `q`, an
//! intersection with `q` among its operands, or a difference whose first
//! operand `q` bounds — that node is empty whatever `p` holds, and the walk
//! may leave `p` out there: the walk finds the same node empty from `q`'s
//! absence alone. (The one trace `p`'s absence can leave is the order in
//! which a difference meets its cutters, which follows the order they came
//! to occupy the row: where two cutters' faces lie within the booleans' tie
//! of each other, that order picks the face shown — 4 of 143,600 pixels of
//! the corpus's z_axis at 1280x720 changed so, none on the other models.)
//!
//! The pay-off is where cutters reach past what they cut (a hole's cylinder
//! longer than the plate is thick, a slot's box wider than the part): their
//! ends keep to the part's outline. On the corpus at 1280x720 the scanline
//! pixels occupied fall 27% on x_end (frame 10% faster) and 19% on
//! p3_x_carriage; old_z_axis_bottom's cutters, bounded by a union of
//! blocks, keep to its box (13% faster). A bevel gear's teeth, long spikes
//! from the gear's axis intersected with the ring that keeps their ends,
//! lose 60% of theirs but the frame only 4%: the ring's outline still takes
//! in the axis, where they all meet.

use crate::scene::csg::CsgTree;

/// Most bounding leaves kept per primitive (the innermost ones, nearest the
/// primitive in the tree and usually the tightest): each costs a clip of the
/// primitive's ends on every scanline it occupies.
pub const MOST_BOUNDS: usize = 2;

/// Per primitive, the leaves (primitives) outside whose outlines it cannot
/// change the solid.
#[derive(Debug, Clone, Default)]
pub struct BoundingLeaves {
    /// `leaves[start[p]..start[p + 1]]` bound primitive `p`.
    start: Vec<u32>,
    leaves: Vec<u32>,
}

impl BoundingLeaves {
    /// The bounding leaves of each of `primitives` primitives of `tree`. A
    /// primitive found in more than one leaf of the tree gets none (it may
    /// matter wherever any of its places does).
    #[must_use]
    pub fn new(tree: &CsgTree, primitives: usize) -> BoundingLeaves {
        let mut found: Vec<Option<Vec<u32>>> = vec![None; primitives];
        let mut twice = vec![false; primitives];
        visit(tree, &mut Vec::new(), &mut |p, bounds| {
            twice[p] |= found[p].is_some();
            let own: Vec<u32> = bounds.iter().rev().copied().filter(|&q| q as usize != p).take(MOST_BOUNDS).collect();
            found[p] = Some(own);
        });
        let mut out = BoundingLeaves { start: Vec::with_capacity(primitives + 1), leaves: Vec::new() };
        for (p, bounds) in found.into_iter().enumerate() {
            out.start.push(out.leaves.len() as u32);
            if !twice[p] {
                out.leaves.extend(bounds.unwrap_or_default());
            }
        }
        out.start.push(out.leaves.len() as u32);
        out
    }

    /// The leaves that bound primitive `p` (none when unknown).
    #[must_use]
    pub fn of(&self, p: usize) -> &[u32] {
        match (self.start.get(p), self.start.get(p + 1)) {
            (Some(&a), Some(&b)) => &self.leaves[a as usize..b as usize],
            _ => &[],
        }
    }
}

/// Calls `leaf(p, bounds)` for every leaf of `tree`, `bounds` the leaves that
/// bound it (outermost first), `outer` those of the tree itself.
fn visit(tree: &CsgTree, outer: &mut Vec<u32>, leaf: &mut impl FnMut(usize, &[u32])) {
    match tree {
        CsgTree::Leaf(p) => leaf(*p, outer),
        CsgTree::Union(kids) => kids.iter().for_each(|k| visit(k, outer, leaf)),
        CsgTree::Intersection(kids) => {
            let each: Vec<Vec<u32>> = kids.iter().map(bounded_by).collect();
            for (k, kid) in kids.iter().enumerate() {
                let depth = outer.len();
                let others = each.iter().enumerate().filter(|&(j, _)| j != k).flat_map(|(_, b)| b);
                outer.extend(others.take(MOST_BOUNDS));
                visit(kid, outer, leaf);
                outer.truncate(depth);
            }
        }
        CsgTree::Difference(first, cutters) => {
            visit(first, outer, leaf);
            let depth = outer.len();
            outer.extend(bounded_by(first));
            cutters.iter().for_each(|c| visit(c, outer, leaf));
            outer.truncate(depth);
        }
    }
}

/// Leaves (at most [`MOST_BOUNDS`]) whose volumes contain the whole of
/// `tree`: a leaf itself, an intersection's operands', a difference's first
/// operand's; none for a union.
fn bounded_by(tree: &CsgTree) -> Vec<u32> {
    let mut out = match tree {
        CsgTree::Leaf(p) => vec![*p as u32],
        CsgTree::Union(_) => Vec::new(),
        CsgTree::Intersection(kids) => kids.iter().flat_map(bounded_by).collect(),
        CsgTree::Difference(first, _) => bounded_by(first),
    };
    out.truncate(MOST_BOUNDS);
    out
}

/// A box of pixels (a primitive's or a node's reach on the screen), as
/// [`narrow`] meets and joins them.
pub trait PixelBox: Copy {
    /// The pixels in both, `None` if none.
    fn meet(self, other: Self) -> Option<Self>;
    /// A box holding the pixels of both.
    fn join(self, other: Self) -> Self;
}

/// Where a node of the tree may be non-empty: anywhere, within a box, or
/// nowhere on the screen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reach<B> {
    Anywhere,
    Within(B),
    Nowhere,
}

impl<B: PixelBox> Reach<B> {
    fn meet(self, other: Reach<B>) -> Reach<B> {
        match (self, other) {
            (Reach::Nowhere, _) | (_, Reach::Nowhere) => Reach::Nowhere,
            (Reach::Anywhere, r) | (r, Reach::Anywhere) => r,
            (Reach::Within(a), Reach::Within(b)) => a.meet(b).map_or(Reach::Nowhere, Reach::Within),
        }
    }

    fn join(self, other: Reach<B>) -> Reach<B> {
        match (self, other) {
            (Reach::Anywhere, _) | (_, Reach::Anywhere) => Reach::Anywhere,
            (Reach::Nowhere, r) | (r, Reach::Nowhere) => r,
            (Reach::Within(a), Reach::Within(b)) => Reach::Within(a.join(b)),
        }
    }

    fn of(b: Option<B>) -> Reach<B> {
        b.map_or(Reach::Nowhere, Reach::Within)
    }
}

/// Narrows each primitive's box of pixels `boxes` (`None`: it shows
/// nowhere) to the boxes of the nodes that bound it, as [`BoundingLeaves`]
/// does with leaves: an intersection's other operands, a cut part. A node's
/// box is its leaves' joined (a union), met (an intersection), or its first
/// operand's (a difference); outside it the node is empty. Unlike
/// [`BoundingLeaves`] this reaches through unions (a part made of many
/// boxes, drilled by long cylinders). A primitive found in more than one
/// leaf is left as it is.
pub fn narrow<B: PixelBox>(tree: &CsgTree, boxes: &mut [Option<B>]) {
    let mut leaves = vec![0u8; boxes.len()];
    count_leaves(tree, &mut leaves);
    narrow_within(tree, Reach::Anywhere, boxes, &leaves);
}

/// How many leaves name each primitive (2 for two or more).
fn count_leaves(tree: &CsgTree, leaves: &mut [u8]) {
    match tree {
        CsgTree::Leaf(p) => leaves[*p] = (leaves[*p] + 1).min(2),
        CsgTree::Union(kids) | CsgTree::Intersection(kids) => kids.iter().for_each(|k| count_leaves(k, leaves)),
        CsgTree::Difference(first, cutters) => {
            count_leaves(first, leaves);
            cutters.iter().for_each(|k| count_leaves(k, leaves));
        }
    }
}

/// Where `tree` may be non-empty, from its primitives' `boxes`.
fn reach<B: PixelBox>(tree: &CsgTree, boxes: &[Option<B>]) -> Reach<B> {
    match tree {
        CsgTree::Leaf(p) => Reach::of(boxes[*p]),
        CsgTree::Union(kids) => kids.iter().fold(Reach::Nowhere, |r, k| r.join(reach(k, boxes))),
        CsgTree::Intersection(kids) => kids.iter().fold(Reach::Anywhere, |r, k| r.meet(reach(k, boxes))),
        CsgTree::Difference(first, _) => reach(first, boxes),
    }
}

/// [`narrow`] of the subtree `tree`, whose result matters only `within`;
/// returns where the subtree may be non-empty afterwards.
fn narrow_within<B: PixelBox>(tree: &CsgTree, within: Reach<B>, boxes: &mut [Option<B>], leaves: &[u8]) -> Reach<B> {
    match tree {
        CsgTree::Leaf(p) => {
            if leaves[*p] == 1 {
                boxes[*p] = match Reach::of(boxes[*p]).meet(within) {
                    Reach::Within(b) => Some(b),
                    _ => None,
                };
            }
            Reach::of(boxes[*p])
        }
        CsgTree::Union(kids) => {
            kids.iter().fold(Reach::Nowhere, |r, k| r.join(narrow_within(k, within, boxes, leaves)))
        }
        CsgTree::Intersection(kids) => {
            // Operand k matters within the others: those before it (as
            // narrowed) and those after it (as they are).
            let mut after = vec![Reach::Anywhere; kids.len() + 1];
            for (k, kid) in kids.iter().enumerate().rev() {
                after[k] = after[k + 1].meet(reach(kid, boxes));
            }
            let mut before = within;
            for (k, kid) in kids.iter().enumerate() {
                before = before.meet(narrow_within(kid, before.meet(after[k + 1]), boxes, leaves));
            }
            before
        }
        CsgTree::Difference(first, cutters) => {
            let part = narrow_within(first, within, boxes, leaves);
            cutters.iter().for_each(|c| _ = narrow_within(c, part, boxes, leaves));
            part
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use CsgTree::{Difference, Intersection, Leaf, Union};

    #[test]
    fn leaves_bound_what_they_intersect_and_what_cuts_them() {
        // ((0 ∪ 1) ∩ 2 ∩ 3) − (4 ∩ 5), then ∪ 6.
        let part = Difference(
            Box::new(Intersection(vec![Union(vec![Leaf(0), Leaf(1)]), Leaf(2), Leaf(3)])),
            vec![Intersection(vec![Leaf(4), Leaf(5)])],
        );
        let tree = Union(vec![part, Leaf(6)]);
        let b = BoundingLeaves::new(&tree, 7);
        let set = |p: usize| {
            let mut v = b.of(p).to_vec();
            v.sort_unstable();
            v
        };
        assert_eq!(set(0), [2, 3]);
        assert_eq!(set(1), [2, 3]);
        assert_eq!(set(2), [3]);
        assert_eq!(set(3), [2]);
        // The cutters: each other's operand, then the part they cut (bounded by
        // 2 and 3), the innermost kept.
        assert_eq!(set(4), [3, 5]);
        assert_eq!(set(5), [3, 4]);
        assert_eq!(set(6), Vec::<u32>::new());
    }

    #[test]
    fn a_primitive_in_two_places_is_unbounded() {
        let tree = Union(vec![Intersection(vec![Leaf(0), Leaf(1)]), Leaf(0)]);
        let b = BoundingLeaves::new(&tree, 2);
        assert!(b.of(0).is_empty());
        assert_eq!(b.of(1), [0]);
        assert!(b.of(5).is_empty());
    }

    /// Columns `lo..=hi` as a box of pixels.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    struct Span(i64, i64);

    impl PixelBox for Span {
        fn meet(self, o: Span) -> Option<Span> {
            let s = Span(self.0.max(o.0), self.1.min(o.1));
            (s.0 <= s.1).then_some(s)
        }

        fn join(self, o: Span) -> Span {
            Span(self.0.min(o.0), self.1.max(o.1))
        }
    }

    #[test]
    fn boxes_narrow_to_what_bounds_them_through_unions() {
        // ((0 ∪ 1) − 2 − (3 ∩ 4)) ∩ 5, and 6 twice.
        let part =
            Difference(Box::new(Union(vec![Leaf(0), Leaf(1)])), vec![Leaf(2), Intersection(vec![Leaf(3), Leaf(4)])]);
        let tree = Union(vec![Intersection(vec![part, Leaf(5), Leaf(6)]), Leaf(6)]);
        let mut boxes = vec![
            Some(Span(0, 10)),
            Some(Span(20, 30)),
            Some(Span(-50, 50)),
            Some(Span(25, 100)),
            Some(Span(40, 100)),
            Some(Span(5, 28)),
            Some(Span(0, 100)),
        ];
        narrow(&tree, &mut boxes);
        let want = [
            Some(Span(5, 10)),  // within 5 (and 6: found twice, it still bounds)
            Some(Span(20, 28)), // within 5
            Some(Span(5, 28)),  // within the union's join (0..30), within 5
            None,               // within the part and 4: nothing left
            None,               // within the part and 3
            Some(Span(5, 28)),  // within the part (0..30)
            Some(Span(0, 100)), // found twice: as it was
        ];
        assert_eq!(boxes, want);
    }
}
