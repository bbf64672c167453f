//! Ray casting of CSG solids: the depth interval a ray spends inside each
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
//! The parts: `shapes` (each unit shape's crossings and normals), `booleans`
//! (the intervals combined along the tree; coplanar cuts decided by [`TIE`]),
//! `lanes` (eight pixels of a scanline at once, for the scanline walk), and
//! `faces` (which of a many-planed polyhedron's faces a block of eight
//! pixels can cross).

use glam::{Affine3A, Mat3A, Vec3, Vec3A};

use super::model::{ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Shape};
use super::occupancy::OccupancyTree;
use crate::bvh::{Aabb, Bvh};
use crate::camera::{Ray, RowLine};

use super::booleans::{
    combine, difference, first_crossing, first_entry, first_of_all, union, Booleans, Inside, LeafSpans, Operation,
    Parts, SpanScratch,
};
use super::faces::{self, FacesOnScreen, RowFaces};
use super::hit::{Crossing, Hit, Interval, IntervalLanes, Span};
use super::lanes;
use super::shapes::{self, normal_matrix, unit_cube, unit_normal, unit_span, Clipping, PlaneLanes};

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
    /// Per primitive: the box `(min, max)` around its unit shape.
    unit_boxes: Vec<(Vec3A, Vec3A)>,
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
        let unit_boxes = solid
            .primitives
            .iter()
            .map(|p| {
                p.unit_corners()
                    .into_iter()
                    .fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |(lo, hi), c| (lo.min(c.into()), hi.max(c.into())))
            })
            .collect();
        let n = solid.primitives.len();
        let bvh = solid.tree.as_ref().filter(|_| bvh && n >= Self::BVH_PRIMITIVES).map(|tree| {
            let boxes: Vec<Aabb> = solid.primitives.iter().map(|p| Aabb::around(&p.corners())).collect();
            (Bvh::build(&boxes), OccupancyTree::new(tree, n))
        });
        CsgCaster { solid, frames, clipping, unit_boxes, bvh }
    }

    /// The box `(min, max)` around primitive `i`'s unit shape (the space of
    /// [`CsgCaster::unit_line`]).
    #[must_use]
    pub fn unit_box(&self, i: usize) -> (Vec3A, Vec3A) {
        self.unit_boxes[i]
    }

    /// Primitives from which [`CsgCaster::first_hit`] culls by a BVH.
    pub const BVH_PRIMITIVES: usize = 8;

    /// A ray's booleans count the primitives it meets ([`Occupied`](crate::csg::occupancy::Occupied)) when
    /// they are fewer than the tree's nodes over this, and walk the whole
    /// tree otherwise: counting one costs about as much as walking four nodes
    /// (measured on a solid whose rays meet a third of its hundreds of
    /// cutters, and on one whose rays meet a few of its thousand parts).
    const NODES_PER_COUNTED: usize = 4;

    /// Operands from which a union's first hit visits them nearest box
    /// first and stops past the nearest hit (fewer are read in turn: the
    /// ordering costs more than it saves). On a union of 101 stacked closed
    /// meshes (Round-Anything's radius extrusion, 960 × 540) it cut the edge
    /// pass's rays from 1.99 s to 0.36 s, the image unchanged to the bit.
    const PRUNED_UNION: usize = 8;

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
    ///
    /// `screen`, when given, is [`CsgCaster::faces_on_screen`]'s answer and
    /// the scanline's index: the faces that show on the scanline are kept
    /// (without measuring each face's corners against the line's plane),
    /// sorted by the blocks of eight pixels their columns reach there, so
    /// that a block clips by the faces over it alone.
    pub fn row_faces(&self, i: usize, unit: &RowLine, screen: Option<(&FacesOnScreen, usize)>, row: &mut RowFaces) {
        row.off();
        let Clipping::Lanes(lanes) = &self.clipping[i] else { return };
        let Some(corners) = &lanes.corners else { return };
        row.find(match screen {
            Some((screen, y)) => faces::Sieve::Screen(screen, y),
            None => faces::Sieve::Plane(corners, unit),
        });
    }

    /// For a polyhedron of many planes, where each face shows in a `size`
    /// frame ([`FacesOnScreen`]; `project` gives a solid-space point's pixel
    /// coordinates, a pixel's centre at `x + ½, y + ½`). `None` for other
    /// primitives, or when a corner has no projection (at or behind the
    /// eye).
    pub fn faces_on_screen(
        &self,
        i: usize,
        project: impl Fn(Vec3) -> Option<glam::Vec2>,
        size: (usize, usize),
    ) -> Option<FacesOnScreen> {
        let Clipping::Lanes(lanes) = &self.clipping[i] else { return None };
        let to_solid = self.solid.primitives[i].transform;
        let corners = lanes.corners.as_ref()?;
        let at = corners.projected(|c| project(to_solid.transform_point3(c)))?;
        Some(FacesOnScreen::new(corners, &at, size))
    }

    /// [`CsgCaster::span_on`] at the eight pixels `8·block..8·block + 8` of
    /// `unit` at once, in SIMD lanes: each the same to the bit as `span_on`
    /// gives it (a polyhedron of many planes clipped by the faces `row`
    /// keeps over the block, from [`CsgCaster::row_faces`] on the same line:
    /// property tests hold both to every face), written into `out` (the
    /// walk's cache, so the lanes are not returned and then copied). With
    /// the faces kept by where they show on the screen, that holds at the
    /// pixels within the primitive's outline on the row (which are all the
    /// walk reads); a pixel further out than a pixel may meet the wedge the
    /// kept faces bound where the primitive itself is missed.
    pub fn spans_on_eight(&self, i: usize, unit: &RowLine, block: usize, row: &RowFaces, out: &mut IntervalLanes) {
        let rays = lanes::RayLanes::new(unit, (block * 8) as f32);
        let shape = &self.solid.primitives[i].shape;
        let spans = match (&self.clipping[i], shape) {
            (Clipping::Box, _) => lanes::unit_cube(&rays),
            (Clipping::Lanes(_), Shape::Polyhedron(poly)) if row.active => {
                lanes::planes(row.over(block).map(|f| (f, &poly.planes[f as usize])), &rays)
            }
            _ => match lanes::shape(shape, &rays) {
                Some(spans) => spans,
                None => return self.spans_one_by_one(i, unit, block, out),
            },
        };
        // Faces are small whole numbers: converted in lanes (one by one, the
        // saturating `as` was a quarter of the fill).
        let face = |f: wide::f32x8| f.trunc_int().to_array().map(|f| f as u32);
        *out = IntervalLanes {
            t: [spans.enter.0.to_array(), spans.exit.0.to_array()],
            face: [face(spans.enter.1), face(spans.exit.1)],
            hit: spans.hit.to_bitmask() as u8,
            primitive: i as u32,
        };
    }

    /// [`CsgCaster::spans_on_eight`] pixel by pixel ([`CsgCaster::span_on`]):
    /// a mesh's layers, whose intervals come from its triangles.
    fn spans_one_by_one(&self, i: usize, unit: &RowLine, block: usize, out: &mut IntervalLanes) {
        *out = IntervalLanes::from_fn(i, |j| self.span_on(i, unit, (block * 8 + j) as f32));
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

    /// [`CsgCaster::crossing_on_line`] at the eight pixels `x0..x0 + 8` of
    /// `unit`, each showing `hit`'s face (its primitive, face and hole-wall
    /// bit) at its own `t`: in lanes, each the scalar crossing to the bit.
    #[must_use]
    pub fn crossings_on_eight(&self, hit: Hit, t: [f32; 8], unit: &RowLine, x0: usize) -> [Crossing; 8] {
        let i = hit.primitive as usize;
        let rays = lanes::RayLanes::new(unit, x0 as f32);
        let shape = &self.solid.primitives[i].shape;
        let cut = hit.cut();
        let n = lanes::normals(shape, hit.face & !Hit::CUT, &rays, wide::f32x8::new(t), &self.frames[i].1)
            .map(|c| if cut { -c } else { c }.to_array());
        std::array::from_fn(|j| Crossing {
            t: t[j],
            normal: Vec3::new(n[0][j], n[1][j], n[2][j]),
            primitive: hit.primitive,
            cut,
        })
    }

    /// Whether `hit`'s face is flat (a polyhedron's plane, a frustum's cap):
    /// its normal is then the same at every point of it.
    #[must_use]
    pub fn flat(&self, hit: Hit) -> bool {
        match &self.solid.primitives[hit.primitive as usize].shape {
            Shape::Sphere => false,
            Shape::Frustum { .. } => hit.face & !Hit::CUT != shapes::SIDE,
            Shape::Polyhedron(_) | Shape::Mesh { .. } => true,
        }
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
        self.first_hit_in_by(tree, &RaySpans { caster: self, ray }, t_min, scratch)
            .map(|h| self.crossing_on_ray(h, ray))
    }

    /// The first surface at `t > t_min` of the solid `tree` describes (seed
    /// 003's nearest surface over segments), each primitive's interval from
    /// `leaf` — e.g. [`CsgCaster::span_on`] — with buffers reused from pixel
    /// to pixel. Its normal is found by the caller, who knows the ray
    /// ([`CsgCaster::crossing_on_line`]).
    ///
    /// A union's operands are not merged when they need not be: where `t_min`
    /// lies outside every operand, the union's first surface is the nearest
    /// of the operands' first entries (on a tie, the one of the primitive
    /// first in the file: [`Hit::nearer_than`]; the scanline walk meets a
    /// union's operands in the order they came to occupy the row, the ray
    /// caster in the tree's), so each operand is combined on its own and only
    /// its first entry kept. An operand holding `t_min` (the near plane inside
    /// the solid) sends the pixel to the full merge.
    pub fn first_hit_in_by<B: Booleans>(
        &self,
        tree: B,
        leaf: &impl LeafSpans,
        t_min: f32,
        scratch: &mut SpanScratch,
    ) -> Option<Hit> {
        if let Some(i) = tree.leaf() {
            // One primitive: its own entry, or its exit from inside it.
            return first_crossing(&[leaf.span(i)?], t_min);
        }
        let Parts { operation, others, .. } = tree.parts();
        if operation == Operation::Union {
            let mut nearest: Option<Hit> = None;
            // Each operand's first entry; `Err` when the ray starts inside one.
            let mut read = |k: B, nearest: &mut Option<Hit>| {
                if let Some(h) = first_entry(k, leaf, t_min, scratch)? {
                    if nearest.is_none_or(|n| h.nearer_than(&n)) {
                        *nearest = Some(h);
                    }
                }
                Ok::<(), Inside>(())
            };
            let outside = if others.clone().nth(Self::PRUNED_UNION - 1).is_some() {
                // Many operands: nearest box first, none past the nearest hit.
                let bound = |k: B| k.leaf().map_or(f32::NEG_INFINITY, |i| leaf.entry_bound(i));
                let mut order: Vec<(f32, B)> = others.map(|k| (bound(k), k)).collect();
                order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
                let mut outside = Ok(());
                for (bound, k) in order {
                    if nearest.is_some_and(|n| n.t < bound) {
                        break;
                    }
                    outside = read(k, &mut nearest);
                    if outside.is_err() {
                        break;
                    }
                }
                outside
            } else {
                others.into_iter().try_for_each(|k| read(k, &mut nearest))
            };
            return match outside {
                Ok(()) => nearest,
                Err(Inside) => first_of_all(tree, leaf, t_min, scratch),
            };
        }
        first_of_all(tree, leaf, t_min, scratch)
    }

    /// The first surface beyond `t_min` of a union of segments (seed 003
    /// §5.2.1's pattern matrix), each given as its positive and its negative
    /// primitives: per segment, the intersection of its positive primitives'
    /// intervals minus the intervals of its negative primitives that
    /// `occupying` says cover the pixel; the nearest over the segments.
    /// `span` gives a primitive's interval ([`CsgCaster::span_on`], cached by
    /// the caller), who finds the normal of the hit returned.
    pub fn first_hit_of_segments<'s>(
        &self,
        segments: impl IntoIterator<Item = (&'s [usize], &'s [usize])>,
        occupying: &impl Fn(usize) -> bool,
        span: &mut impl FnMut(usize) -> Option<Interval>,
        t_min: f32,
        scratch: &mut SpanScratch,
    ) -> Option<Hit> {
        scratch.stack.clear();
        let mut parts = 0;
        'segments: for (positive, negative) in segments {
            let mut inside: Option<Interval> = None;
            for &i in positive {
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
            for &i in negative.iter().filter(|&&i| occupying(i)) {
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
            union(scratch, 0);
        }
        first_crossing(&scratch.stack, t_min)
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
            bvh.crossed(ray, t_max, |i| met.push(i));
            let hit = if met.len() * Self::NODES_PER_COUNTED < shape.len() {
                // Few primitives met: they occupy the ray (seed 003's counts,
                // [`OccupancyTree`]) and the booleans visit only what they make
                // non-empty.
                let mut counts = std::mem::take(&mut s.counts);
                counts.fit(shape);
                met.iter().for_each(|&i| counts.set(shape, i as usize, true));
                let root = counts.root(shape);
                let hit = root.and_then(|root| self.first_hit_in_by(root, &RaySpans { caster: self, ray }, t_min, s));
                counts.clear(shape);
                s.counts = counts;
                hit
            } else {
                // Most of the tree met: walk all of it, the others missed.
                let mut crossed = std::mem::take(&mut s.crossed);
                crossed.resize(self.frames.len(), false);
                met.iter().for_each(|&i| crossed[i as usize] = true);
                let leaf = RaySpans { caster: self, ray };
                let leaf = Crossed { crossed: &crossed, leaf };
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
        SCRATCH.with_borrow_mut(|s| {
            // The thread's buffers, so the baseline pays for no allocation.
            let mut all = std::mem::take(&mut s.intervals);
            all.clear();
            all.extend((0..self.frames.len()).map(|i| self.interval(i, ray)));
            let hit = self.first_hit_in_by(tree, &|i| all[i], t_min, s);
            s.intervals = all;
            hit.map(|h| self.crossing_on_ray(h, ray))
        })
    }
}

thread_local! {
    /// Span buffers for [`CsgCaster::first_hit`], one per thread, so traced rays
    /// allocate nothing.
    static SCRATCH: std::cell::RefCell<SpanScratch> = std::cell::RefCell::default();
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

/// The spans of one ray, with where it enters each primitive's box.
struct RaySpans<'a> {
    caster: &'a CsgCaster,
    ray: &'a Ray,
}

impl LeafSpans for RaySpans<'_> {
    #[inline(always)]
    fn span(&self, i: usize) -> Option<Interval> {
        self.caster.interval(i, self.ray)
    }

    fn entry_bound(&self, i: usize) -> f32 {
        let (o, d) = self.caster.unit_ray(i, self.ray);
        let (lo, hi) = self.caster.unit_boxes[i];
        let inv = Vec3A::ONE / Vec3A::from(d);
        let (a, b) = ((lo - Vec3A::from(o)) * inv, (hi - Vec3A::from(o)) * inv);
        let (near, far) = (a.min(b).max_element(), a.max(b).min_element());
        if near.is_nan() || far.is_nan() {
            return f32::NEG_INFINITY;
        }
        if near > far {
            return f32::INFINITY;
        }
        // A little short of the box, for rounding in the primitive's own cut.
        near - 1e-4 * near.abs().max(1.0)
    }
}

/// [`RaySpans`] of the primitives a ray's boxes crossed only.
struct Crossed<'a> {
    crossed: &'a [bool],
    leaf: RaySpans<'a>,
}

impl LeafSpans for Crossed<'_> {
    #[inline(always)]
    fn span(&self, i: usize) -> Option<Interval> {
        if self.crossed[i] {
            self.leaf.span(i)
        } else {
            None
        }
    }

    fn entry_bound(&self, i: usize) -> f32 {
        if self.crossed[i] {
            self.leaf.entry_bound(i)
        } else {
            f32::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::shapes::tests::vector;
    use super::*;

    /// Primitive 0's eight pixels of block `block` of `line` in lanes
    /// (clipped by the faces `row` keeps) equal each pixel's alone: the same
    /// `t` to the bit, the same faces.
    fn eight_as_one_by_one(
        caster: &CsgCaster,
        line: &RowLine,
        block: usize,
        row: &RowFaces,
    ) -> Result<(), TestCaseError> {
        eight_as_one_by_one_within(caster, line, block, row, (i64::MIN, i64::MAX))
    }

    /// [`eight_as_one_by_one`] at the pixels of the block within `columns`.
    fn eight_as_one_by_one_within(
        caster: &CsgCaster,
        line: &RowLine,
        block: usize,
        row: &RowFaces,
        (first, last): (i64, i64),
    ) -> Result<(), TestCaseError> {
        let mut eight = IntervalLanes::default();
        caster.spans_on_eight(0, line, block, row, &mut eight);
        let bits =
            |s: Option<Interval>| s.map(|s| (s.enter.t.to_bits(), s.enter.face, s.exit.t.to_bits(), s.exit.face));
        for j in (0..8).filter(|&j| (first..=last).contains(&((block * 8 + j) as i64))) {
            prop_assert_eq!(bits(eight.get(j)), bits(caster.span_on(0, line, (block * 8 + j) as f32)), "pixel {}", j);
        }
        Ok(())
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
        /// A polyhedron of many faces clipped, row by row, by only the faces
        /// the row's plane meets gives each pixel's interval as every face
        /// does, to the bit: a faceted ball of 74 faces and random rows.
        #[test]
        fn a_row_clipped_by_the_faces_it_meets_is_clipped_by_all(
            line in (vector(-1.5..1.5), vector(-0.05..0.05), vector(-2.0..2.0), vector(-0.05..0.05)),
            block in 0usize..3,
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
            caster.row_faces(0, &line, None, &mut row);
            prop_assert!(row.active);
            eight_as_one_by_one(&caster, &line, block, &row)?;
        }

        /// The same with the faces picked by where they show
        /// ([`CsgCaster::faces_on_screen`]: a row's faces by their rows, a
        /// block's by their columns): a turned, stretched faceted ball seen
        /// by a random camera, at every pixel of a random scanline the walk
        /// reads — within the ball's outline there (procedure 2's ends,
        /// `outline.rs`). Further out, the faces kept over a block may bound
        /// a wedge that a ray meets although it misses the ball.
        #[test]
        fn a_block_clipped_by_the_faces_over_it_is_clipped_by_all(
            eye in vector(-4.0..4.0),
            turn in vector(-3.0..3.0),
            stretch in vector(0.5..1.5),
            y in 0usize..120,
            ortho in any::<bool>(),
        ) {
            use crate::camera::{Camera, Projection};
            let eye = eye + Vec3::new(0.0, 0.0, 4.0);
            let transform = Affine3A::from_scale_rotation_translation(
                stretch.max(Vec3::splat(0.5)),
                glam::Quat::from_euler(glam::EulerRot::XYZ, turn.x, turn.y, turn.z),
                Vec3::ZERO,
            );
            let primitive =
                Primitive { shape: Shape::Polyhedron(faceted_ball(8, 12)), transform, color: None, source: 0..0 };
            let caster = CsgCaster::new(&CsgSolid { primitives: vec![primitive], tree: Some(CsgTree::Leaf(0)) });
            let projection = if ortho {
                Projection::Orthographic { height: 4.0 }
            } else {
                Projection::Perspective { fov_y_deg: 60.0 }
            };
            let camera =
                Camera { eye, target: Vec3::ZERO, up: Vec3::Y, near: 0.05, far: 100.0, projection, shift: glam::Vec2::ZERO };
            let (w, h) = (160u32, 120u32);
            let vp = camera.view_projection(w as f32 / h as f32);
            let screen = caster.faces_on_screen(0, |p| {
                let c = vp * p.extend(1.0);
                (c.w > 1e-6).then(|| glam::Vec2::new((0.5 + 0.5 * c.x / c.w) * w as f32, (0.5 - 0.5 * c.y / c.w) * h as f32))
            }, (w as usize, h as usize));
            let Some(screen) = screen else { return Ok(()) }; // the eye inside the ball's hull
            let line = caster.unit_line(0, &camera.pixel_rays(glam::Vec2::new(w as f32, h as f32)).row_line(y));
            let mut row = RowFaces::default();
            caster.row_faces(0, &line, Some((&screen, y)), &mut row);
            prop_assert!(row.active);
            let rays = camera.pixel_rays(glam::Vec2::new(w as f32, h as f32));
            let outline = crate::csg::outline::Outline::new(&caster.solid().primitives[0], vp, &rays);
            let Some(columns) = outline.and_then(|o| o.columns(y as i64)) else { return Ok(()) };
            for block in 0..w as usize / 8 {
                eight_as_one_by_one_within(&caster, &line, block, &row, columns)?;
            }
        }
    }

    proptest! {
        /// Eight crossings of one face given their normals in lanes
        /// ([`CsgCaster::crossings_on_eight`]) are each pixel's alone
        /// ([`CsgCaster::crossing_on_line`]) to the bit: spheres and frustums
        /// (side and caps) under random turns and stretches, hole walls, rays
        /// of a perspective or an orthographic row, zero normals included
        /// (a cone's apex, `t` where the sphere's centre lies).
        #[test]
        fn crossings_in_lanes_are_each_pixel_alone(
            kind in 0usize..3,
            radii in (prop_oneof![0.0f32..2.0, Just(0.0f32)], 0.0f32..2.0),
            turn in vector(-3.0..3.0),
            stretch in vector(0.2..3.0),
            line in (vector(-1.5..1.5), vector(-0.05..0.05), vector(-2.0..2.0), vector(-0.05..0.05)),
            t in prop::array::uniform8(prop_oneof![0.0f32..4.0, Just(0.0f32)]),
            block in 0usize..3,
            cut in any::<bool>(),
            from_centre in any::<bool>(),
        ) {
            let (shape, face) = match kind {
                0 => (Shape::Sphere, 0),
                k => (Shape::Frustum { bottom: radii.0, top: radii.1 }, if k == 1 { shapes::SIDE } else { shapes::TOP }),
            };
            let transform = Affine3A::from_scale_rotation_translation(
                stretch,
                glam::Quat::from_euler(glam::EulerRot::XYZ, turn.x, turn.y, turn.z),
                turn,
            );
            let primitive = Primitive { shape, transform, color: None, source: 0..0 };
            let caster = CsgCaster::new(&CsgSolid { primitives: vec![primitive], tree: Some(CsgTree::Leaf(0)) });
            let (mut origin, mut origin_step, dir, dir_step) = line;
            if from_centre {
                // Rays from the unit shape's origin: at t = 0, a zero normal.
                (origin, origin_step) = (Vec3::ZERO, Vec3::ZERO);
            }
            let line = RowLine { origin, origin_step, dir, dir_step };
            let hit = Hit::new(0.0, 0, face).with_cut(cut);
            let eight = caster.crossings_on_eight(hit, t, &line, block * 8);
            let bits = |c: Crossing| (c.t.to_bits(), c.normal.to_array().map(f32::to_bits), c.primitive, c.cut);
            for (j, lane) in eight.into_iter().enumerate() {
                let one = caster.crossing_on_line(Hit { t: t[j], ..hit }, &line, (block * 8 + j) as f32);
                prop_assert_eq!(bits(lane), bits(one), "pixel {}", j);
            }
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
            block in 0usize..3,
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
            eight_as_one_by_one(&caster, &line, block, &RowFaces::default())?;
        }
    }
}
