//! Bounding volume hierarchy over boxes: a binary tree built by the binned
//! surface-area heuristic (as pbrt-v4's `BVHAggregate`, 16 bins), collapsed to
//! eight children a node (as Embree's BVH8: a node's children found by opening
//! its largest interior child until there are eight), flattened depth-first,
//! traversed nearest child first.
//!
//! A node keeps its children's boxes axis by axis across eight lanes, so one
//! slab test of eight-lane vectors (AVX) tells which children a ray enters and
//! where. Against the binary tree it replaces (the same build, two boxes a
//! node), primary rays on one thread of the 2-core machine of the benchmarks
//! page: 11.0–11.9 against 10.7 Mrays/s on a 99k-triangle sphere, 10.6–10.8
//! against 9.0–9.1 on a 998k one, together with the eight-lane leaf test of
//! [`crate::triangle::ShearedRay::intersect_lanes`]
//! (`RAYON_NUM_THREADS=1 kage-bench rays --scenes sphere100k,sphere1m`).
//!
//! Coherent rays (a block of pixels' primary rays, a pixel's samples) walk
//! it eight together ([`Bvh::intersect_packet_leaves`], as Embree's
//! `rtcIntersect8`): a node's children are first tested against the whole
//! packet at once in interval arithmetic (the slab test over the span of the
//! rays' origins and reciprocal directions: one eight-lane test drops the
//! children no ray can enter), then each child left against the eight rays,
//! a ray a lane, with the one-ray test's operations; a leaf's triangles are
//! tested once for all the rays that reach it
//! ([`crate::triangle::RayLanes`]). Each ray gets the hit it finds alone.
//! Primary rays of 4 × 2 pixel blocks, one thread, alternated with one ray
//! at a time (`RAYON_NUM_THREADS=1 kage-bench rays --scenes
//! sphere10k,sphere1m`, a 2-core AVX-512 EPYC VM): 21.8 against 16.1–16.3
//! Mrays/s on a 9.8k-triangle sphere, 15.4–15.5 against 13.0–13.2 on a 998k
//! one (at a million triangles each leaf is reached by fewer of the
//! packet's rays).
//!
//! The build moves little memory: a primitive is a 32-byte item (its box,
//! its index in the boxes' spare lanes), a split's bins keep both the boxes
//! and the centres' bounds of their items, so a child's extents come from
//! its parent's bins and each node's items are read once to bin and once to
//! partition; the two sides of a split are built in parallel, the top
//! nodes' scans in parallel chunks, and the binary tree is collapsed and
//! flattened in parallel (large subtrees apart, joined with their indices
//! shifted). A 998k-triangle sphere's build (`TraceScene::new`, 2 threads)
//! went from ~290 to ~200 ms by these: the binary tree 140 → 100 ms, the
//! collapse 40 → 20, the item list 28 → 3, the triangle columns 36 → 11
//! (stage timers in one run; `kage-bench rays` gives the whole build beside
//! Embree's), and to ~150 ms with leaves of eight ([`Bvh::build_lanes`]).
//!
//! The hierarchy knows only boxes. Traversal hands each leaf to a closure that
//! intersects it, so one walker serves the scene's triangles and solids (ray
//! tracing, a leaf's triangles tested eight at a time) and a solid's primitives
//! (CSG casting).

use glam::Vec3;
use wide::f32x8;

use crate::camera::Ray;
use crate::triangle::{set_bits, RayLanes};

mod build;

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

/// Children a node holds: eight boxes are tested at once, one per lane of an
/// eight-wide vector (AVX), as Embree's BVH8 does.
const WIDTH: usize = 8;

/// A node of the flattened eight-wide tree: its children's boxes, axis by
/// axis across the eight lanes (a child per lane), so one slab test of eight
/// lanes decides which children the ray enters and at what distance.
#[derive(Debug, Clone, Copy)]
#[repr(align(32))]
struct Node {
    /// Smallest corners' x, y, z, then largest corners' x, y, z, a child a lane.
    bounds: [[f32; WIDTH]; 6],
    /// Per child: a leaf's first index into `order`, or an interior child's
    /// node index.
    child: [u32; WIDTH],
    /// Per child: the primitives of a leaf child (1 to 255), or 0 for an
    /// interior child.
    count: [u8; WIDTH],
    /// Children in use (the first `children` lanes).
    children: u8,
}

impl Node {
    const EMPTY: Node = Node { bounds: [[0.0; WIDTH]; 6], child: [0; WIDTH], count: [0; WIDTH], children: 0 };

    /// Entry distances of the ray (given as origin and 1/direction) into the
    /// children's boxes, and a bit per child it enters before `t_max` (slab
    /// test, eight lanes at once; the far distance is widened by a few ulps so
    /// a ray grazing a face is not lost to rounding).
    #[inline(always)]
    fn entries(&self, origin: [f32x8; 3], inv_dir: [f32x8; 3], t_max: f32) -> (f32x8, u32) {
        let bounds = self.bounds.map(f32x8::from);
        let (near, enters) = slab_test(&bounds, origin, inv_dir, f32x8::splat(t_max));
        (near, enters & ((1u32 << self.children) - 1))
    }
}

/// The slab test, eight lanes at once (a box a lane, or a ray a lane): the
/// distances at which the rays enter the boxes (`bounds`: smallest corners'
/// x, y, z, then largest corners'), and a bit per lane entered before
/// `t_max`; the far distance is widened by a few ulps so a ray grazing a
/// face is not lost to rounding. One function for both walks, so a packet's
/// lane decides as its ray alone does.
#[inline(always)]
fn slab_test(bounds: &[f32x8; 6], origin: [f32x8; 3], inv_dir: [f32x8; 3], t_max: f32x8) -> (f32x8, u32) {
    let slab = |axis: usize| {
        let (t0, t1) =
            ((bounds[axis] - origin[axis]) * inv_dir[axis], (bounds[axis + 3] - origin[axis]) * inv_dir[axis]);
        (t0.fast_min(t1), t0.fast_max(t1))
    };
    let ((nx, fx), (ny, fy), (nz, fz)) = (slab(0), slab(1), slab(2));
    let near = nx.fast_max(ny).fast_max(nz).fast_max(f32x8::ZERO);
    let far = fx.fast_min(fy).fast_min(fz) * f32x8::splat(1.0 + 2.0 * f32::EPSILON * 2.0);
    (near, (near.simd_le(far) & near.simd_lt(t_max)).to_bitmask())
}

/// A postponed child: its parent node's index times [`WIDTH`] plus its lane
/// (low 32 bits) and the distance at which the ray enters its box (high 32
/// bits), packed so the walk's stack is a plain array of integers.
type Postponed = u64;

fn postponed(slot: u32, t: f32) -> Postponed {
    u64::from(t.to_bits()) << 32 | u64::from(slot)
}

fn postponed_slot(p: Postponed) -> (usize, usize, f32) {
    let slot = p as u32 as usize;
    (slot / WIDTH, slot % WIDTH, f32::from_bits((p >> 32) as u32))
}

/// The ray's origin and reciprocal direction, each axis in eight lanes.
#[inline(always)]
fn ray_lanes(ray: &Ray) -> ([f32x8; 3], [f32x8; 3]) {
    let inv = ray.dir.recip();
    let lanes = |v: Vec3| [f32x8::splat(v.x), f32x8::splat(v.y), f32x8::splat(v.z)];
    (lanes(ray.origin), lanes(inv))
}

/// Postponed children of one walk: a fixed array, spilling to the heap only
/// on trees deeper than a binned build makes.
struct Stack<T: Copy, const N: usize> {
    fixed: [T; N],
    len: usize,
    spilled: Vec<T>,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    #[inline(always)]
    fn new(zero: T) -> Self {
        Stack { fixed: [zero; N], len: 0, spilled: Vec::new() }
    }

    #[inline(always)]
    fn push(&mut self, p: T) {
        if self.len < N {
            self.fixed[self.len] = p;
            self.len += 1;
        } else {
            self.spilled.push(p);
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if let Some(p) = self.spilled.pop() {
            return Some(p);
        }
        self.len = self.len.checked_sub(1)?;
        Some(self.fixed[self.len])
    }
}

/// Rays walked together by [`Bvh::intersect_packet_leaves`], one a lane.
pub const PACKET: usize = WIDTH;

/// Eight rays walked together: origins and reciprocal directions, a ray a
/// lane, and per axis the interval their origins and reciprocal
/// directions span (`None` where the directions change sign along the axis
/// or one is parallel to it), for the test that drops at once the children
/// of a node no ray of the packet can enter.
struct Packet {
    origin: [f32x8; 3],
    inv_dir: [f32x8; 3],
    /// Per axis: smallest and largest origin, smallest and largest
    /// reciprocal direction, of the rays in use.
    span: [Option<[f32; 4]>; 3],
}

impl Packet {
    fn new(rays: &RayLanes) -> Packet {
        let (origin, dir) = rays.lanes();
        let inv_dir = dir.map(|d| f32x8::splat(1.0) / d);
        let span = |k: usize| {
            let (o, d) = (origin[k].to_array(), inv_dir[k].to_array());
            let (lo, hi) = (
                |v: [f32; PACKET]| v.into_iter().fold(f32::INFINITY, f32::min),
                |v: [f32; PACKET]| v.into_iter().fold(f32::NEG_INFINITY, f32::max),
            );
            let s = [lo(o), hi(o), lo(d), hi(d)];
            let same_sign = s[2] > 0.0 || s[3] < 0.0;
            (same_sign && s.iter().all(|v| v.is_finite())).then_some(s)
        };
        Packet { origin, inv_dir, span: std::array::from_fn(span) }
    }
}

impl Node {
    /// A bit per child that some ray of the packet may enter before `t_max`:
    /// the slab test in interval arithmetic over the packet's spans, eight
    /// children at once. Never drops a child that [`Node::packet_entries`]
    /// finds a ray entering (rounding is monotonic, so the corner products
    /// bound every ray's).
    #[inline(always)]
    fn packet_candidates(&self, p: &Packet, t_max: f32) -> u32 {
        let (mut near, mut far) = (f32x8::ZERO, f32x8::splat(f32::INFINITY));
        for (axis, span) in p.span.iter().enumerate() {
            let Some([o_lo, o_hi, i_lo, i_hi]) = *span else { continue };
            let (lo, hi) = (f32x8::from(self.bounds[axis]), f32x8::from(self.bounds[axis + 3]));
            let (entry, exit) = if i_lo > 0.0 { (lo, hi) } else { (hi, lo) };
            let (i_lo, i_hi) = (f32x8::splat(i_lo), f32x8::splat(i_hi));
            let products = |plane: f32x8| {
                let (a, b) = (plane - f32x8::splat(o_hi), plane - f32x8::splat(o_lo));
                let (p, q, r, s) = (a * i_lo, a * i_hi, b * i_lo, b * i_hi);
                (p.fast_min(q).fast_min(r).fast_min(s), p.fast_max(q).fast_max(r).fast_max(s))
            };
            near = near.fast_max(products(entry).0);
            far = far.fast_min(products(exit).1);
        }
        let far = far * f32x8::splat(1.0 + 2.0 * f32::EPSILON * 2.0);
        let may = near.simd_le(far) & near.simd_lt(f32x8::splat(t_max));
        may.to_bitmask() & ((1u32 << self.children) - 1)
    }

    /// [`Node::entries`] of child `k` for the eight rays of a packet, a ray a
    /// lane: the same operations, so each lane decides as its ray alone
    /// would.
    #[inline(always)]
    fn packet_entries(&self, k: usize, p: &Packet, t_max: f32x8) -> (f32x8, u32) {
        let bounds = self.bounds.map(|axis| f32x8::splat(axis[k]));
        slab_test(&bounds, p.origin, p.inv_dir, t_max)
    }
}

/// A bounding volume hierarchy over primitives known by their boxes.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

impl Bvh {
    /// The nearest primitive along `ray` before `t_max`: `hit(i, t_max)` intersects
    /// primitive `i` and returns its distance if nearer than `t_max`. Returns the
    /// primitive and distance.
    pub fn intersect(&self, ray: &Ray, t_max: f32, mut hit: impl FnMut(u32, f32) -> Option<f32>) -> Option<(u32, f32)> {
        self.intersect_leaves(ray, t_max, |leaf, mut t_max| {
            let mut best = None;
            for &i in leaf {
                if let Some(t) = hit(i, t_max) {
                    t_max = t;
                    best = Some((i, t));
                }
            }
            best
        })
    }

    /// [`Bvh::intersect`] a leaf at a time, for callers that test a leaf's
    /// primitives together: `hit(leaf, t_max)` intersects the primitives
    /// `leaf` (after [`Bvh::renumber`], consecutive numbers) and returns the
    /// nearest one nearer than `t_max` and its distance.
    pub fn intersect_leaves(
        &self,
        ray: &Ray,
        mut t_max: f32,
        mut hit: impl FnMut(&[u32], f32) -> Option<(u32, f32)>,
    ) -> Option<(u32, f32)> {
        let mut best = None;
        self.walk(ray, &mut t_max, |leaf, t_max| {
            if let Some((i, t)) = hit(leaf, *t_max) {
                *t_max = t;
                best = Some((i, t));
            }
            false
        });
        best
    }

    /// Whether any primitive blocks `ray` before `t_max` (stops at the first).
    pub fn occluded(&self, ray: &Ray, t_max: f32, mut hit: impl FnMut(u32, f32) -> Option<f32>) -> bool {
        self.occluded_leaves(ray, t_max, |leaf, t_max| leaf.iter().any(|&i| hit(i, t_max).is_some()))
    }

    /// [`Bvh::occluded`] a leaf at a time: `blocks(leaf, t_max)` says whether
    /// any of the primitives `leaf` blocks the ray before `t_max`.
    pub fn occluded_leaves(&self, ray: &Ray, mut t_max: f32, mut blocks: impl FnMut(&[u32], f32) -> bool) -> bool {
        let mut any = false;
        self.walk(ray, &mut t_max, |leaf, t_max| {
            any = blocks(leaf, *t_max);
            any
        });
        any
    }

    /// Every primitive whose leaf's box `ray` enters before `t_max`, in no
    /// particular order (a walk that keeps no order: for callers that want
    /// them all, as the CSG caster's counts do).
    pub fn crossed(&self, ray: &Ray, t_max: f32, mut visit: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let (origin, inv) = ray_lanes(ray);
        let mut stack: Stack<Postponed, 32> = Stack::new(0);
        let mut at = 0usize;
        loop {
            let node = &self.nodes[at];
            let (_, enters) = node.entries(origin, inv, t_max);
            for k in set_bits(enters) {
                let (child, count) = (node.child[k] as usize, node.count[k] as usize);
                if count > 0 {
                    self.order[child..child + count].iter().for_each(|&i| visit(i));
                } else {
                    stack.push(postponed((at * WIDTH + k) as u32, 0.0));
                }
            }
            let Some(p) = stack.pop() else { return };
            let (parent, k, _) = postponed_slot(p);
            at = self.nodes[parent].child[k] as usize;
        }
    }

    /// Visits the leaves the ray reaches (their primitives), nearer child first
    /// (by entry distance); `visit` returns true to stop. A postponed child is
    /// skipped when the ray has since found a hit nearer than its box.
    fn walk(&self, ray: &Ray, t_max: &mut f32, mut visit: impl FnMut(&[u32], &mut f32) -> bool) {
        if self.nodes.is_empty() {
            return;
        }
        let (origin, inv) = ray_lanes(ray);
        let mut stack: Stack<Postponed, 32> = Stack::new(0);
        // The node walked now, or a leaf's primitives (`leaf` > 0 of them).
        let (mut at, mut leaf) = (0usize, 0u8);
        loop {
            if leaf > 0 {
                if visit(&self.order[at..at + leaf as usize], t_max) {
                    return;
                }
            } else {
                let node = &self.nodes[at];
                let (near, enters) = node.entries(origin, inv, *t_max);
                if enters != 0 && enters & (enters - 1) == 0 {
                    // One child entered: walk it.
                    let k = enters.trailing_zeros() as usize;
                    (at, leaf) = (node.child[k] as usize, node.count[k]);
                    continue;
                }
                if enters != 0 {
                    // The children entered, farthest first (ties: the later child
                    // first), so the nearest is walked now and the rest postponed.
                    let near = near.to_array();
                    let mut entered = [(0.0f32, 0usize); WIDTH];
                    let mut n = 0;
                    for k in set_bits(enters) {
                        let mut j = n;
                        while j > 0 && entered[j - 1].0 <= near[k] {
                            entered[j] = entered[j - 1];
                            j -= 1;
                        }
                        entered[j] = (near[k], k);
                        n += 1;
                    }
                    let slot = |k: usize| (at * WIDTH + k) as u32;
                    entered[..n - 1].iter().for_each(|&(t, k)| stack.push(postponed(slot(k), t)));
                    let k = entered[n - 1].1;
                    (at, leaf) = (node.child[k] as usize, node.count[k]);
                    continue;
                }
            }
            loop {
                let Some(p) = stack.pop() else { return };
                let (parent, k, t) = postponed_slot(p);
                if t < *t_max {
                    let node = &self.nodes[parent];
                    (at, leaf) = (node.child[k] as usize, node.count[k]);
                    break;
                }
            }
        }
    }

    /// [`Bvh::intersect_leaves`] for up to eight rays walked together (a
    /// packet: coherent rays, such as a block of pixels' primary rays, reach
    /// mostly the same nodes). `lanes` has a bit per ray in use (the others
    /// should repeat one of them: the packet's span covers every lane);
    /// `t_max` is per ray. `hit(leaf, lanes, t_max)` intersects the primitives `leaf` with the rays of `lanes`
    /// (those that enter its box before their `t_max`) and lowers each one's
    /// `t_max` to its nearest hit. Each ray reaches every leaf it would reach
    /// alone before finding its nearest hit: its answer is its own.
    pub fn intersect_packet_leaves(
        &self,
        rays: &RayLanes,
        lanes: u32,
        t_max: &mut [f32; PACKET],
        mut hit: impl FnMut(&[u32], u32, &mut [f32; PACKET]),
    ) {
        if self.nodes.is_empty() || lanes == 0 {
            return;
        }
        let p = Packet::new(rays);
        let farthest = |t: &[f32; PACKET]| set_bits(lanes).map(|k| t[k]).fold(f32::NEG_INFINITY, f32::max);
        let mut far = farthest(t_max);
        let mut t = f32x8::from(*t_max);
        let mut stack: Stack<(u32, f32x8), 48> = Stack::new((0, f32x8::ZERO));
        // The node walked now, or a leaf's primitives (`leaf` > 0 of them),
        // and the rays that entered it.
        let (mut at, mut leaf, mut mask) = (0usize, 0u8, lanes);
        loop {
            if leaf > 0 {
                hit(&self.order[at..at + leaf as usize], mask, t_max);
                (t, far) = (f32x8::from(*t_max), farthest(t_max));
            } else {
                let node = &self.nodes[at];
                let mut entered = [(0.0f32, 0usize, 0u32, f32x8::ZERO); WIDTH];
                let mut n = 0;
                for k in set_bits(node.packet_candidates(&p, far)) {
                    let (near, m) = node.packet_entries(k, &p, t);
                    let m = m & mask;
                    if m == 0 {
                        continue;
                    }
                    // Rays that do not enter it never reach it from the stack.
                    let mut near = near.to_array();
                    (0..PACKET).filter(|i| m >> i & 1 == 0).for_each(|i| near[i] = f32::INFINITY);
                    let first = near.into_iter().fold(f32::INFINITY, f32::min);
                    let near = f32x8::from(near);
                    // Farthest first (ties: the later child first).
                    let mut j = n;
                    while j > 0 && entered[j - 1].0 <= first {
                        entered[j] = entered[j - 1];
                        j -= 1;
                    }
                    entered[j] = (first, k, m, near);
                    n += 1;
                }
                if n > 0 {
                    let slot = |k: usize| (at * WIDTH + k) as u32;
                    entered[..n - 1].iter().for_each(|&(_, k, _, near)| stack.push((slot(k), near)));
                    let (_, k, m, _) = entered[n - 1];
                    (at, leaf, mask) = (node.child[k] as usize, node.count[k], m);
                    continue;
                }
            }
            loop {
                let Some((slot, near)) = stack.pop() else { return };
                let m = near.simd_lt(t).to_bitmask();
                if m != 0 {
                    let node = &self.nodes[slot as usize / WIDTH];
                    let k = slot as usize % WIDTH;
                    (at, leaf, mask) = (node.child[k] as usize, node.count[k], m);
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

#[cfg(test)]
mod tests {
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    use super::*;

    /// The walk's stack gives back what it was given, last first, past its
    /// fixed part too (a tree deeper than a balanced build).
    #[test]
    fn the_stack_spills_and_stays_last_in_first_out() {
        let mut stack: Stack<Postponed, 32> = Stack::new(0);
        (0..100u32).for_each(|i| stack.push(postponed(i, i as f32 * 0.5)));
        for i in (0..100u32).rev() {
            let (parent, lane, t) = postponed_slot(stack.pop().expect("pushed"));
            assert_eq!((parent * WIDTH + lane, t), (i as usize, i as f32 * 0.5));
        }
        assert!(stack.pop().is_none());
    }

    /// Nodes hold up to eight children, and every primitive is in exactly
    /// one leaf.
    #[test]
    fn every_primitive_is_in_one_leaf_of_an_eight_wide_tree() {
        let boxes: Vec<Aabb> = (0..5000)
            .map(|i| {
                let p = Vec3::new((i % 17) as f32, (i % 23) as f32 * 0.7, (i / 391) as f32 * 1.3);
                Aabb { min: p, max: p + Vec3::splat(0.5) }
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        let mut seen = vec![0u32; boxes.len()];
        let mut wide = 0;
        for node in &bvh.nodes {
            assert!((1..=WIDTH as u8).contains(&node.children));
            wide += usize::from(node.children > 2);
            for k in 0..node.children as usize {
                if node.count[k] > 0 {
                    let first = node.child[k] as usize;
                    bvh.order[first..first + node.count[k] as usize].iter().for_each(|&i| seen[i as usize] += 1);
                }
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "each primitive once");
        assert!(wide * 2 > bvh.nodes.len(), "most nodes are wider than binary: {wide} of {}", bvh.nodes.len());
    }

    /// The unordered walk finds every primitive the ordered walk reaches, and
    /// every primitive whose own box the ray enters.
    #[test]
    fn the_unordered_walk_reaches_what_the_ordered_one_does() {
        let mut rng = StdRng::seed_from_u64(11);
        let mut r = || rng.gen_range(-1.0f32..1.0);
        let boxes: Vec<Aabb> = (0..3000)
            .map(|_| {
                let p = Vec3::new(r(), r(), r()) * 4.0;
                Aabb { min: p, max: p + Vec3::new(r().abs(), r().abs(), r().abs()) * 0.3 }
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        let mut met = 0;
        for _ in 0..500 {
            let origin = Vec3::new(r(), r(), r()) * 6.0;
            let ray = Ray { origin, dir: (Vec3::new(r(), r(), r()) - origin).normalize() };
            let t_max = if r() > 0.0 { 5.0 } else { f32::INFINITY };
            let (mut ordered, mut unordered) = (Vec::new(), Vec::new());
            bvh.intersect(&ray, t_max, |i, _| {
                ordered.push(i);
                None
            });
            bvh.crossed(&ray, t_max, |i| unordered.push(i));
            ordered.sort_unstable();
            unordered.sort_unstable();
            assert_eq!(ordered, unordered);
            let inv = ray.dir.recip();
            for (i, b) in boxes.iter().enumerate() {
                let (t0, t1) = ((b.min - origin) * inv, (b.max - origin) * inv);
                let (near, far) = (t0.min(t1).max_element().max(0.0), t0.max(t1).min_element());
                if near <= far && near < t_max {
                    met += 1;
                    assert!(unordered.binary_search(&(i as u32)).is_ok(), "box {i} entered but not reached");
                }
            }
        }
        assert!(met > 500, "{met}");
    }
}
