//! The build: a binary tree by the binned surface-area heuristic, collapsed
//! to eight children a node and flattened depth first (the module above says
//! why and how fast).

use glam::{Vec3A, Vec4};
use rayon::prelude::*;

use super::{Aabb, Bvh, Node, WIDTH};

const BINS: usize = 16;
/// Primitives a leaf holds at most by default ([`Bvh::build`]).
const LEAF_MAX: usize = 4;
/// Triangles a leaf of [`Bvh::build_lanes`] holds at most: as many as one
/// eight-lane test takes.
const LEAF_LANES: usize = crate::triangle::LANES;
const PARALLEL_BELOW: usize = 4096;
/// Nodes larger than this scan their items in parallel.
const PARALLEL_SCAN: usize = 1 << 16;
/// Subtrees over more items than this are flattened in parallel.
const PARALLEL_FLATTEN: usize = 1 << 15;

/// A box in 16-byte SIMD vectors, for the build: whole-vector loads and stores
/// (a `Vec3` box is stored with masked moves, which stall the binning loop).
#[derive(Debug, Clone, Copy)]
struct Box3A {
    min: Vec3A,
    max: Vec3A,
}

impl Box3A {
    const EMPTY: Box3A = Box3A { min: Vec3A::INFINITY, max: Vec3A::NEG_INFINITY };

    #[inline(always)]
    fn union(self, o: Box3A) -> Box3A {
        Box3A { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    #[inline(always)]
    fn grow(self, p: Vec3A) -> Box3A {
        Box3A { min: self.min.min(p), max: self.max.max(p) }
    }

    fn area(self) -> f32 {
        let d = (self.max - self.min).max(Vec3A::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
}

/// A primitive in the build: its box in two 16-byte vectors (32 bytes, half
/// of a box, a centre and an index stored apart: the partitions move half the
/// memory). The index rides in the fourth lanes, its high and low 16 bits as
/// small whole numbers (exact, and never subnormal in the vector arithmetic).
#[derive(Debug, Clone, Copy)]
struct Item {
    min: Vec4,
    max: Vec4,
}

impl Item {
    fn new(index: u32, b: &Aabb) -> Item {
        Item { min: b.min.extend((index >> 16) as f32), max: b.max.extend((index & 0xffff) as f32) }
    }

    #[inline(always)]
    fn bounds(&self) -> Box3A {
        Box3A { min: Vec3A::from_vec4(self.min), max: Vec3A::from_vec4(self.max) }
    }

    #[inline(always)]
    fn centre(&self) -> Vec3A {
        (Vec3A::from_vec4(self.min) + Vec3A::from_vec4(self.max)) * 0.5
    }

    fn index(&self) -> u32 {
        ((self.min.w as u32) << 16) | self.max.w as u32
    }
}

/// Items' bounds and the bounds of their centres: what a node's split needs,
/// handed down from its parent's bins.
#[derive(Debug, Clone, Copy)]
struct Extents {
    bounds: Box3A,
    centres: Box3A,
}

impl Extents {
    const EMPTY: Extents = Extents { bounds: Box3A::EMPTY, centres: Box3A::EMPTY };

    #[inline(always)]
    fn add(self, item: &Item) -> Extents {
        Extents { bounds: self.bounds.union(item.bounds()), centres: self.centres.grow(item.centre()) }
    }

    fn union(self, o: Extents) -> Extents {
        Extents { bounds: self.bounds.union(o.bounds), centres: self.centres.union(o.centres) }
    }
}

enum BuildNode {
    Leaf { bounds: Box3A, start: usize, count: usize },
    Interior { bounds: Box3A, count: usize, children: Box<[BuildNode; 2]> },
}

impl Bvh {
    /// Builds the hierarchy over primitives with these boxes (parallel for large
    /// inputs).
    #[must_use]
    pub fn build(bounds: &[Aabb]) -> Bvh {
        Bvh::build_with(bounds.len(), LEAF_MAX, |i| bounds[i])
    }

    /// [`Bvh::build`] over `len` primitives whose leaves are tested eight at a
    /// time (triangles in lanes): leaves of up to eight, primitive `i`'s box
    /// being `bounds(i)` (asked once each, in parallel: no list of boxes is
    /// kept). A leaf of eight costs one eight-lane test, as a leaf of four
    /// does; the tree has a level less. On the spheres of `kage-bench rays`
    /// (2 threads, one run) the 998k-triangle build takes 142–149 ms instead
    /// of 182–189, at the same ray rates (packets 28–29 against 25–28
    /// Mrays/s).
    ///
    /// # Panics
    /// If `len` exceeds `u32::MAX`.
    #[must_use]
    pub fn build_lanes(len: usize, bounds: impl Fn(usize) -> Aabb + Sync) -> Bvh {
        Bvh::build_with(len, LEAF_LANES, bounds)
    }

    /// The build, with leaves of up to `leaf_max` primitives where the SAH
    /// finds no cheaper split.
    fn build_with(len: usize, leaf_max: usize, bounds: impl Fn(usize) -> Aabb + Sync) -> Bvh {
        assert!(u32::try_from(len).is_ok(), "{len} primitives: at most u32::MAX");
        if len == 0 {
            return Bvh { nodes: Vec::new(), order: Vec::new() };
        }
        let item = |i: usize| Item::new(i as u32, &bounds(i));
        let mut items: Vec<Item> = (0..len).into_par_iter().with_min_len(1 << 12).map(item).collect();
        let extents = extents(&items);
        let root = build_node(&mut items, 0, extents, leaf_max);
        let order = items.par_iter().map(Item::index).collect();
        let nodes = flatten_parallel(&root);
        rayon::spawn(move || drop(root)); // a tree of boxes freed off the caller's path
        Bvh { nodes, order }
    }
}

fn build_node(items: &mut [Item], start: usize, extents: Extents, leaf_max: usize) -> BuildNode {
    let Extents { bounds, centres } = extents;
    let count = items.len();
    if count <= leaf_max {
        return BuildNode::Leaf { bounds, start, count };
    }
    let axis = (centres.max - centres.min).max_position();
    let extent = centres.max[axis] - centres.min[axis];
    let (mid, left, right) =
        match (extent > 0.0).then(|| best_split(items, axis, centres.min[axis], extent, bounds, leaf_max)).flatten() {
            Some(split) => {
                let mid = partition(items, |i| bin_of(i.centre()[axis], centres.min[axis], extent) <= split.bin);
                (mid, split.left, split.right)
            }
            None if count <= 255 => return BuildNode::Leaf { bounds, start, count },
            None => {
                items.sort_unstable_by(|a, b| a.centre()[axis].total_cmp(&b.centre()[axis]));
                let mid = count / 2;
                (mid, self::extents(&items[..mid]), self::extents(&items[mid..]))
            }
        };
    let (l, r) = items.split_at_mut(mid);
    let (a, b) = if count > PARALLEL_BELOW {
        rayon::join(|| build_node(l, start, left, leaf_max), || build_node(r, start + mid, right, leaf_max))
    } else {
        (build_node(l, start, left, leaf_max), build_node(r, start + mid, right, leaf_max))
    };
    BuildNode::Interior { bounds, count, children: Box::new([a, b]) }
}

/// The items' extents (in parallel for large nodes: near the root, one node
/// holds all the work).
fn extents(items: &[Item]) -> Extents {
    let scan = |items: &[Item]| items.iter().fold(Extents::EMPTY, Extents::add);
    if items.len() > PARALLEL_SCAN {
        items.par_chunks(PARALLEL_SCAN / 4).map(scan).reduce(|| Extents::EMPTY, Extents::union)
    } else {
        scan(items)
    }
}

fn bin_of(c: f32, min: f32, extent: f32) -> usize {
    (((c - min) * (BINS as f32 / extent)) as usize).min(BINS - 1)
}

/// The cheapest SAH split of a node.
struct Split {
    /// The left side's last bin.
    bin: usize,
    /// Each side's extents.
    left: Extents,
    right: Extents,
}

/// The cheapest SAH split, or `None` if making a leaf is cheaper (or nothing
/// separates).
fn best_split(items: &[Item], axis: usize, min: f32, extent: f32, bounds: Box3A, leaf_max: usize) -> Option<Split> {
    type Bins = [(Extents, usize); BINS];
    let fill = |items: &[Item]| {
        let mut bins: Bins = [(Extents::EMPTY, 0); BINS];
        for i in items {
            let b = &mut bins[bin_of(i.centre()[axis], min, extent)];
            *b = (b.0.add(i), b.1 + 1);
        }
        bins
    };
    let bins = if items.len() > PARALLEL_SCAN {
        let merge = |mut a: Bins, b: Bins| {
            a.iter_mut().zip(b).for_each(|(x, y)| *x = (x.0.union(y.0), x.1 + y.1));
            a
        };
        items.par_chunks(PARALLEL_SCAN / 4).map(fill).reduce(|| [(Extents::EMPTY, 0); BINS], merge)
    } else {
        fill(items)
    };
    let mut right = [(Extents::EMPTY, 0usize); BINS];
    let mut acc = (Extents::EMPTY, 0);
    for k in (1..BINS).rev() {
        acc = (acc.0.union(bins[k].0), acc.1 + bins[k].1);
        right[k] = acc;
    }
    let mut left = (Extents::EMPTY, 0);
    let mut best: Option<(f32, Split)> = None;
    for k in 0..BINS - 1 {
        left = (left.0.union(bins[k].0), left.1 + bins[k].1);
        let (r, rn) = right[k + 1];
        if left.1 == 0 || rn == 0 {
            continue;
        }
        let cost = 0.125
            + (left.0.bounds.area() * left.1 as f32 + r.bounds.area() * rn as f32)
                / bounds.area().max(f32::MIN_POSITIVE);
        if best.as_ref().is_none_or(|(c, _)| cost < *c) {
            best = Some((cost, Split { bin: k, left: left.0, right: r }));
        }
    }
    let (cost, split) = best?;
    (items.len() > leaf_max * 16 || cost < items.len() as f32).then_some(split)
}

/// Moves the items for which `left` holds to the front; returns how many.
fn partition(items: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..items.len() {
        if left(&items[i]) {
            items.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

/// A binary node's children in its eight-wide node: found by opening, while
/// fewer than eight, the interior child of largest surface area (the binary
/// tree collapsed, as Embree's BVH8 builder does).
fn wide_children(node: &BuildNode) -> Vec<&BuildNode> {
    // Each kid with its area if interior (a leaf is never opened).
    fn entry(n: &BuildNode) -> (f32, &BuildNode) {
        match n {
            BuildNode::Leaf { .. } => (f32::NEG_INFINITY, n),
            BuildNode::Interior { bounds, .. } => (bounds.area(), n),
        }
    }
    let mut kids = Vec::with_capacity(WIDTH);
    kids.push(entry(node));
    while kids.len() < WIDTH {
        let (k, &(area, widest)) =
            kids.iter().enumerate().max_by(|a, b| a.1 .0.total_cmp(&b.1 .0)).expect("a kid at least");
        let BuildNode::Interior { children, .. } = widest else { break };
        debug_assert!(area > f32::NEG_INFINITY);
        kids[k] = entry(&children[0]);
        kids.insert(k + 1, entry(&children[1]));
    }
    kids.into_iter().map(|(_, n)| n).collect()
}

/// The eight-wide node over `kids`; `interior(k, kid)` gives an interior
/// child's node index.
fn wide_node<'a>(kids: &[&'a BuildNode], mut interior: impl FnMut(usize, &'a BuildNode) -> u32) -> Node {
    let mut wide = Node::EMPTY;
    wide.children = kids.len() as u8;
    for (k, &kid) in kids.iter().enumerate() {
        let b = kid.bounds();
        let corners = [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z];
        corners.iter().zip(&mut wide.bounds).for_each(|(&v, axis)| axis[k] = v);
        (wide.child[k], wide.count[k]) = match *kid {
            BuildNode::Leaf { start, count, .. } => {
                debug_assert!((1..=255).contains(&count), "leaves hold 1 to 255 primitives");
                (start as u32, count as u8)
            }
            BuildNode::Interior { .. } => (interior(k, kid), 0),
        };
    }
    wide
}

/// Writes `node` and its subtree as eight-wide nodes, depth first; returns its
/// index.
fn flatten(node: &BuildNode, out: &mut Vec<Node>) -> u32 {
    let at = out.len();
    out.push(Node::EMPTY);
    out[at] = wide_node(&wide_children(node), |_, kid| flatten(kid, out));
    at as u32
}

/// [`flatten`] into a vector of its own, large subtrees in parallel (each
/// flattened apart, then moved behind its parent with its node indices
/// shifted): the same nodes in the same order.
fn flatten_parallel(node: &BuildNode) -> Vec<Node> {
    let mut out = Vec::with_capacity(node.count() / 8 + 1);
    if node.count() <= PARALLEL_FLATTEN {
        flatten(node, &mut out);
        return out;
    }
    let kids = wide_children(node);
    let interior = |kid: &&BuildNode| matches!(kid, BuildNode::Interior { .. });
    let mut subtrees: Vec<Option<Vec<Node>>> =
        kids.par_iter().map(|kid| interior(kid).then(|| flatten_parallel(kid))).collect();
    out.push(Node::EMPTY);
    out[0] = wide_node(&kids, |k, _| {
        let mut sub = subtrees[k].take().expect("an interior child's subtree");
        let offset = out.len() as u32;
        for n in &mut sub {
            for c in 0..usize::from(n.children) {
                if n.count[c] == 0 {
                    n.child[c] += offset;
                }
            }
        }
        out.extend(sub);
        offset
    });
    out
}

impl BuildNode {
    fn bounds(&self) -> Box3A {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => *bounds,
        }
    }

    fn count(&self) -> usize {
        match self {
            BuildNode::Leaf { count, .. } | BuildNode::Interior { count, .. } => *count,
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    use super::*;

    /// An item gives back any index it was made with (its two halves ride
    /// in the boxes' fourth lanes).
    #[test]
    fn an_item_keeps_its_index() {
        let b = Aabb { min: Vec3::splat(-1.0), max: Vec3::ONE };
        for i in [0, 1, 65_535, 65_536, 65_537, 1_000_003, 0x1234_5678, u32::MAX - 1, u32::MAX] {
            let item = Item::new(i, &b);
            assert_eq!(item.index(), i);
            assert_eq!((Vec3::from(item.bounds().min), Vec3::from(item.bounds().max)), (b.min, b.max));
        }
    }

    fn random_boxes(n: usize, seed: u64) -> Vec<Aabb> {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut r = || rng.gen_range(-1.0f32..1.0);
        (0..n)
            .map(|_| {
                let p = Vec3::new(r(), r(), r()) * 10.0;
                Aabb { min: p, max: p + Vec3::new(r().abs(), r().abs(), r().abs()) * 0.2 }
            })
            .collect()
    }

    /// Every node of the binary tree holds the bounds of its own items, and
    /// its children split its items: the extents each split hands down from
    /// its bins are those a scan of the items finds.
    #[test]
    fn handed_down_extents_are_the_items_extents() {
        fn check(node: &BuildNode, items: &[Item]) -> usize {
            let (start, count) = match node {
                BuildNode::Leaf { start, count, .. } => (*start, *count),
                BuildNode::Interior { children, count, .. } => {
                    let left = check(&children[0], items);
                    assert_eq!(left + check(&children[1], items), *count);
                    (first_item(node), *count)
                }
            };
            let scanned = extents(&items[start..start + count]).bounds;
            let b = node.bounds();
            assert_eq!((Vec3::from(b.min), Vec3::from(b.max)), (Vec3::from(scanned.min), Vec3::from(scanned.max)));
            count
        }
        fn first_item(node: &BuildNode) -> usize {
            match node {
                BuildNode::Leaf { start, .. } => *start,
                BuildNode::Interior { children, .. } => first_item(&children[0]),
            }
        }
        let boxes = random_boxes(20_000, 5);
        let mut items: Vec<Item> = boxes.iter().enumerate().map(|(i, b)| Item::new(i as u32, b)).collect();
        let all = extents(&items);
        let root = build_node(&mut items, 0, all, LEAF_MAX);
        assert_eq!(check(&root, &items), boxes.len());
    }

    /// A tree flattened in parallel (large subtrees apart, then joined) is
    /// the tree flattened depth first by one thread, node for node.
    #[test]
    fn a_tree_flattened_in_parallel_is_the_serial_one() {
        let boxes = random_boxes(4 * PARALLEL_FLATTEN, 9);
        let mut items: Vec<Item> = boxes.iter().enumerate().map(|(i, b)| Item::new(i as u32, b)).collect();
        let all = extents(&items);
        let root = build_node(&mut items, 0, all, LEAF_MAX);
        let mut serial = Vec::new();
        flatten(&root, &mut serial);
        let parallel = flatten_parallel(&root);
        let key = |n: &Node| (n.bounds.map(|a| a.map(f32::to_bits)), n.child, n.count, n.children);
        assert!(serial.len() > 1000);
        assert_eq!(serial.iter().map(key).collect::<Vec<_>>(), parallel.iter().map(key).collect::<Vec<_>>());
    }
}
