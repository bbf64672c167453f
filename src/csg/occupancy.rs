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
//! ([`crate::csg::combine`] through [`Booleans`]) then visit only
//! the non-empty parts. Nested unions, intersections and differences are
//! merged into their parents first (`(a − b) − c` is `a − b − c`), so the
//! lists are long and the tree shallow.

use crate::csg::{Booleans, CsgTree, Operation, Parts};

/// No node.
const NONE: u32 = u32::MAX;

/// One node of an [`OccupancyTree`].
#[derive(Debug, Clone, Copy)]
struct Node {
    operation: Operation,
    parent: u32,
    /// Its operands: `operands[start..start + count]` of the tree (a
    /// difference's first operand first).
    start: u32,
    count: u32,
}

/// The shape of a tree, flattened into arrays, ready to have its counts kept by
/// [`Occupied`].
#[derive(Debug, Clone)]
pub struct OccupancyTree {
    nodes: Vec<Node>,
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
            nodes: Vec::new(),
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
        let node = self.nodes.len() as u32;
        let operation = tree.parts().operation;
        self.nodes.push(Node { operation, parent, start: 0, count: 0 });
        self.next_leaf.push(NONE);
        if let Operation::Leaf(i) = operation {
            self.next_leaf[node as usize] = std::mem::replace(&mut self.first_leaf[i], node);
        }
        let mut kids = Vec::new();
        merged_operands(tree, &mut kids);
        let ids: Vec<u32> = kids.into_iter().map(|k| self.add(k, node)).collect();
        // After the subtrees: each node's operands lie together.
        let n = &mut self.nodes[node as usize];
        (n.start, n.count) = (self.operands.len() as u32, ids.len() as u32);
        self.operands.extend(ids);
        node
    }

    /// How many nodes the tree has.
    #[must_use]
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the tree is one primitive or a union of primitives: the
    /// booleans then read each occupant once, on its own, and nothing cuts,
    /// clips or merges.
    #[must_use]
    pub fn is_union_of_leaves(&self) -> bool {
        let root = &self.nodes[self.root as usize];
        let leaf = |k: &u32| matches!(self.nodes[*k as usize].operation, Operation::Leaf(_));
        match root.operation {
            Operation::Leaf(_) => true,
            Operation::Union => self.operands_of(root).iter().all(leaf),
            _ => false,
        }
    }

    fn operands_of(&self, node: &Node) -> &[u32] {
        &self.operands[node.start as usize..(node.start + node.count) as usize]
    }
}

/// The part each cutting primitive cuts (`cut_region.rs` keeps a cutter
/// to where in space it meets it): per primitive that lies under a cutter of
/// a difference (the nearest such), the primitives of that difference's
/// first operand, its body. A difference's set lies within its body's
/// primitives, and such a primitive changes the set of the cutters it lies
/// under only within itself (widened by [`crate::csg::TIE`]):
/// where the two do not meet, it changes nothing of the solid.
#[derive(Debug, Clone, Default)]
pub struct CutterBodies {
    /// Per primitive: its body (an index into `bodies`), or none.
    body: Vec<u32>,
    /// Per body: its primitives, `primitives[start..end]`.
    bodies: Vec<(u32, u32)>,
    primitives: Vec<u32>,
}

impl CutterBodies {
    /// The bodies of `tree`'s cutting primitives (a primitive with more
    /// than one leaf has none).
    #[must_use]
    pub fn new(tree: &OccupancyTree) -> CutterBodies {
        let mut table = CutterBodies { body: vec![NONE; tree.first_leaf.len()], ..CutterBodies::default() };
        let mut by_node = vec![NONE; tree.nodes.len()];
        for (i, &leaf) in tree.first_leaf.iter().enumerate() {
            if leaf == NONE || tree.next_leaf[leaf as usize] != NONE {
                continue;
            }
            let Some(difference) = tree.cutting(leaf) else { continue };
            if by_node[difference as usize] == NONE {
                by_node[difference as usize] = table.bodies.len() as u32;
                let start = table.primitives.len() as u32;
                let body = tree.operands[tree.nodes[difference as usize].start as usize];
                tree.leaves_under(body, &mut table.primitives);
                table.bodies.push((start, table.primitives.len() as u32));
            }
            table.body[i] = by_node[difference as usize];
        }
        table
    }

    /// Primitive `i`'s body, if it cuts.
    #[inline]
    #[must_use]
    pub fn body_of(&self, i: usize) -> Option<usize> {
        let b = *self.body.get(i)?;
        (b != NONE).then_some(b as usize)
    }

    /// The primitives of body `b`.
    #[inline]
    #[must_use]
    pub fn primitives(&self, b: usize) -> &[u32] {
        let (start, end) = self.bodies[b];
        &self.primitives[start as usize..end as usize]
    }
}

impl OccupancyTree {
    /// The nearest difference above `node` that it lies under a cutter of.
    fn cutting(&self, mut node: u32) -> Option<u32> {
        loop {
            let parent = self.nodes[node as usize].parent;
            if parent == NONE {
                return None;
            }
            let p = &self.nodes[parent as usize];
            if p.operation == Operation::Difference && self.operands[p.start as usize] != node {
                return Some(parent);
            }
            node = parent;
        }
    }

    /// The primitives of the leaves under `node`, into `out`.
    fn leaves_under(&self, node: u32, out: &mut Vec<u32>) {
        let n = &self.nodes[node as usize];
        if let Operation::Leaf(i) = n.operation {
            out.push(i as u32);
        }
        for &k in self.operands_of(n) {
            self.leaves_under(k, out);
        }
    }
}

/// The operands of `tree` with nested nodes of the same kind merged in: a
/// union's unions, an intersection's intersections, and a difference's first
/// operand when it is itself a difference (`(a − b) − c`).
fn merged_operands<'t>(tree: &'t CsgTree, out: &mut Vec<&'t CsgTree>) {
    let mut merge = |k: &'t CsgTree, same: bool| if same { merged_operands(k, out) } else { out.push(k) };
    match tree {
        CsgTree::Leaf(_) => {}
        CsgTree::Union(kids) => kids.iter().for_each(|k| merge(k, matches!(k, CsgTree::Union(_)))),
        CsgTree::Intersection(kids) => kids.iter().for_each(|k| merge(k, matches!(k, CsgTree::Intersection(_)))),
        CsgTree::Difference(a, cutters) => {
            merge(a, matches!(**a, CsgTree::Difference(..)));
            // A union of cutters stays one operand: its spans are merged once
            // and cut out in one pass, where cutting them one by one would
            // walk the ever more fragmented remainder once per cutter.
            cutters.iter().for_each(|c| out.push(c));
        }
    }
}

/// A set of ids below a bound, listed, with each id's place in the list, so
/// an id joins or leaves in constant time (the visible-segment list of seed
/// 003 §5.2.1; the primitives present in [`Occupied`]).
#[derive(Debug, Clone, Default)]
pub struct PlacedSet {
    list: Vec<u32>,
    place: Vec<u32>,
}

impl PlacedSet {
    /// An empty set of ids below `n`.
    #[must_use]
    pub fn new(n: usize) -> Self {
        PlacedSet { list: Vec::new(), place: vec![NONE; n] }
    }

    /// Takes ids below `n` (only while empty).
    fn resize(&mut self, n: usize) {
        debug_assert!(self.list.is_empty(), "resized while holding ids");
        self.place.resize(n, NONE);
    }

    /// Whether `id` is in the set.
    #[must_use]
    pub fn contains(&self, id: usize) -> bool {
        self.place[id] != NONE
    }

    /// Adds `id` (not in the set).
    pub fn insert(&mut self, id: usize) {
        self.place[id] = self.list.len() as u32;
        self.list.push(id as u32);
    }

    /// Removes `id` (in the set).
    pub fn remove(&mut self, id: usize) {
        let k = self.place[id] as usize;
        self.list.swap_remove(k);
        if let Some(&moved) = self.list.get(k) {
            self.place[moved as usize] = k as u32;
        }
        self.place[id] = NONE;
    }

    /// Where `id` stands in [`PlacedSet::ids`] (`None` when not in the set).
    #[must_use]
    pub fn place(&self, id: usize) -> Option<usize> {
        let k = self.place[id];
        (k != NONE).then_some(k as usize)
    }

    /// The ids, in no particular order.
    #[must_use]
    pub fn ids(&self) -> &[u32] {
        &self.list
    }
}

/// The counts of an [`OccupancyTree`] for the primitives occupying the
/// current pixel (all empty at first). Kept apart from the tree, so one set of
/// buffers serves every tree a thread meets ([`Occupied::fit`]); each call
/// names the tree.
#[derive(Debug, Clone, Default)]
pub struct Occupied {
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
    present: PlacedSet,
}

impl Occupied {
    /// Counts for `tree` with no primitive present.
    #[cfg(test)]
    #[must_use]
    pub fn new(tree: &OccupancyTree) -> Occupied {
        let mut counts = Occupied::default();
        counts.fit(tree);
        counts
    }

    /// Sizes empty counts for `tree` (they stay empty).
    pub fn fit(&mut self, tree: &OccupancyTree) {
        let n = tree.len();
        self.full.resize(n, false);
        self.live.resize(n, 0);
        self.place.resize(n, NONE);
        self.list.resize(tree.operands.len(), NONE);
        self.present.resize(tree.first_leaf.len());
    }

    /// Primitive `i` starts (`on`) or stops occupying the pixel.
    pub fn set(&mut self, tree: &OccupancyTree, i: usize, on: bool) {
        if self.present.contains(i) == on {
            return;
        }
        if on {
            self.present.insert(i);
        } else {
            self.present.remove(i);
        }
        let mut leaf = tree.first_leaf[i];
        while leaf != NONE {
            self.full[leaf as usize] = on;
            self.climb(tree, leaf);
            leaf = tree.next_leaf[leaf as usize];
        }
    }

    /// The primitives present (occupying the pixel), each with its place in
    /// the list.
    #[must_use]
    pub fn present(&self) -> &PlacedSet {
        &self.present
    }

    /// Every primitive leaves.
    pub fn clear(&mut self, tree: &OccupancyTree) {
        while let Some(&i) = self.present.ids().last() {
            self.set(tree, i as usize, false);
        }
    }

    /// `node` just became full or empty: its parent's count or list follows,
    /// and so on up while a node's own emptiness changes.
    fn climb(&mut self, t: &OccupancyTree, mut node: u32) {
        loop {
            let parent = t.nodes[node as usize].parent;
            if parent == NONE {
                return;
            }
            let (p, pn) = (parent as usize, t.nodes[parent as usize]);
            let on = self.full[node as usize];
            let first = t.operands[pn.start as usize];
            let full = match pn.operation {
                Operation::Intersection => {
                    if on {
                        self.live[p] += 1;
                    } else {
                        self.live[p] -= 1;
                    }
                    self.live[p] == pn.count
                }
                Operation::Difference if node == first => on,
                op => {
                    self.listed(pn.start as usize, p, node, on);
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

    /// Adds `node` to the list of node `p` (which starts at `start`) or
    /// removes it.
    fn listed(&mut self, start: usize, p: usize, node: u32, on: bool) {
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

    /// `tree` as the pixel sees it, `None` when it is empty here.
    #[must_use]
    pub fn root<'a>(&'a self, tree: &'a OccupancyTree) -> Option<OccupiedNode<'a>> {
        let node = tree.root;
        self.full[node as usize].then_some(OccupiedNode { tree, counts: self, node })
    }

    /// Whether `tree` is non-empty here.
    #[cfg(test)]
    #[must_use]
    pub fn is_full(&self, tree: &OccupancyTree) -> bool {
        self.full[tree.root as usize]
    }
}

/// A node of an [`Occupied`] tree, read by the span combiner: a union shows
/// its non-empty operands, a difference its first operand and non-empty
/// cutters, an intersection all its operands.
#[derive(Debug, Clone, Copy)]
pub struct OccupiedNode<'a> {
    tree: &'a OccupancyTree,
    counts: &'a Occupied,
    node: u32,
}

impl<'a> Booleans for OccupiedNode<'a> {
    #[inline(always)]
    fn parts(self) -> Parts<Self, impl Iterator<Item = Self> + Clone> {
        let (t, c, n) = (self.tree, self.counts, self.node as usize);
        let node = t.nodes[n];
        let start = node.start as usize;
        let listed = || &c.list[start..start + c.live[n] as usize];
        let (first, others) = match node.operation {
            Operation::Leaf(_) => (None, &[][..]),
            Operation::Intersection => match t.operands_of(&node).split_first() {
                Some((&first, others)) => (Some(first), others),
                None => (None, &[][..]),
            },
            Operation::Union => (None, listed()),
            Operation::Difference => (Some(t.operands[start]), listed()),
        };
        let at = move |node| OccupiedNode { tree: t, counts: c, node };
        Parts { operation: node.operation, first: first.map(at), others: others.iter().map(move |&n| at(n)) }
    }

    #[inline(always)]
    fn leaf(self) -> Option<usize> {
        match self.tree.nodes[self.node as usize].operation {
            Operation::Leaf(i) => Some(i),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{Affine3A, Vec3};
    use proptest::prelude::*;

    use super::*;
    use crate::csg::{combine, CsgCaster, Interval, SpanScratch};
    use crate::csg::{random_tree, ConvexPolyhedron, CsgSolid, Primitive, Shape};

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

    /// Primitive `i`'s interval along a ray down the z axis: a unit cube
    /// stretched over `t0..t1` (and a hair), as a caster finds it.
    fn span(i: usize, t0: f32, t1: f32) -> Interval {
        let (lo, hi) = (t0.min(t1), t0.max(t1) + 0.01);
        let cube =
            Affine3A::from_translation(Vec3::new(-0.5, -0.5, lo)) * Affine3A::from_scale(Vec3::new(1.0, 1.0, hi - lo));
        let primitives = (0..=i)
            .map(|_| Primitive {
                shape: Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
                transform: cube,
                color: None,
                source: 0..0,
            })
            .collect();
        let caster = CsgCaster::new(&CsgSolid { primitives, tree: Some(CsgTree::Leaf(i)) });
        caster
            .interval(i, &crate::camera::Ray { origin: Vec3::ZERO, dir: Vec3::Z })
            .expect("the ray runs through the cube")
    }

    const N: usize = 8;

    proptest! {
        /// After every change of occupancy, the counts say what the tree
        /// says, and the booleans over the non-empty parts give the same spans
        /// as over the whole tree with absent primitives missed.
        #[test]
        fn counts_follow_the_tree(
            t in random_tree(N, 3),
            ends in prop::collection::vec((0.0f32..10.0, 0.0f32..10.0), N),
            changes in prop::collection::vec((0..N, any::<bool>()), 1..40),
        ) {
            let shape = OccupancyTree::new(&t, N);
            let mut counts = Occupied::new(&shape);
            let mut on = [false; N];
            let spans: Vec<Interval> = ends.iter().enumerate().map(|(i, &(a, b))| span(i, a, b)).collect();
            for (i, present) in changes {
                counts.set(&shape, i, present);
                on[i] = present;
                prop_assert_eq!(counts.is_full(&shape), non_empty(&t, &on));
                let mut whole = SpanScratch::default();
                combine(&t, &|k: usize| on[k].then_some(spans[k]), &mut whole);
                let mut seen = SpanScratch::default();
                if let Some(root) = counts.root(&shape) {
                    combine(root, &|k: usize| {
                        assert!(on[k], "an absent primitive was read");
                        Some(spans[k])
                    }, &mut seen);
                }
                prop_assert_eq!(whole.spans(), seen.spans());
            }
            counts.clear(&shape);
            prop_assert!(!counts.is_full(&shape));
            prop_assert!(counts.full.iter().all(|f| !f) && counts.live.iter().all(|&l| l == 0));
        }
    }
}
