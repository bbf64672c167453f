//! Reference counts at every node of a CSG tree (seed 003 §5.2.1, in tree form).
//!
//! The paper keeps, per segment of its sum of products, a count of the
//! segment's primitives not yet occupying the pixel (RCx along a scanline, RCy
//! down the frame); a segment whose count reaches zero joins the
//! visible-segment list, and a pixel combines the intervals of the visible
//! segments only. Without the expansion (which can explode) the same
//! bookkeeping is kept at every node of the tree:
//!
//! - a leaf is non-empty while its primitive occupies the pixel;
//! - a union is non-empty while one of its operands is, and keeps the list of
//!   those (the root's list is the visible-segment list);
//! - an intersection is non-empty while all of its operands are (a count: the
//!   paper's RC);
//! - a difference is non-empty while its first operand is, and keeps the list
//!   of its non-empty cutters: a negative primitive that does not occupy the
//!   pixel costs nothing there (the paper's slow case, given a fast path).
//!
//! A primitive entering or leaving the x-occupancy list changes its leaf, and
//! the change climbs only while a node's emptiness changes: a few nodes
//! however large the tree, with no allocation. A pixel's booleans
//! ([`crate::raytrace::csg::combine`] through [`Booleans`]) then visit only
//! the non-empty parts. Nested unions, intersections and cutters are merged
//! into their parents first (`(a − b) − c` is `a − b − c`, `a − (b ∪ c)` too),
//! so the lists are long and the tree shallow.

use crate::raytrace::csg::{Booleans, Operation};
use crate::scene::csg::CsgTree;

/// No node.
const NONE: u32 = u32::MAX;

/// The shape of a tree, flattened into arrays, ready to have its counts kept by
/// [`Occupied`].
#[derive(Debug, Clone)]
pub struct OccupancyTree {
    operation: Vec<Operation>,
    parent: Vec<u32>,
    /// Each node's operands: `operands[start[n]..start[n] + count[n]]`.
    start: Vec<u32>,
    count: Vec<u32>,
    operands: Vec<u32>,
    /// Per primitive, its first leaf; further leaves of the same primitive
    /// chain through `next_leaf`.
    first_leaf: Vec<u32>,
    next_leaf: Vec<u32>,
    root: u32,
}

impl OccupancyTree {
    /// The shape of `tree` over `primitives` primitives.
    #[must_use]
    pub fn new(tree: &CsgTree, primitives: usize) -> OccupancyTree {
        let mut t = OccupancyTree {
            operation: Vec::new(),
            parent: Vec::new(),
            start: Vec::new(),
            count: Vec::new(),
            operands: Vec::new(),
            first_leaf: vec![NONE; primitives],
            next_leaf: Vec::new(),
            root: 0,
        };
        t.root = t.add(tree, NONE);
        t
    }

    /// Adds `tree` under `parent`; returns its node.
    fn add(&mut self, tree: &CsgTree, parent: u32) -> u32 {
        let node = self.operation.len() as u32;
        let operation = tree.operation();
        self.operation.push(operation);
        self.parent.push(parent);
        self.next_leaf.push(NONE);
        if let Operation::Leaf(i) = operation {
            self.next_leaf[node as usize] = std::mem::replace(&mut self.first_leaf[i], node);
        }
        self.start.push(0);
        self.count.push(0);
        let mut kids = Vec::new();
        merged_operands(tree, &mut kids);
        let ids: Vec<u32> = kids.into_iter().map(|k| self.add(k, node)).collect();
        // After the subtrees: each node's operands lie together.
        self.start[node as usize] = self.operands.len() as u32;
        self.count[node as usize] = ids.len() as u32;
        self.operands.extend(ids);
        node
    }

    /// The nodes (for sizing [`Occupied`]).
    fn len(&self) -> usize {
        self.operation.len()
    }

    fn operands_of(&self, node: u32) -> &[u32] {
        let (s, c) = (self.start[node as usize] as usize, self.count[node as usize] as usize);
        &self.operands[s..s + c]
    }
}

/// The operands of `tree` with nested nodes of the same kind merged in: a
/// union's unions, an intersection's intersections, a difference's first
/// operand when it is itself a difference (`(a − b) − c`), and cutters that are
/// unions (`a − (b ∪ c)`).
fn merged_operands<'t>(tree: &'t CsgTree, out: &mut Vec<&'t CsgTree>) {
    let mut merge = |k: &'t CsgTree, same: bool| if same { merged_operands(k, out) } else { out.push(k) };
    match tree {
        CsgTree::Leaf(_) => {}
        CsgTree::Union(kids) => kids.iter().for_each(|k| merge(k, matches!(k, CsgTree::Union(_)))),
        CsgTree::Intersection(kids) => kids.iter().for_each(|k| merge(k, matches!(k, CsgTree::Intersection(_)))),
        CsgTree::Difference(a, cutters) => {
            merge(a, matches!(**a, CsgTree::Difference(..)));
            cutters.iter().for_each(|c| merge(c, matches!(c, CsgTree::Union(_))));
        }
    }
}

/// The counts of an [`OccupancyTree`] for the primitives occupying the
/// current pixel (all empty at first).
#[derive(Debug, Clone)]
pub struct Occupied<'t> {
    tree: &'t OccupancyTree,
    /// Per node: whether it is non-empty here.
    full: Vec<bool>,
    /// Per node: how many of its operands are non-empty (an intersection's RC),
    /// or, for unions and differences, how long its list is.
    live: Vec<u32>,
    /// The lists: node `n`'s non-empty operands (a difference: its cutters) in
    /// `list[start[n]..start[n] + live[n]]`.
    list: Vec<u32>,
    /// Per node: where it stands in its parent's list.
    place: Vec<u32>,
    /// Primitives occupying the pixel, to empty the tree quickly.
    present: Vec<u32>,
    is_present: Vec<bool>,
}

impl<'t> Occupied<'t> {
    /// Counts for `tree` with no primitive present.
    #[must_use]
    pub fn new(tree: &'t OccupancyTree) -> Occupied<'t> {
        let n = tree.len();
        Occupied {
            tree,
            full: vec![false; n],
            live: vec![0; n],
            list: vec![NONE; tree.operands.len()],
            place: vec![NONE; n],
            present: Vec::new(),
            is_present: vec![false; tree.first_leaf.len()],
        }
    }

    /// Primitive `i` starts (`on`) or stops occupying the pixel.
    pub fn set(&mut self, i: usize, on: bool) {
        if self.is_present[i] == on {
            return;
        }
        self.is_present[i] = on;
        if on {
            self.present.push(i as u32);
        } else if let Some(k) = self.present.iter().position(|&p| p == i as u32) {
            self.present.swap_remove(k);
        }
        let mut leaf = self.tree.first_leaf[i];
        while leaf != NONE {
            self.full[leaf as usize] = on;
            self.climb(leaf);
            leaf = self.tree.next_leaf[leaf as usize];
        }
    }

    /// Every primitive leaves.
    pub fn clear(&mut self) {
        while let Some(&i) = self.present.last() {
            self.set(i as usize, false);
        }
    }

    /// `node` just became full or empty: its parent's count or list follows,
    /// and so on up while a node's own emptiness changes.
    fn climb(&mut self, mut node: u32) {
        let t = self.tree;
        loop {
            let parent = t.parent[node as usize];
            if parent == NONE {
                return;
            }
            let p = parent as usize;
            let on = self.full[node as usize];
            let first = t.operands_of(parent)[0];
            let full = match t.operation[p] {
                Operation::Intersection => {
                    if on {
                        self.live[p] += 1;
                    } else {
                        self.live[p] -= 1;
                    }
                    self.live[p] == t.count[p]
                }
                Operation::Difference if node == first => on,
                op => {
                    self.listed(parent, node, on);
                    if op == Operation::Union {
                        self.live[p] > 0
                    } else {
                        self.full[first as usize]
                    }
                }
            };
            if full == self.full[p] {
                return;
            }
            self.full[p] = full;
            node = parent;
        }
    }

    /// Adds `node` to `parent`'s list or removes it.
    fn listed(&mut self, parent: u32, node: u32, on: bool) {
        let (p, start) = (parent as usize, self.tree.start[parent as usize] as usize);
        if on {
            self.place[node as usize] = self.live[p];
            self.list[start + self.live[p] as usize] = node;
            self.live[p] += 1;
        } else {
            let at = self.place[node as usize] as usize;
            self.live[p] -= 1;
            let last = self.list[start + self.live[p] as usize];
            self.list[start + at] = last;
            self.place[last as usize] = at as u32;
            self.place[node as usize] = NONE;
        }
    }

    /// The tree as the pixel sees it, `None` when it is empty here.
    #[must_use]
    pub fn root(&self) -> Option<OccupiedNode<'_>> {
        let root = self.tree.root;
        self.full[root as usize].then_some(OccupiedNode { occupied: self, node: root })
    }

    /// Whether the tree is non-empty here.
    #[must_use]
    pub fn is_full(&self) -> bool {
        self.full[self.tree.root as usize]
    }
}

/// A node of an [`Occupied`] tree, read by the span combiner: a union shows
/// its non-empty operands, a difference its first operand and non-empty
/// cutters, an intersection all its operands.
#[derive(Debug, Clone, Copy)]
pub struct OccupiedNode<'a> {
    occupied: &'a Occupied<'a>,
    node: u32,
}

impl<'a> Booleans for OccupiedNode<'a> {
    fn operation(self) -> Operation {
        self.occupied.tree.operation[self.node as usize]
    }

    fn operands(self) -> impl Iterator<Item = OccupiedNode<'a>> {
        let o = self.occupied;
        let t = o.tree;
        let n = self.node as usize;
        let listed = |start: usize| &o.list[start..start + o.live[n] as usize];
        let (first, rest): (Option<u32>, &[u32]) = match t.operation[n] {
            Operation::Leaf(_) => (None, &[]),
            Operation::Intersection => (None, t.operands_of(self.node)),
            Operation::Union => (None, listed(t.start[n] as usize)),
            Operation::Difference => (Some(t.operands_of(self.node)[0]), listed(t.start[n] as usize)),
        };
        first.into_iter().chain(rest.iter().copied()).map(move |node| OccupiedNode { occupied: o, node })
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use proptest::prelude::*;

    use super::*;
    use crate::raytrace::csg::{combine, Crossing, Span, SpanScratch};

    /// Random trees over primitives `0..n`, up to three levels deep.
    fn tree(n: usize) -> impl Strategy<Value = CsgTree> {
        let leaf = (0..n).prop_map(CsgTree::Leaf);
        leaf.prop_recursive(3, 24, 4, |inner| {
            prop_oneof![
                prop::collection::vec(inner.clone(), 1..4).prop_map(CsgTree::Union),
                prop::collection::vec(inner.clone(), 1..4).prop_map(CsgTree::Intersection),
                (inner.clone(), prop::collection::vec(inner, 1..4))
                    .prop_map(|(a, cut)| CsgTree::Difference(Box::new(a), cut)),
            ]
        })
    }

    /// Whether `tree` can be non-empty where only `on` primitives are present
    /// (the counts' meaning, stated recursively).
    fn non_empty(tree: &CsgTree, on: &[bool]) -> bool {
        match tree {
            CsgTree::Leaf(i) => on[*i],
            CsgTree::Union(k) => k.iter().any(|k| non_empty(k, on)),
            CsgTree::Intersection(k) => k.iter().all(|k| non_empty(k, on)),
            CsgTree::Difference(a, _) => non_empty(a, on),
        }
    }

    fn span(i: usize, t0: f32, t1: f32) -> Span {
        let at = |t| Crossing { t, normal: Vec3::Z, primitive: i as u32, cut: false };
        Span { enter: at(t0.min(t1)), exit: at(t0.max(t1) + 0.01) }
    }

    const N: usize = 8;

    proptest! {
        /// After every change of occupancy, the counts say what the tree
        /// says, and the booleans over the non-empty parts give the same spans
        /// as over the whole tree with absent primitives missed.
        #[test]
        fn counts_follow_the_tree(
            t in tree(N),
            ends in prop::collection::vec((0.0f32..10.0, 0.0f32..10.0), N),
            changes in prop::collection::vec((0..N, any::<bool>()), 1..40),
        ) {
            let shape = OccupancyTree::new(&t, N);
            let mut counts = Occupied::new(&shape);
            let mut on = [false; N];
            let spans: Vec<Span> = ends.iter().enumerate().map(|(i, &(a, b))| span(i, a, b)).collect();
            for (i, present) in changes {
                counts.set(i, present);
                on[i] = present;
                prop_assert_eq!(counts.is_full(), non_empty(&t, &on));
                let mut whole = SpanScratch::default();
                combine(&t, &|k| on[k].then_some(spans[k]), &mut whole);
                let mut seen = SpanScratch::default();
                if let Some(root) = counts.root() {
                    combine(root, &|k| {
                        assert!(on[k], "an absent primitive was read");
                        Some(spans[k])
                    }, &mut seen);
                }
                prop_assert_eq!(whole.spans(), seen.spans());
            }
            counts.clear();
            prop_assert!(!counts.is_full());
            prop_assert!(counts.full.iter().all(|f| !f) && counts.live.iter().all(|&l| l == 0));
        }
    }
}
