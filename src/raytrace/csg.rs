//! Ray casting of CSG solids (issue 6): the depth interval a ray spends inside each
//! convex primitive (seed 003's procedure 3, "front and back depth at a pixel",
//! solved in closed form), combined along the boolean tree into the spans the ray
//! spends inside the solid, whose first entry is the visible surface.
//!
//! This is the paper's baseline (a ray per pixel against every primitive), the
//! oracle the scanline renderer is tested against, and the way traced reflections
//! and the reference renderer see CSG solids.
//!
//! Each primitive is intersected in its unit shape's space: the ray is carried
//! there by the inverse transform without normalising its direction, so the ray
//! parameter `t` is the same in both spaces, and normals go back by the inverse
//! transpose.
//!
//! Coplanar faces (a cutter flush with the face it cuts, which real models are
//! full of) are decided one way: a difference removes its cutter's closed interval
//! widened by a hair ([`TIE`]), so a cut face exactly on a solid face removes it
//! instead of speckling.

use glam::{Affine3A, Mat3A, Vec3, Vec3A, Vec4};
use wide::f32x8;

use super::bvh::{Aabb, Bvh};
use crate::scene::camera::RowLine;
use crate::scene::csg::{ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Shape};
use crate::scene::Ray;
use crate::visibility::occupancy::{OccupancyTree, Occupied};

mod lanes;

/// Relative width (of `t`) within which a cutter's boundary counts as reaching a
/// solid's boundary.
pub const TIE: f32 = 1e-5;

/// Where a ray crosses a solid's surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Ray parameter.
    pub t: f32,
    /// Unit outward normal of the solid there (solid space).
    pub normal: Vec3,
    /// The primitive whose surface it is.
    pub primitive: u32,
    /// Whether that surface belongs to a subtracted primitive (a hole's wall).
    pub cut: bool,
}

/// A stretch of the ray inside the solid, from `enter` to `exit`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    /// Where the ray enters.
    pub enter: Crossing,
    /// Where it leaves.
    pub exit: Crossing,
}

/// A [`Crossing`] before its normal is found: which face of which primitive
/// the ray crosses, and where. Combining intervals along the tree reads only
/// `t`, so the booleans move these (12 bytes) and only the crossing finally
/// seen pays for its normal ([`CsgCaster::crossing_on_ray`],
/// [`CsgCaster::crossing_on_line`]), from the face and the ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// The primitive whose surface it is.
    pub primitive: u32,
    /// The face of the primitive's unit shape (a polyhedron's plane; a
    /// frustum's side or cap), and in its top bit whether the surface
    /// belongs to a subtracted primitive (a hole's wall).
    face: u32,
}

impl Hit {
    /// The bit of `face` that marks a hole's wall.
    const CUT: u32 = 1 << 31;

    fn new(t: f32, primitive: usize, face: u32) -> Hit {
        Hit { t, primitive: primitive as u32, face }
    }

    /// Whether the surface belongs to a subtracted primitive (a hole's wall).
    #[must_use]
    pub fn cut(&self) -> bool {
        self.face & Self::CUT != 0
    }
}

/// A stretch of a ray inside a primitive or a part of the solid, its ends
/// not yet given normals ([`Hit`]): what the booleans combine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Where the ray enters.
    pub enter: Hit,
    /// Where it leaves.
    pub exit: Hit,
}

/// One primitive's [`Interval`]s at eight neighbouring pixels of a scanline
/// ([`CsgCaster::spans_on_eight`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct IntervalLanes {
    /// Entry and exit `t` per pixel.
    t: [[f32; 8]; 2],
    /// Entry and exit faces per pixel.
    face: [[u32; 8]; 2],
    /// Bit `j`: pixel `j` meets the primitive.
    hit: u8,
    primitive: u32,
}

impl IntervalLanes {
    /// The interval at pixel `j` (0–7) of the eight, if its ray meets the
    /// primitive.
    #[inline]
    #[must_use]
    pub fn get(&self, j: usize) -> Option<Interval> {
        (self.hit >> j & 1 != 0).then(|| {
            let hit = |k: usize| Hit { t: self.t[k][j], primitive: self.primitive, face: self.face[k][j] };
            Interval { enter: hit(0), exit: hit(1) }
        })
    }
}

/// The faces of a many-planed polyhedron that one scanline's rays can cross
/// ([`CsgCaster::row_faces`]), with buffers reused from row to row.
#[derive(Debug, Clone, Default)]
pub struct RowFaces {
    /// Whether `faces` applies (the primitive is such a polyhedron).
    active: bool,
    faces: Vec<u32>,
    distances: Vec<f32>,
}

/// The spans of `ray` inside `solid`, sorted and disjoint (empty if it misses).
#[must_use]
pub fn spans(solid: &CsgSolid, ray: &Ray) -> Vec<Span> {
    CsgCaster::new(solid).spans(ray)
}

/// The first surface of `solid` along `ray` at `t` in `(t_min, t_max)`.
#[must_use]
pub fn first_hit(solid: &CsgSolid, ray: &Ray, t_min: f32, t_max: f32) -> Option<Crossing> {
    CsgCaster::new(solid).first_hit(ray, t_min, t_max)
}

/// A solid ready for many rays: each primitive's inverse transform and normal
/// matrix computed once, and for solids of many primitives a BVH over their
/// bounds, so a ray meets only the primitives whose boxes it crosses.
#[derive(Debug, Clone)]
pub struct CsgCaster {
    solid: CsgSolid,
    /// Per primitive: solid space → unit shape, and the normal matrix back.
    frames: Vec<(Affine3A, Mat3A)>,
    /// Per primitive: how its unit shape is cut when it is not the generic
    /// procedure's ([`unit_span`]): a box by slabs, a polyhedron of many
    /// planes eight planes at a time.
    clipping: Vec<Clipping>,
    /// Over the primitives' boxes, from [`CsgCaster::BVH_PRIMITIVES`] up,
    /// with the tree's shape for counting the primitives a ray's boxes cross.
    bvh: Option<(Bvh, OccupancyTree)>,
}

impl CsgCaster {
    /// Prepares a copy of `solid`.
    #[must_use]
    pub fn new(solid: &CsgSolid) -> Self {
        Self::from_solid(solid.clone())
    }

    /// Prepares a copy of `solid` for a caller that finds the primitives each
    /// ray meets itself (seed 003's scanline walk knows every row's
    /// occupants): without the BVH, which [`CsgCaster::first_hit`] alone uses.
    #[must_use]
    pub fn without_bvh(solid: &CsgSolid) -> Self {
        Self::prepared(solid.clone(), false)
    }

    /// Prepares `solid`.
    #[must_use]
    pub fn from_solid(solid: CsgSolid) -> Self {
        Self::prepared(solid, true)
    }

    /// Prepares `solid`, with a BVH over its primitives if `bvh` and it has
    /// enough of them.
    fn prepared(solid: CsgSolid, bvh: bool) -> Self {
        let frames = solid.primitives.iter().map(|p| (p.transform.inverse(), normal_matrix(&p.transform))).collect();
        let cube = ConvexPolyhedron::unit_cube();
        let clipping = solid
            .primitives
            .iter()
            .map(|p| match &p.shape {
                Shape::Polyhedron(q) if q.planes == cube.planes => Clipping::Box,
                Shape::Polyhedron(q) if q.planes.len() >= PlaneLanes::MIN_PLANES => {
                    Clipping::Lanes(Box::new(PlaneLanes::new(q)))
                }
                _ => Clipping::Shape,
            })
            .collect();
        let n = solid.primitives.len();
        let bvh = solid.tree.as_ref().filter(|_| bvh && n >= Self::BVH_PRIMITIVES).map(|tree| {
            let boxes: Vec<Aabb> = solid.primitives.iter().map(|p| Aabb::around(&p.corners())).collect();
            (Bvh::build(&boxes), OccupancyTree::new(tree, n))
        });
        CsgCaster { solid, frames, clipping, bvh }
    }

    /// Primitives from which [`CsgCaster::first_hit`] culls by a BVH.
    pub const BVH_PRIMITIVES: usize = 8;

    /// A ray's booleans count the primitives it meets ([`Occupied`]) when
    /// they are fewer than the tree's nodes over this, and walk the whole
    /// tree otherwise: counting one costs about as much as walking four nodes
    /// (measured on the Menger sponge, whose rays meet a third of its 221
    /// cutters, and the name tag, whose rays meet a few of its 1023 parts).
    const NODES_PER_COUNTED: usize = 4;

    /// The solid.
    #[must_use]
    pub fn solid(&self) -> &CsgSolid {
        &self.solid
    }

    /// How many primitives the solid has.
    #[must_use]
    pub fn primitives(&self) -> usize {
        self.frames.len()
    }

    /// The span of `ray` inside primitive `i`, if it meets it.
    #[must_use]
    pub fn span(&self, i: usize, ray: &Ray) -> Option<Span> {
        self.interval(i, ray).map(|s| self.finish_on_ray(s, ray))
    }

    /// [`CsgCaster::span`] before its ends are given normals: what the
    /// booleans combine.
    #[must_use]
    pub fn interval(&self, i: usize, ray: &Ray) -> Option<Interval> {
        let (o, d) = self.unit_ray(i, ray);
        self.unit_interval(i, o, d)
    }

    /// `ray` carried into primitive `i`'s unit space.
    fn unit_ray(&self, i: usize, ray: &Ray) -> (Vec3, Vec3) {
        (self.frames[i].0.transform_point3(ray.origin), self.frames[i].0.transform_vector3(ray.dir))
    }

    /// The interval of primitive `i` along `o + t·d` in its unit shape's space.
    fn unit_interval(&self, i: usize, o: Vec3, d: Vec3) -> Option<Interval> {
        let span = match &self.clipping[i] {
            Clipping::Box => unit_cube(o, d),
            Clipping::Lanes(planes) => planes.clip(o, d),
            Clipping::Shape => unit_span(&self.solid.primitives[i].shape, o, d),
        };
        let ((t0, f0), (t1, f1)) = span?;
        Some(Interval { enter: Hit::new(t0, i, f0), exit: Hit::new(t1, i, f1) })
    }

    /// A scanline's rays ([`RowLine`]) carried into primitive `i`'s unit space
    /// once, so each pixel's ray there costs two multiply-adds per coordinate
    /// instead of a matrix product (seed 003's coherence along a scanline).
    #[must_use]
    pub fn unit_line(&self, i: usize, line: &RowLine) -> RowLine {
        let m = &self.frames[i].0;
        RowLine {
            origin: m.transform_point3(line.origin),
            origin_step: m.transform_vector3(line.origin_step),
            dir: m.transform_vector3(line.dir),
            dir_step: m.transform_vector3(line.dir_step),
        }
    }

    /// The interval of primitive `i` along pixel `x`'s ray of `unit` (a line
    /// from [`CsgCaster::unit_line`]); `t` counts lengths of the line's
    /// (unnormalised) direction.
    #[must_use]
    pub fn span_on(&self, i: usize, unit: &RowLine, x: f32) -> Option<Interval> {
        let ray = unit.at(x);
        self.unit_interval(i, ray.origin, ray.dir)
    }

    /// For a polyhedron of many planes, the faces the rays of `unit` (a line
    /// from [`CsgCaster::unit_line`]) can cross, kept in `row` for
    /// [`CsgCaster::spans_on_eight`]; nothing for other primitives. A
    /// scanline's rays lie in one plane, which meets few of a rounded
    /// box's hundreds of faces.
    pub fn row_faces(&self, i: usize, unit: &RowLine, row: &mut RowFaces) {
        row.active = false;
        if let Clipping::Lanes(lanes) = &self.clipping[i] {
            if let Some(corners) = &lanes.corners {
                corners.met_by(unit, &mut row.distances, &mut row.faces);
                row.active = true;
            }
        }
    }

    /// [`CsgCaster::span_on`] at the eight pixels `x0..x0 + 8` of `unit` at
    /// once, in SIMD lanes: each the same to the bit as `span_on` gives it
    /// (a polyhedron of many planes clipped by the faces `row` keeps, from
    /// [`CsgCaster::row_faces`] on the same line).
    #[must_use]
    pub fn spans_on_eight(&self, i: usize, unit: &RowLine, x0: f32, row: &RowFaces) -> IntervalLanes {
        let rays = lanes::RayLanes::new(unit, x0);
        let shape = &self.solid.primitives[i].shape;
        let spans = match (&self.clipping[i], shape) {
            (Clipping::Box, _) => lanes::unit_cube(&rays),
            (Clipping::Lanes(_), Shape::Polyhedron(poly)) if row.active => {
                lanes::planes(row.faces.iter().map(|&f| (f, &poly.planes[f as usize])), &rays)
            }
            _ => lanes::shape(shape, &rays),
        };
        let face = |f: wide::f32x8| f.to_array().map(|f| f as u32);
        IntervalLanes {
            t: [spans.enter.0.to_array(), spans.exit.0.to_array()],
            face: [face(spans.enter.1), face(spans.exit.1)],
            hit: spans.hit.to_bitmask() as u8,
            primitive: i as u32,
        }
    }

    /// The crossing `hit` of `ray` with its unit outward normal (solid space).
    #[must_use]
    pub fn crossing_on_ray(&self, hit: Hit, ray: &Ray) -> Crossing {
        let (o, d) = self.unit_ray(hit.primitive as usize, ray);
        self.finish(hit, o + d * hit.t)
    }

    /// The crossing `hit` of pixel `x`'s ray of `unit` (the line of the hit's
    /// primitive from [`CsgCaster::unit_line`]) with its unit outward normal
    /// (solid space).
    #[must_use]
    pub fn crossing_on_line(&self, hit: Hit, unit: &RowLine, x: f32) -> Crossing {
        self.finish(hit, unit.at(x).at(hit.t))
    }

    /// `hit` with the unit outward normal (solid space) of its face at `p`
    /// (unit shape space): the shape's normal carried back by the inverse
    /// transpose, reversed on a hole's wall.
    fn finish(&self, hit: Hit, p: Vec3) -> Crossing {
        let i = hit.primitive as usize;
        let n = unit_normal(&self.solid.primitives[i].shape, hit.face & !Hit::CUT, p);
        let normal = (self.frames[i].1 * n).normalize_or_zero();
        let cut = hit.cut();
        Crossing { t: hit.t, normal: if cut { -normal } else { normal }, primitive: hit.primitive, cut }
    }

    /// Both ends of `interval` (of `ray`) with their normals.
    fn finish_on_ray(&self, interval: Interval, ray: &Ray) -> Span {
        Span { enter: self.crossing_on_ray(interval.enter, ray), exit: self.crossing_on_ray(interval.exit, ray) }
    }

    /// The spans of `ray` inside the part of the solid `tree` describes.
    #[must_use]
    pub fn spans_of(&self, tree: &CsgTree, ray: &Ray) -> Vec<Span> {
        let mut scratch = SpanScratch::default();
        combine(tree, &|i| self.interval(i, ray), &mut scratch);
        scratch.stack.iter().map(|&s| self.finish_on_ray(s, ray)).collect()
    }

    /// The first surface of the part `tree` along `ray` at `t > t_min`, with
    /// buffers reused from pixel to pixel.
    #[must_use]
    pub fn first_hit_with(&self, tree: &CsgTree, ray: &Ray, t_min: f32, scratch: &mut SpanScratch) -> Option<Crossing> {
        self.first_hit_in_by(tree, &|i| self.interval(i, ray), t_min, scratch).map(|h| self.crossing_on_ray(h, ray))
    }

    /// The first surface at `t > t_min` of the solid `tree` describes (seed
    /// 003's nearest surface over segments), each primitive's interval from
    /// `leaf` — e.g. [`CsgCaster::span_on`] — with buffers reused from pixel
    /// to pixel. Its normal is found by the caller, who knows the ray
    /// ([`CsgCaster::crossing_on_line`]).
    ///
    /// A union's operands are not merged when they need not be: where `t_min`
    /// lies outside every operand, the union's first surface is the nearest
    /// of the operands' first entries (the first operand's on a tie, as the
    /// merge would give it), so each operand is combined on its own and only
    /// its first entry kept. An operand holding `t_min` (the near plane inside
    /// the solid) sends the pixel to the full merge.
    pub fn first_hit_in_by<B: Booleans>(
        &self,
        tree: B,
        leaf: &impl Fn(usize) -> Option<Interval>,
        t_min: f32,
        scratch: &mut SpanScratch,
    ) -> Option<Hit> {
        let Parts { operation, others, .. } = tree.parts();
        if operation == Operation::Union {
            let mut nearest: Option<Hit> = None;
            for k in others {
                match first_entry(k, leaf, t_min, scratch) {
                    Ok(Some(h)) if nearest.is_none_or(|n| h.t < n.t) => nearest = Some(h),
                    Ok(_) => {}
                    Err(Inside) => return first_of_all(tree, leaf, t_min, scratch),
                }
            }
            return nearest;
        }
        first_of_all(tree, leaf, t_min, scratch)
    }

    /// The first surface beyond `t_min` of a union of pattern-matrix segments
    /// (seed 003 §5.2.1): per segment, the intersection of its positive
    /// primitives' intervals minus the intervals of its negative primitives
    /// that `occupying` says cover the pixel; the nearest over the segments.
    /// `span` gives a primitive's interval ([`CsgCaster::span_on`], cached by
    /// the caller), who finds the normal of the hit returned.
    pub fn first_hit_of_segments<'s>(
        &self,
        segments: impl IntoIterator<Item = &'s crate::visibility::pattern::Segment>,
        occupying: &impl Fn(usize) -> bool,
        span: &mut impl FnMut(usize) -> Option<Interval>,
        t_min: f32,
        scratch: &mut SpanScratch,
    ) -> Option<Hit> {
        scratch.stack.clear();
        let mut parts = 0;
        'segments: for seg in segments {
            let mut inside: Option<Interval> = None;
            for &i in &seg.positive {
                let Some(s) = span(i) else { continue 'segments };
                inside = Some(match inside {
                    None => s,
                    Some(a) => Interval {
                        enter: if a.enter.t >= s.enter.t { a.enter } else { s.enter },
                        exit: if a.exit.t <= s.exit.t { a.exit } else { s.exit },
                    },
                });
            }
            let Some(inside) = inside.filter(|s| s.enter.t < s.exit.t) else { continue };
            let base = scratch.stack.len();
            scratch.stack.push(inside);
            for &i in seg.negative.iter().filter(|&&i| occupying(i)) {
                let Some(cut) = span(i) else { continue };
                let SpanScratch { stack, out, .. } = scratch;
                out.clear();
                difference(&stack[base..], &[cut], out);
                stack.truncate(base);
                stack.extend_from_slice(out);
                if stack.len() == base {
                    break;
                }
            }
            parts += 1;
        }
        if parts > 1 {
            union(&mut scratch.stack, 0);
        }
        scratch.stack.iter().flat_map(|s| [s.enter, s.exit]).find(|c| c.t > t_min)
    }

    /// The spans of `ray` inside the solid.
    #[must_use]
    pub fn spans(&self, ray: &Ray) -> Vec<Span> {
        self.solid.tree.as_ref().map_or_else(Vec::new, |t| self.spans_of(t, ray))
    }

    /// The first surface along `ray` at `t` in `(t_min, t_max)`: the primitives
    /// whose boxes the ray crosses (all of them without a BVH) are cast, the
    /// others count as missed.
    #[must_use]
    pub fn first_hit(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Crossing> {
        let tree = self.solid.tree.as_ref()?;
        let Some((bvh, shape)) = &self.bvh else {
            return SCRATCH.with_borrow_mut(|s| self.first_hit_with(tree, ray, t_min, s)).filter(|c| c.t < t_max);
        };
        SCRATCH.with_borrow_mut(|s| {
            let mut met = std::mem::take(&mut s.met);
            bvh.intersect(ray, t_max, |i, _| {
                met.push(i);
                None
            });
            let hit = if met.len() * Self::NODES_PER_COUNTED < shape.len() {
                // Few primitives met: they occupy the ray (seed 003's counts,
                // [`OccupancyTree`]) and the booleans visit only what they make
                // non-empty.
                let mut counts = std::mem::take(&mut s.counts);
                counts.fit(shape);
                met.iter().for_each(|&i| counts.set(shape, i as usize, true));
                let root = counts.root(shape);
                let hit = root.and_then(|root| self.first_hit_in_by(root, &|i| self.interval(i, ray), t_min, s));
                counts.clear(shape);
                s.counts = counts;
                hit
            } else {
                // Most of the tree met: walk all of it, the others missed.
                let mut crossed = std::mem::take(&mut s.crossed);
                crossed.resize(self.frames.len(), false);
                met.iter().for_each(|&i| crossed[i as usize] = true);
                let leaf = |i: usize| if crossed[i] { self.interval(i, ray) } else { None };
                let hit = self.first_hit_in_by(tree, &leaf, t_min, s);
                met.iter().for_each(|&i| crossed[i as usize] = false);
                s.crossed = crossed;
                hit
            };
            met.clear();
            s.met = met;
            hit.filter(|c| c.t < t_max).map(|h| self.crossing_on_ray(h, ray))
        })
    }

    /// The first surface along `ray` beyond `t_min` when every primitive's span
    /// is computed first, whether or not the booleans need it: the paper's
    /// baseline ray caster (every pixel, every primitive, no acceleration).
    #[must_use]
    pub fn first_hit_every_primitive(&self, ray: &Ray, t_min: f32) -> Option<Crossing> {
        let tree = self.solid.tree.as_ref()?;
        let all: Vec<Option<Interval>> = (0..self.frames.len()).map(|i| self.interval(i, ray)).collect();
        self.first_hit_in_by(tree, &|i| all[i], t_min, &mut SpanScratch::default())
            .map(|h| self.crossing_on_ray(h, ray))
    }
}

thread_local! {
    /// Span buffers for [`CsgCaster::first_hit`], one per thread, so traced rays
    /// allocate nothing.
    static SCRATCH: std::cell::RefCell<SpanScratch> = std::cell::RefCell::default();
}

/// Reusable buffers for combining spans along a tree, so a pixel allocates
/// nothing: each node leaves its spans on top of `stack`.
#[derive(Debug, Clone, Default)]
pub struct SpanScratch {
    stack: Vec<Interval>,
    out: Vec<Interval>,
    /// The primitives whose boxes the ray crosses.
    met: Vec<u32>,
    /// The same as flags (all false between rays).
    crossed: Vec<bool>,
    /// The same as counts in the tree (empty between rays).
    counts: Occupied,
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
/// ([`crate::visibility::occupancy`]).
pub trait Booleans: Copy {
    /// The node's operation and operands.
    fn parts(self) -> Parts<Self, impl Iterator<Item = Self>>;

    /// The primitive, if the node is a leaf (what `parts` says, more cheaply).
    fn leaf(self) -> Option<usize>;
}

impl Booleans for &CsgTree {
    #[inline(always)]
    fn parts(self) -> Parts<Self, impl Iterator<Item = Self>> {
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
pub fn combine<B: Booleans>(tree: B, leaf: &impl Fn(usize) -> Option<Interval>, scratch: &mut SpanScratch) -> usize {
    let base = scratch.stack.len();
    let Parts { operation, first, others } = tree.parts();
    match operation {
        Operation::Leaf(i) => scratch.stack.extend(leaf(i)),
        Operation::Union => {
            let mut parts = 0;
            for k in others {
                match k.leaf() {
                    Some(i) => scratch.stack.extend(leaf(i)),
                    None => _ = combine(k, leaf, scratch),
                }
                parts += 1;
            }
            // One operand's spans are already sorted and disjoint.
            if parts > 1 {
                union(&mut scratch.stack, base);
            }
        }
        op @ (Operation::Intersection | Operation::Difference) => {
            let Some(first) = first else { return base };
            combine(first, leaf, scratch);
            for k in others {
                if scratch.stack.len() == base {
                    break; // nothing left to intersect with or cut from
                }
                if let Some(i) = k.leaf() {
                    // One interval or none: narrow or cut in place.
                    match (leaf(i), op) {
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

/// `t_min` lies inside a part of the solid.
struct Inside;

/// The first crossing beyond `t_min` of the subtree `tree` if it is an entry
/// (`None` if there is none); [`Inside`] if it is an exit.
fn first_entry<B: Booleans>(
    tree: B,
    leaf: &impl Fn(usize) -> Option<Interval>,
    t_min: f32,
    scratch: &mut SpanScratch,
) -> Result<Option<Hit>, Inside> {
    scratch.stack.clear();
    match tree.leaf() {
        Some(i) => scratch.stack.extend(leaf(i)),
        None => _ = combine(tree, leaf, scratch),
    }
    for s in &scratch.stack {
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
fn first_of_all<B: Booleans>(
    tree: B,
    leaf: &impl Fn(usize) -> Option<Interval>,
    t_min: f32,
    scratch: &mut SpanScratch,
) -> Option<Hit> {
    scratch.stack.clear();
    combine(tree, leaf, scratch);
    scratch.stack.iter().flat_map(|s| [s.enter, s.exit]).find(|c| c.t > t_min)
}

/// Merges the spans on `stack` from `base` into sorted disjoint spans covering
/// their union.
fn union(stack: &mut Vec<Interval>, base: usize) {
    stack[base..].sort_unstable_by(|x, y| x.enter.t.total_cmp(&y.enter.t));
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
fn difference(a: &[Interval], b: &[Interval], out: &mut Vec<Interval>) {
    for x in a {
        // `b` is sorted and disjoint: walk it once, cutting `x` from the left.
        let mut rest = Some(*x);
        for y in b {
            let Some(p) = rest else { break };
            let (lo, hi) = (y.enter.t - TIE * y.enter.t.abs().max(1.0), y.exit.t + TIE * y.exit.t.abs().max(1.0));
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
    let (lo, hi) = (y.enter.t - TIE * y.enter.t.abs().max(1.0), y.exit.t + TIE * y.exit.t.abs().max(1.0));
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

/// The span of `ray` inside primitive `p` (index `index`), if it meets it.
#[must_use]
pub fn primitive_span(p: &Primitive, index: usize, ray: &Ray) -> Option<Span> {
    let (to_unit, to_solid) = (p.transform.inverse(), normal_matrix(&p.transform));
    let (o, d) = (to_unit.transform_point3(ray.origin), to_unit.transform_vector3(ray.dir));
    let ((t0, f0), (t1, f1)) = unit_span(&p.shape, o, d)?;
    let crossing = |t: f32, face: u32| Crossing {
        t,
        normal: (to_solid * unit_normal(&p.shape, face, o + d * t)).normalize_or_zero(),
        primitive: index as u32,
        cut: false,
    };
    Some(Span { enter: crossing(t0, f0), exit: crossing(t1, f1) })
}

/// The (unnormalised) outward normal of a unit shape's face `face` at its
/// point `p`: the sphere's radius; a frustum's side (face [`SIDE`]) or caps
/// ([`BOTTOM`], [`TOP`]); a polyhedron's plane.
fn unit_normal(shape: &Shape, face: u32, p: Vec3) -> Vec3 {
    match shape {
        Shape::Sphere => p,
        Shape::Frustum { bottom, top } => match face {
            BOTTOM => Vec3::NEG_Z,
            TOP => Vec3::Z,
            _ => {
                let k = top - bottom;
                Vec3::new(p.x, p.y, -k * (bottom + k * p.z))
            }
        },
        Shape::Polyhedron(poly) => poly.planes[face as usize].truncate(),
    }
}

/// A frustum's faces ([`unit_normal`]).
const SIDE: u32 = 0;
/// See [`SIDE`].
const BOTTOM: u32 = 1;
/// See [`SIDE`].
const TOP: u32 = 2;

/// The span of the ray `o + t·d` inside a unit shape.
fn unit_span(shape: &Shape, o: Vec3, d: Vec3) -> Option<UnitSpan> {
    match shape {
        Shape::Sphere => sphere(o, d),
        Shape::Frustum { bottom, top } => frustum(*bottom, *top, o, d),
        Shape::Polyhedron(poly) => polyhedron(poly, o, d),
    }
}

/// The inverse transpose of the transform's linear part: carries normals.
fn normal_matrix(m: &Affine3A) -> Mat3A {
    m.matrix3.inverse().transpose()
}

/// A span in unit-shape space: entry and exit parameters with their faces
/// ([`unit_normal`]).
type UnitSpan = ((f32, u32), (f32, u32));

/// The roots of `a·t² + 2·b·t + c`, smaller first, if real.
fn roots(a: f32, b: f32, c: f32) -> Option<(f32, f32)> {
    let disc = b * b - a * c;
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    // The numerically stable pair: no subtraction of nearly equal numbers.
    let q = -(b + b.signum() * disc.sqrt());
    let (r0, r1) = (q / a, c / q);
    Some(if r0 < r1 { (r0, r1) } else { (r1, r0) })
}

/// The unit sphere.
fn sphere(o: Vec3, d: Vec3) -> Option<UnitSpan> {
    let (t0, t1) = roots(d.dot(d), o.dot(d), o.dot(o) - 1.0)?;
    Some(((t0, 0), (t1, 0)))
}

/// The frustum `0 ≤ z ≤ 1`, `x² + y² ≤ r(z)²`, `r(z) = bottom + (top − bottom)·z`:
/// the slab between the caps intersected with the quadric's inside, which within
/// the slab is one convex piece (the apex of a cone lies on a cap).
fn frustum(bottom: f32, top: f32, o: Vec3, d: Vec3) -> Option<UnitSpan> {
    let k = top - bottom;
    let slab = slab_z(o, d)?;
    let r_o = bottom + k * o.z;
    // f(t) = x² + y² − r(z)², inside where f ≤ 0.
    let (a, b, c) = (
        d.x * d.x + d.y * d.y - k * k * d.z * d.z,
        o.x * d.x + o.y * d.y - k * d.z * r_o,
        o.x * o.x + o.y * o.y - r_o * r_o,
    );
    const ALL: (f32, f32) = (f32::NEG_INFINITY, f32::INFINITY);
    const NONE: (f32, f32) = (f32::INFINITY, f32::NEG_INFINITY);
    let inside: [(f32, f32); 2] = match roots(a, b, c) {
        // The quadric's inside along the line is between the roots (a > 0) or
        // outside them (a < 0: the line runs steeper than the cone's side).
        Some((r0, r1)) if a > 0.0 => [(r0, r1), NONE],
        Some((r0, r1)) => [(f32::NEG_INFINITY, r0), (r1, f32::INFINITY)],
        // Linear along a line parallel to the cone's side: a half-line.
        None if a == 0.0 && b != 0.0 => {
            let t = -c / (2.0 * b);
            [if b > 0.0 { (f32::NEG_INFINITY, t) } else { (t, f32::INFINITY) }, NONE]
        }
        // No crossing: all inside or all outside, as at any one point.
        None if c <= 0.0 => [ALL, NONE],
        None => return None,
    };
    let ((s0, n0), (s1, n1)) = slab;
    let mut best: Option<UnitSpan> = None;
    for (q0, q1) in inside {
        let enter = if q0 > s0 { (q0, SIDE) } else { (s0, n0) };
        let exit = if q1 < s1 { (q1, SIDE) } else { (s1, n1) };
        if enter.0 < exit.0 {
            best = Some(match best {
                None => (enter, exit),
                Some((e, x)) => (if e.0 <= enter.0 { e } else { enter }, if x.0 >= exit.0 { x } else { exit }),
            });
        }
    }
    best
}

/// The slab `0 ≤ z ≤ 1` with its caps.
fn slab_z(o: Vec3, d: Vec3) -> Option<UnitSpan> {
    if d.z == 0.0 {
        return (0.0..=1.0).contains(&o.z).then_some(((f32::NEG_INFINITY, BOTTOM), (f32::INFINITY, TOP)));
    }
    let (ta, tb) = (-o.z / d.z, (1.0 - o.z) / d.z);
    Some(if d.z > 0.0 { ((ta, BOTTOM), (tb, TOP)) } else { ((tb, TOP), (ta, BOTTOM)) })
}

/// The unit cube ([`ConvexPolyhedron::unit_cube`]) by slabs: per axis, the
/// planes at 0 and 1, one entering and one leaving, each `t` found as
/// [`polyhedron`] finds it from the cube's planes (so the same to the bit, with
/// the same faces), without the dot products.
fn unit_cube(o: Vec3, d: Vec3) -> Option<UnitSpan> {
    // Both planes of every axis at once: two vector divisions.
    let (o, d) = (Vec3A::from(o), Vec3A::from(d));
    let (ones, zeros) = ((Vec3A::ONE - o) / d, -o / d);
    let (mut enter, mut exit) = ((f32::NEG_INFINITY, 0), (f32::INFINITY, 0));
    for axis in 0..3 {
        // Faces 2·axis (the plane at 1, outward +axis) and 2·axis + 1 (at 0).
        let (o, d, face) = (o[axis], d[axis], 2 * axis as u32);
        if d == 0.0 {
            // Parallel to both planes: outside one of them (as the plane
            // clipping tests it: a NaN passes) misses.
            if 1.0 - o < 0.0 || o < 0.0 {
                return None;
            }
            continue;
        }
        let (at_one, at_zero) = (ones[axis], zeros[axis]);
        let (inward, outward) =
            if d > 0.0 { ((at_zero, face + 1), (at_one, face)) } else { ((at_one, face), (at_zero, face + 1)) };
        if outward.0 < exit.0 {
            exit = outward;
        }
        if inward.0 > enter.0 {
            enter = inward;
        }
    }
    (enter.0 < exit.0 && enter.0.is_finite() && exit.0.is_finite()).then_some((enter, exit))
}

/// How a caster cuts a primitive's unit shape.
#[derive(Debug, Clone)]
enum Clipping {
    /// The shape's own procedure ([`unit_span`]).
    Shape,
    /// The unit cube, by slabs ([`unit_cube`]).
    Box,
    /// A convex polyhedron of many planes, eight planes at a time.
    Lanes(Box<PlaneLanes>),
}

/// A convex polyhedron's planes in lanes of eight (structure of arrays): a
/// ray is clipped by eight planes with one division. Lanes past the last plane
/// hold `0·p ≤ 1`, which clips nothing.
#[derive(Debug, Clone)]
struct PlaneLanes {
    normal: [Vec<f32x8>; 3],
    w: Vec<f32x8>,
    /// Its faces' corners, for leaving out faces a scanline cannot cross.
    corners: Option<lanes::FaceCorners>,
}

impl PlaneLanes {
    /// Planes from which lanes pay: below, a plane-by-plane loop is as quick
    /// as one pass of lanes and the reduction of their answers (measured: a
    /// pyramid's five planes, bevel gears' teeth of eight: 10–15% slower in
    /// lanes; the hull of eight faceted balls, hundreds of planes: 3x faster).
    const MIN_PLANES: usize = 16;

    fn new(poly: &ConvexPolyhedron) -> PlaneLanes {
        let lanes = |f: fn(&Vec4) -> f32, pad: f32| -> Vec<f32x8> {
            poly.planes.chunks(8).map(|c| f32x8::new(std::array::from_fn(|j| c.get(j).map_or(pad, f)))).collect()
        };
        PlaneLanes {
            normal: [lanes(|p| p.x, 0.0), lanes(|p| p.y, 0.0), lanes(|p| p.z, 0.0)],
            w: lanes(|p| p.w, 1.0),
            corners: lanes::FaceCorners::new(poly),
        }
    }

    /// What [`polyhedron`] gives for the same planes, the same `t` to the bit
    /// and the same faces: each lane keeps the first of its planes with the
    /// latest entry (earliest exit), and of the lanes tied at the end the one
    /// with the first plane wins. Never inlined: it is for polyhedra of many
    /// planes, and inlined into the per-pixel interval it slowed the boxes'
    /// and small polyhedra's path by 10%.
    #[inline(never)]
    fn clip(&self, o: Vec3, d: Vec3) -> Option<UnitSpan> {
        let s = f32x8::splat;
        let ([ox, oy, oz], [dx, dy, dz]) = (o.to_array().map(s), d.to_array().map(s));
        let zero = f32x8::ZERO;
        let (mut enter, mut exit) = ((s(f32::NEG_INFINITY), zero), (s(f32::INFINITY), zero));
        let mut miss = zero;
        let mut face = f32x8::new(std::array::from_fn(|j| j as f32));
        for (k, &w) in self.w.iter().enumerate() {
            let [nx, ny, nz] = [self.normal[0][k], self.normal[1][k], self.normal[2][k]];
            let along = nx * dx + ny * dy + nz * dz;
            let gap = w - (nx * ox + ny * oy + nz * oz);
            // Parallel to a plane and outside it: the ray misses.
            miss |= along.simd_eq(zero) & gap.simd_lt(zero);
            let t = gap / along;
            let leaves = along.simd_gt(zero) & t.simd_lt(exit.0);
            exit = (leaves.select(t, exit.0), leaves.select(face, exit.1));
            let enters = along.simd_lt(zero) & t.simd_gt(enter.0);
            enter = (enters.select(t, enter.0), enters.select(face, enter.1));
            face += s(8.0);
        }
        if miss.any() {
            return None;
        }
        let (enter, exit) = (first_of_lanes(enter, |a, b| a > b), first_of_lanes(exit, |a, b| a < b));
        (enter.0 < exit.0 && enter.0.is_finite() && exit.0.is_finite()).then_some((enter, exit))
    }
}

/// Of eight lanes' `(t, face)`, the `t` no other is `later` than, on a tie
/// the one with the first face.
#[inline(always)]
fn first_of_lanes((t, face): (f32x8, f32x8), later: impl Fn(f32, f32) -> bool) -> (f32, u32) {
    let (t, face) = (t.to_array(), face.to_array());
    let mut best = (t[0], face[0] as u32);
    for j in 1..8 {
        let f = face[j] as u32;
        if later(t[j], best.0) || (t[j] == best.0 && f < best.1) {
            best = (t[j], f);
        }
    }
    best
}

/// A convex polyhedron: the ray clipped by every face plane.
fn polyhedron(poly: &ConvexPolyhedron, o: Vec3, d: Vec3) -> Option<UnitSpan> {
    let (mut enter, mut exit) = ((f32::NEG_INFINITY, 0), (f32::INFINITY, 0));
    for (face, plane) in (0..).zip(&poly.planes) {
        let n = plane.truncate();
        let (along, gap) = (n.dot(d), plane.w - n.dot(o));
        if along == 0.0 {
            if gap < 0.0 {
                return None;
            }
            continue;
        }
        let t = gap / along;
        if along > 0.0 {
            if t < exit.0 {
                exit = (t, face);
            }
        } else if t > enter.0 {
            enter = (t, face);
        }
    }
    (enter.0 < exit.0 && enter.0.is_finite() && exit.0.is_finite()).then_some((enter, exit))
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// A coordinate, sometimes exactly on one of the cube's planes.
    fn coordinate(range: std::ops::Range<f32>) -> impl Strategy<Value = f32> {
        prop_oneof![4 => range, 1 => Just(0.0f32), 1 => Just(1.0f32)]
    }

    fn vector(range: std::ops::Range<f32>) -> impl Strategy<Value = Vec3> {
        (coordinate(range.clone()), coordinate(range.clone()), coordinate(range))
            .prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

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

    /// A ball of `rings` bands of `sides` flat quadrilaterals (its corners
    /// on the unit sphere), closed by two flat caps.
    fn faceted_ball(rings: usize, sides: usize) -> ConvexPolyhedron {
        let corner = |k: usize, j: usize| {
            let (phi, theta) =
                (std::f32::consts::PI * k as f32 / rings as f32, std::f32::consts::TAU * j as f32 / sides as f32);
            Vec3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), phi.cos())
        };
        let vertices: Vec<Vec3> = (1..rings).flat_map(|k| (0..sides).map(move |j| corner(k, j))).collect();
        let mut planes = vec![Vec3::Z.extend(corner(1, 0).z), Vec3::NEG_Z.extend(-corner(rings - 1, 0).z)];
        for k in 1..rings - 1 {
            for j in 0..sides {
                let (a, b, c) = (corner(k, j), corner(k, j + 1), corner(k + 1, j));
                let n = (b - a).cross(c - a).normalize();
                let n = if n.dot(a) < 0.0 { -n } else { n };
                planes.push(n.extend(n.dot(a)));
            }
        }
        ConvexPolyhedron { planes, vertices }
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

        /// Eight planes at a time clip as plane by plane does: the same `t`
        /// to the bit and the same faces, for random planes (some axis
        /// aligned, some repeated so that faces tie) and rays (some parallel
        /// to a plane), any number of planes (lanes left over included).
        #[test]
        fn planes_in_lanes_clip_as_plane_by_plane(
            normals in prop::collection::vec(vector(-1.0..1.0), 1..40),
            offsets in prop::collection::vec(prop_oneof![0.2f32..2.0, Just(1.0f32)], 40),
            o in vector(-1.0..1.0),
            d in vector(-2.0..2.0),
        ) {
            let mut planes: Vec<Vec4> = normals.iter().zip(&offsets).map(|(n, &w)| n.extend(w)).collect();
            planes.extend_from_within(..planes.len() / 3);
            let poly = ConvexPolyhedron { planes, vertices: Vec::new() };
            prop_assert_eq!(PlaneLanes::new(&poly).clip(o, d), polyhedron(&poly, o, d));
        }

        /// A polyhedron of many faces clipped, row by row, by only the faces
        /// the row's plane meets gives each pixel's interval as every face
        /// does, to the bit: a faceted ball of 74 faces and random rows.
        #[test]
        fn a_row_clipped_by_the_faces_it_meets_is_clipped_by_all(
            line in (vector(-1.5..1.5), vector(-0.05..0.05), vector(-2.0..2.0), vector(-0.05..0.05)),
            x0 in 0u32..24,
            ortho in any::<bool>(),
        ) {
            let (origin, mut origin_step, dir, mut dir_step) = line;
            // A row's rays share an eye (perspective) or a direction.
            if ortho { dir_step = Vec3::ZERO } else { origin_step = Vec3::ZERO }
            let primitive = Primitive {
                shape: Shape::Polyhedron(faceted_ball(8, 12)),
                transform: Affine3A::IDENTITY,
                color: None,
                source: 0..0,
            };
            let caster = CsgCaster::new(&CsgSolid { primitives: vec![primitive], tree: Some(CsgTree::Leaf(0)) });
            let line = RowLine { origin, origin_step, dir, dir_step };
            let mut row = RowFaces::default();
            caster.row_faces(0, &line, &mut row);
            prop_assert!(row.active);
            let eight = caster.spans_on_eight(0, &line, x0 as f32, &row);
            let bits = |s: Option<Interval>| s.map(|s| (s.enter.t.to_bits(), s.enter.face, s.exit.t.to_bits(), s.exit.face));
            for j in 0..8 {
                prop_assert_eq!(bits(eight.get(j)), bits(caster.span_on(0, &line, (x0 + j as u32) as f32)), "pixel {}", j);
            }
        }

        /// The slab test of a box gives what clipping by the unit cube's
        /// planes gives: the same parameters to the bit and the same faces,
        /// rays parallel to a face and rays along one included.
        #[test]
        fn a_box_by_slabs_is_the_cube_by_planes(o in vector(-2.0..3.0), d in vector(-2.0..2.0)) {
            prop_assert_eq!(unit_cube(o, d), polyhedron(&ConvexPolyhedron::unit_cube(), o, d));
        }
    }

    proptest! {
        // Cheap cases, and the rare ones (a row in a cap's plane) need many.
        #![proptest_config(ProptestConfig::with_cases(4096))]

        /// Eight pixels in lanes give each pixel's interval as one pixel at a
        /// time does, to the bit, with the same faces: every unit shape (a
        /// cone's apex and a flat cylinder included, a box by slabs, a few
        /// planes and many, some tied), rows whose rays run parallel to an
        /// axis.
        #[test]
        fn eight_pixels_in_lanes_are_each_pixel_alone(
            kind in 0usize..5,
            radii in (prop_oneof![0.0f32..2.0, Just(0.0f32), Just(1.0f32)], prop_oneof![0.0f32..2.0, Just(1.0f32)]),
            normals in prop::collection::vec(vector(-1.0..1.0), 8..24),
            line in (vector(-1.5..1.5), vector(-0.05..0.05), vector(-2.0..2.0), vector(-0.05..0.05)),
            x0 in 0u32..24,
            flat in 0usize..6,
        ) {
            let (origin, origin_step, mut dir, mut dir_step) = line;
            if flat < 3 {
                // The row's rays all parallel to a pair of faces.
                (dir[flat], dir_step[flat]) = (0.0, 0.0);
            }
            // Some planes twice, so that faces tie.
            let planes = |n: usize| normals.iter().take(n).chain(&normals[..2]).map(|v| v.extend(1.0)).collect();
            let shape = match kind {
                0 => Shape::Sphere,
                1 => Shape::Frustum { bottom: radii.0, top: radii.1 },
                2 => Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
                3 => Shape::Polyhedron(ConvexPolyhedron { planes: planes(8), vertices: Vec::new() }),
                _ => Shape::Polyhedron(ConvexPolyhedron { planes: planes(24), vertices: Vec::new() }),
            };
            let primitive = Primitive { shape, transform: Affine3A::IDENTITY, color: None, source: 0..0 };
            let caster = CsgCaster::new(&CsgSolid { primitives: vec![primitive], tree: Some(CsgTree::Leaf(0)) });
            let line = RowLine { origin, origin_step, dir, dir_step };
            let eight = caster.spans_on_eight(0, &line, x0 as f32, &RowFaces::default());
            let bits = |s: Option<Interval>| s.map(|s| (s.enter.t.to_bits(), s.enter.face, s.exit.t.to_bits(), s.exit.face));
            for j in 0..8 {
                prop_assert_eq!(bits(eight.get(j)), bits(caster.span_on(0, &line, (x0 + j as u32) as f32)), "pixel {}", j);
            }
        }
    }
}
