//! Bounding volume hierarchy over boxes: binned surface-area-heuristic build (as
//! pbrt-v4's `BVHAggregate`, 16 bins), flattened depth-first, traversed near child
//! first.
//!
//! The hierarchy knows only boxes. Traversal hands each leaf to a closure that
//! intersects it, so one walker serves the scene's triangles and solids (ray
//! tracing) and a solid's primitives (CSG casting).

use glam::{Vec3, Vec3A};
use rayon::prelude::*;

use crate::camera::Ray;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (the identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    /// The box around `points`.
    #[must_use]
    pub fn around(points: &[Vec3]) -> Aabb {
        points.iter().fold(Aabb::EMPTY, |b, &p| Aabb { min: b.min.min(p), max: b.max.max(p) })
    }

    /// The box around both.
    #[must_use]
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    /// Surface area (0 for the empty box).
    #[must_use]
    pub fn area(self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// Centre.
    #[must_use]
    pub fn centre(self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
}

/// A node of the flattened tree. Its box is kept in 16-byte SIMD vectors, so
/// the slab test is a handful of vector instructions.
#[derive(Debug, Clone, Copy)]
struct Node {
    min: Vec3A,
    max: Vec3A,
    /// Leaf: first index into `order`; interior: index of the second child (the
    /// first child follows its parent).
    offset: u32,
    /// Primitives in a leaf; 0 for interior nodes.
    count: u16,
}

impl Node {
    fn new(b: &Box3A, offset: u32, count: u16) -> Node {
        Node { min: b.min, max: b.max, offset, count }
    }

    /// Entry distance of the ray (given as origin and 1/direction) if it meets the
    /// box before `t_max` (slab test; the far distance is widened by a few ulps so
    /// a ray grazing a face is not lost to rounding).
    #[inline(always)]
    fn entry(&self, origin: Vec3A, inv_dir: Vec3A, t_max: f32) -> Option<f32> {
        let t0 = (self.min - origin) * inv_dir;
        let t1 = (self.max - origin) * inv_dir;
        let near = t0.min(t1).max_element().max(0.0);
        let far = t0.max(t1).min_element() * (1.0 + 2.0 * f32::EPSILON * 2.0);
        (near <= far && near < t_max).then_some(near)
    }
}

/// A bounding volume hierarchy over primitives known by their boxes.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

const BINS: usize = 16;
const LEAF_MAX: usize = 4;
const PARALLEL_BELOW: usize = 4096;
/// Nodes larger than this scan their items in parallel.
const PARALLEL_SCAN: usize = 1 << 16;

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

struct Item {
    bounds: Box3A,
    centre: Vec3A,
    index: u32,
}

enum BuildNode {
    Leaf { bounds: Box3A, start: usize, count: usize },
    Interior { bounds: Box3A, children: Box<[BuildNode; 2]> },
}

impl Bvh {
    /// Builds the hierarchy over primitives with these boxes (parallel for large
    /// inputs).
    #[must_use]
    pub fn build(bounds: &[Aabb]) -> Bvh {
        let item = |(i, b): (usize, &Aabb)| {
            let bounds = Box3A { min: b.min.into(), max: b.max.into() };
            Item { bounds, centre: (bounds.min + bounds.max) * 0.5, index: i as u32 }
        };
        let mut items: Vec<Item> = bounds.iter().enumerate().map(item).collect();
        if items.is_empty() {
            return Bvh { nodes: Vec::new(), order: Vec::new() };
        }
        let root = build_node(&mut items, 0);
        let order = items.iter().map(|i| i.index).collect();
        let mut nodes = Vec::with_capacity(2 * bounds.len() / LEAF_MAX + 1);
        flatten(&root, &mut nodes);
        Bvh { nodes, order }
    }

    /// The nearest primitive along `ray` before `t_max`: `hit(i, t_max)` intersects
    /// primitive `i` and returns its distance if nearer than `t_max`. Returns the
    /// primitive and distance.
    pub fn intersect(
        &self,
        ray: &Ray,
        mut t_max: f32,
        mut hit: impl FnMut(u32, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        let mut best = None;
        self.walk(ray, &mut t_max, |i, t_max| {
            if let Some(t) = hit(i, *t_max) {
                *t_max = t;
                best = Some((i, t));
            }
            false
        });
        best
    }

    /// Whether any primitive blocks `ray` before `t_max` (stops at the first).
    pub fn occluded(&self, ray: &Ray, mut t_max: f32, mut hit: impl FnMut(u32, f32) -> Option<f32>) -> bool {
        let mut any = false;
        self.walk(ray, &mut t_max, |i, t_max| {
            any = hit(i, *t_max).is_some();
            any
        });
        any
    }

    /// Visits the leaves the ray reaches, nearer child first (by entry distance);
    /// `visit` returns true to stop. A postponed child is skipped when the ray has
    /// since found a hit nearer than its box.
    fn walk(&self, ray: &Ray, t_max: &mut f32, mut visit: impl FnMut(u32, &mut f32) -> bool) {
        let inv = ray.dir.recip();
        let (origin, inv) = (Vec3A::from(ray.origin), Vec3A::from(inv));
        let entry = |i: usize, t_max: f32| self.nodes[i].entry(origin, inv, t_max);
        if self.nodes.is_empty() || entry(0, *t_max).is_none() {
            return;
        }
        let mut stack = [(0u32, 0.0f32); 64];
        let mut depth = 0;
        let mut at = 0usize;
        loop {
            let node = &self.nodes[at];
            if node.count > 0 {
                let first = node.offset as usize;
                for &i in &self.order[first..first + node.count as usize] {
                    if visit(i, t_max) {
                        return;
                    }
                }
            } else {
                let (a, b) = (at + 1, node.offset as usize);
                match (entry(a, *t_max), entry(b, *t_max)) {
                    (Some(ta), Some(tb)) => {
                        let ((near, _), (far, t_far)) = if ta <= tb { ((a, ta), (b, tb)) } else { ((b, tb), (a, ta)) };
                        stack[depth] = (far as u32, t_far);
                        depth += 1;
                        at = near;
                        continue;
                    }
                    (Some(_), None) => {
                        at = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        at = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            loop {
                if depth == 0 {
                    return;
                }
                depth -= 1;
                let (next, t_entry) = stack[depth];
                if t_entry < *t_max {
                    at = next as usize;
                    break;
                }
            }
        }
    }

    /// Renumbers the primitives in leaf order and returns the permutation: entry
    /// `k` is the old index of the primitive now numbered `k`. Callers that store
    /// primitive data reorder it with the permutation, so leaves read contiguous
    /// memory.
    pub fn renumber(&mut self) -> Vec<u32> {
        let old = std::mem::take(&mut self.order);
        self.order = (0..old.len() as u32).collect();
        old
    }

    /// Number of nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }
}

fn build_node(items: &mut [Item], start: usize) -> BuildNode {
    let (bounds, centres) = extents(items);
    if items.len() <= LEAF_MAX {
        return BuildNode::Leaf { bounds, start, count: items.len() };
    }
    let axis = (centres.max - centres.min).max_position();
    let extent = centres.max[axis] - centres.min[axis];
    let mid = match (extent > 0.0).then(|| best_split(items, axis, centres.min[axis], extent, bounds)).flatten() {
        Some(split) => partition(items, |i| bin_of(i.centre[axis], centres.min[axis], extent) <= split),
        None if items.len() <= 255 => return BuildNode::Leaf { bounds, start, count: items.len() },
        None => {
            items.sort_unstable_by(|a, b| a.centre[axis].total_cmp(&b.centre[axis]));
            items.len() / 2
        }
    };
    let (left, right) = items.split_at_mut(mid);
    let (a, b) = if left.len() + right.len() > PARALLEL_BELOW {
        rayon::join(|| build_node(left, start), || build_node(right, start + mid))
    } else {
        (build_node(left, start), build_node(right, start + mid))
    };
    BuildNode::Interior { bounds, children: Box::new([a, b]) }
}

/// The box around the items and the box around their centres (in parallel for
/// large nodes: near the root, one node holds all the work).
fn extents(items: &[Item]) -> (Box3A, Box3A) {
    let scan = |items: &[Item]| {
        let (mut b, mut c) = (Box3A::EMPTY, Box3A::EMPTY);
        for i in items {
            b = b.union(i.bounds);
            c = c.grow(i.centre);
        }
        (b, c)
    };
    if items.len() > PARALLEL_SCAN {
        let merge = |(a, c): (Box3A, Box3A), (b, d): (Box3A, Box3A)| (a.union(b), c.union(d));
        items.par_chunks(PARALLEL_SCAN / 4).map(scan).reduce(|| (Box3A::EMPTY, Box3A::EMPTY), merge)
    } else {
        scan(items)
    }
}

fn bin_of(c: f32, min: f32, extent: f32) -> usize {
    (((c - min) * (BINS as f32 / extent)) as usize).min(BINS - 1)
}

/// The last bin of the left side of the cheapest SAH split, or `None` if making a
/// leaf is cheaper (or nothing separates).
fn best_split(items: &[Item], axis: usize, min: f32, extent: f32, bounds: Box3A) -> Option<usize> {
    type Bins = [(Box3A, usize); BINS];
    let fill = |items: &[Item]| {
        let mut bins: Bins = [(Box3A::EMPTY, 0); BINS];
        for i in items {
            let b = &mut bins[bin_of(i.centre[axis], min, extent)];
            *b = (b.0.union(i.bounds), b.1 + 1);
        }
        bins
    };
    let bins = if items.len() > PARALLEL_SCAN {
        let merge = |mut a: Bins, b: Bins| {
            a.iter_mut().zip(b).for_each(|(x, y)| *x = (x.0.union(y.0), x.1 + y.1));
            a
        };
        items.par_chunks(PARALLEL_SCAN / 4).map(fill).reduce(|| [(Box3A::EMPTY, 0); BINS], merge)
    } else {
        fill(items)
    };
    let mut right = [(0.0f32, 0usize); BINS];
    let mut acc = (Box3A::EMPTY, 0);
    for k in (1..BINS).rev() {
        acc = (acc.0.union(bins[k].0), acc.1 + bins[k].1);
        right[k] = (acc.0.area(), acc.1);
    }
    let mut left = (Box3A::EMPTY, 0);
    let mut best: Option<(f32, usize)> = None;
    for k in 0..BINS - 1 {
        left = (left.0.union(bins[k].0), left.1 + bins[k].1);
        let (ra, rn) = right[k + 1];
        if left.1 == 0 || rn == 0 {
            continue;
        }
        let cost = 0.125 + (left.0.area() * left.1 as f32 + ra * rn as f32) / bounds.area().max(f32::MIN_POSITIVE);
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, k));
        }
    }
    let (cost, k) = best?;
    (items.len() > LEAF_MAX * 16 || cost < items.len() as f32).then_some(k)
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

fn flatten(node: &BuildNode, out: &mut Vec<Node>) {
    match node {
        BuildNode::Leaf { bounds, start, count } => {
            out.push(Node::new(bounds, *start as u32, *count as u16));
        }
        BuildNode::Interior { bounds, children } => {
            let at = out.len();
            out.push(Node::new(bounds, 0, 0));
            flatten(&children[0], out);
            out[at].offset = out.len() as u32;
            flatten(&children[1], out);
        }
    }
}
