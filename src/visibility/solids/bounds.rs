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
//! of each other, that order picks the face shown: a few pixels in a hundred
//! thousand, on the models that have such ties at all.)
//!
//! The pay-off is where cutters reach past what they cut (a hole's cylinder
//! longer than the plate is thick, a slot's box wider than the part): their
//! ends keep to the part's outline, and the pixels the walk visits fall by
//! up to a quarter on the corpus's printer parts (`docs/benchmarks.md`,
//! "Design measurements"). Where the bounding node's own outline is wide (a
//! gear's teeth, intersected with the ring that keeps their ends, still
//! reach the axis inside the ring) the clip saves pixels but little time.

use crate::csg::{Bound, BoxBound, CsgTree, Reach};

/// Most bounding leaves kept per primitive (the innermost ones, nearest the
/// primitive in the tree and usually the tightest): each costs a clip of the
/// primitive's ends on every scanline it occupies.
pub const MOST_BOUNDS: usize = 2;

/// One way of bounding the primitives of a tree ([`BoundingLeaves`] or the
/// boxes of [`narrow`]), walked by [`bound_leaves`].
trait Bounding {
    /// What bounds a node.
    type Bound: Bound;
    /// What bounds primitive `p` as it stands.
    fn own(&self, p: usize) -> Self::Bound;
    /// Primitive `p` (found in one leaf only) matters only `within`: takes
    /// note, and returns what bounds it now.
    fn within(&mut self, p: usize, within: &Self::Bound) -> Self::Bound;
}

/// Hands every primitive of `tree` found in one leaf (`once`) what bounds
/// it there, the subtree mattering only `within`: an intersection's
/// operands are within each other, a difference's cutters within the part
/// they cut. Returns what bounds `tree` afterwards.
fn bound_leaves<T: Bounding>(t: &mut T, tree: &CsgTree, within: &T::Bound, once: &[bool]) -> T::Bound {
    match tree {
        CsgTree::Leaf(p) if once[*p] => t.within(*p, within),
        CsgTree::Leaf(p) => t.own(*p),
        CsgTree::Union(kids) => kids.iter().fold(T::Bound::nowhere(), |b, k| b.join(&bound_leaves(t, k, within, once))),
        CsgTree::Intersection(kids) => {
            // Operand k matters within the others: those before it (as
            // bounded) and those after it (as they are).
            let mut after = vec![T::Bound::anywhere(); kids.len() + 1];
            for (k, kid) in kids.iter().enumerate().rev() {
                after[k] = after[k + 1].meet(&kid.bound(&|p| t.own(p)));
            }
            let mut before = within.clone();
            for (k, kid) in kids.iter().enumerate() {
                let own = bound_leaves(t, kid, &before.meet(&after[k + 1]), once);
                before = before.meet(&own);
            }
            before
        }
        CsgTree::Difference(first, cutters) => {
            let part = within.meet(&bound_leaves(t, first, within, once));
            cutters.iter().for_each(|c| _ = bound_leaves(t, c, &part, once));
            part
        }
    }
}

/// Whether each of `primitives` primitives is found in exactly one leaf of
/// `tree` (one found in more may matter wherever any of its places does).
fn found_once(tree: &CsgTree, primitives: usize) -> Vec<bool> {
    fn count(tree: &CsgTree, seen: &mut [u8]) {
        match tree {
            CsgTree::Leaf(p) => seen[*p] = seen[*p].saturating_add(1),
            CsgTree::Union(kids) | CsgTree::Intersection(kids) => kids.iter().for_each(|k| count(k, seen)),
            CsgTree::Difference(first, cutters) => {
                count(first, seen);
                cutters.iter().for_each(|k| count(k, seen));
            }
        }
    }
    let mut seen = vec![0u8; primitives];
    count(tree, &mut seen);
    seen.into_iter().map(|n| n == 1).collect()
}

/// Leaves that bound a node, innermost last (at most [`MOST_BOUNDS`]);
/// none for a union (a list of leaves cannot say "within one or another").
#[derive(Debug, Clone, Copy, Default)]
struct LeafList {
    leaves: [u32; MOST_BOUNDS],
    len: usize,
}

impl LeafList {
    fn of(p: usize) -> LeafList {
        LeafList::anywhere().with(p as u32)
    }

    /// These and `q`, the oldest dropped past [`MOST_BOUNDS`].
    fn with(mut self, q: u32) -> LeafList {
        if self.len == MOST_BOUNDS {
            self.leaves.rotate_left(1);
            self.len -= 1;
        }
        self.leaves[self.len] = q;
        self.len += 1;
        self
    }

    fn leaves(&self) -> &[u32] {
        &self.leaves[..self.len]
    }
}

impl Bound for LeafList {
    fn anywhere() -> Self {
        LeafList { leaves: [0; MOST_BOUNDS], len: 0 }
    }

    fn meet(&self, other: &Self) -> Self {
        other.leaves().iter().fold(*self, |list, &q| list.with(q))
    }

    /// A list cannot say "nothing inside": no bound, which holds too.
    fn nowhere() -> Self {
        LeafList::anywhere()
    }

    fn join(&self, _: &Self) -> Self {
        LeafList::anywhere()
    }
}

/// Per primitive, the leaves (primitives) outside whose outlines it cannot
/// change the solid.
#[derive(Debug, Clone, Default)]
pub struct BoundingLeaves {
    /// `leaves[start[p]..start[p + 1]]` bound primitive `p`.
    start: Vec<u32>,
    leaves: Vec<u32>,
}

/// [`BoundingLeaves`] as they are found.
struct FoundLeaves(Vec<LeafList>);

impl Bounding for FoundLeaves {
    type Bound = LeafList;

    fn own(&self, p: usize) -> LeafList {
        LeafList::of(p)
    }

    fn within(&mut self, p: usize, within: &LeafList) -> LeafList {
        let others = within.leaves().iter().filter(|&&q| q as usize != p);
        self.0[p] = others.fold(LeafList::anywhere(), |list, &q| list.with(q));
        self.own(p)
    }
}

impl BoundingLeaves {
    /// The bounding leaves of each of `primitives` primitives of `tree` (none
    /// for a primitive found in more than one leaf).
    #[must_use]
    pub fn new(tree: &CsgTree, primitives: usize) -> BoundingLeaves {
        let mut found = FoundLeaves(vec![LeafList::default(); primitives]);
        bound_leaves(&mut found, tree, &LeafList::anywhere(), &found_once(tree, primitives));
        let mut out = BoundingLeaves { start: Vec::with_capacity(primitives + 1), leaves: Vec::new() };
        for bounds in found.0 {
            out.start.push(out.leaves.len() as u32);
            out.leaves.extend_from_slice(bounds.leaves());
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

/// Each primitive's box of pixels, as [`narrow`] cuts them.
struct Boxes<'a, B>(&'a mut [Option<B>]);

impl<B: BoxBound> Bounding for Boxes<'_, B> {
    type Bound = Reach<B>;

    fn own(&self, p: usize) -> Reach<B> {
        Reach::of(self.0[p])
    }

    fn within(&mut self, p: usize, within: &Reach<B>) -> Reach<B> {
        self.0[p] = match self.own(p).meet(within) {
            Reach::Within(b) => Some(b),
            _ => None,
        };
        self.own(p)
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
pub fn narrow<B: BoxBound>(tree: &CsgTree, boxes: &mut [Option<B>]) {
    let once = found_once(tree, boxes.len());
    bound_leaves(&mut Boxes(boxes), tree, &Reach::Anywhere, &once);
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

    impl BoxBound for Span {
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
