//! Where in space a cutter can change its solid (beyond seed 003, and beyond
//! the screen boxes of [`super::bounds`], which meet the cutter's projection
//! with its part's): a primitive under the cutters of a difference `A − C`
//! changes the difference only at points inside both itself and `A` — so
//! within the box around itself and the box around one of `A`'s primitives
//! ([`super::occupancy::CutterBodies`]). Each such pair of boxes (each a
//! parallelepiped: the primitive's unit box carried by its transform) meets
//! in a convex region whose corners are found once per solid; a frame
//! projects them, and the primitive's box of pixels shrinks to theirs. A
//! chamfer's long block, rotated along an edge of the part, then occupies
//! only the strip of screen along that edge where it cuts, where the screen
//! boxes kept all of the part's box it covers.
//!
//! The boxes are widened (a hundredth of each unit box's side) so that the
//! booleans' tie ([`crate::csg::TIE`], which widens a cutter's
//! interval by a relative hair of `t`) stays inside them: a frame that sees
//! the region so far away that the tie could reach past the widening keeps
//! the primitive's box as it was.

use glam::{DVec3, Mat4, Vec3, Vec3A};
use rayon::prelude::*;

use crate::camera::Camera;
use crate::csg::occupancy::{CutterBodies, OccupancyTree};
use crate::csg::outline::{screen_point, Extent};
use crate::csg::{BoxBound, CsgCaster, CsgSolid, TIE};

/// How far each unit box is widened on each side, as a part of its side.
const WIDENING: f64 = 0.01;

/// Relative rounding allowed a point on a shared face (far above `f32`'s,
/// far below [`WIDENING`]).
const ROUNDING: f64 = 1e-5;

/// Pixels added around a region's projected corners (rounding).
const MARGIN_PX: f32 = 2.0;

/// A bound on a pixel ray's length per unit of depth along the view axis
/// (the row lines' `t` is that depth): 4 covers fields of view up to 150°.
const RAY_PER_DEPTH: f32 = 4.0;

/// Primitives from which the regions are found in parallel.
const PARALLEL_FROM: usize = 16;

/// A parallelepiped as six half-spaces `n·x ≤ d`, two per axis.
type Slabs = [(DVec3, f64); 6];

/// Per primitive that cuts, the convex region (its corners) outside which it
/// changes nothing, and how far that region reaches past the true boxes.
#[derive(Debug, Clone, Default)]
pub(super) struct CutRegions {
    regions: Vec<Option<Region>>,
}

/// The corners of a cutter's regions (one per primitive of its body it may
/// meet; none at all where it meets none) and the least distance by which
/// they were widened.
#[derive(Debug, Clone)]
struct Region {
    corners: Vec<Vec3>,
    widened: f32,
    /// The cutter's own box (how far away the region can lie).
    own: (Vec3A, Vec3A),
}

impl CutRegions {
    /// The regions of `solid`'s cutters (`tree` its occupancy tree; the
    /// unit boxes from `caster`).
    pub(super) fn new(solid: &CsgSolid, caster: &CsgCaster, tree: &OccupancyTree) -> CutRegions {
        let bodies = CutterBodies::new(tree);
        let n = solid.primitives.len();
        let boxes: Vec<Parallelepiped> = (0..n).map(|i| Parallelepiped::of(solid, caster, i)).collect();
        let region = |i: usize| {
            let b = bodies.body_of(i)?;
            let c = &boxes[i];
            // A flat box (a transform that cannot be undone) bounds nothing.
            let parts = bodies.primitives(b).iter().map(|&p| &boxes[p as usize]);
            if !c.solid() || !parts.clone().all(Parallelepiped::solid) {
                return None;
            }
            let mut region = Region { corners: Vec::new(), widened: c.widened as f32, own: c.bounds };
            for p in parts {
                // Boxes apart in space: no corner.
                if c.bounds.0.max(p.bounds.0).cmpgt(c.bounds.1.min(p.bounds.1)).any() {
                    continue;
                }
                region.widened = region.widened.min(p.widened as f32);
                c.meet(p, &mut region.corners);
            }
            Some(region)
        };
        let regions = if n >= PARALLEL_FROM {
            (0..n).into_par_iter().map(region).collect()
        } else {
            (0..n).map(region).collect()
        };
        CutRegions { regions }
    }

    /// Primitive `i`'s box of pixels `pixels` shrunk to where it can change
    /// the solid seen by `camera` through `vp` in a `size` image (`None`:
    /// nowhere). Unchanged where it cuts nothing, or where a corner lies at
    /// or behind the eye, or the tie could reach past the widening.
    pub(super) fn narrow(
        &self,
        i: usize,
        pixels: Option<Extent>,
        camera: &Camera,
        vp: Mat4,
        size: (u32, u32),
    ) -> Option<Extent> {
        let (Some(pixels), Some(Some(region))) = (pixels, self.regions.get(i)) else { return pixels };
        // The depth of the cutter's box's farthest corner.
        let forward = Vec3A::from((camera.target - camera.eye).normalize_or_zero());
        let (centre, half) = ((region.own.0 + region.own.1) * 0.5, (region.own.1 - region.own.0) * 0.5);
        let farthest = (centre - Vec3A::from(camera.eye)).dot(forward) + half.dot(forward.abs());
        if region.widened <= 2.0 * TIE * RAY_PER_DEPTH * farthest.max(1.0) {
            return Some(pixels);
        }
        if region.corners.is_empty() {
            return None;
        }
        let (mut lo, mut hi) = (glam::Vec2::INFINITY, glam::Vec2::NEG_INFINITY);
        for &c in &region.corners {
            let Some(p) = screen_point(c, vp, size) else { return Some(pixels) };
            (lo, hi) = (lo.min(p), hi.max(p));
        }
        // Pixel (x, y) has its centre at (x + ½, y + ½).
        let column = |v: f32, round: fn(f32) -> f32| round(v - 0.5) as i64;
        let shown = Extent {
            x0: column(lo.x - MARGIN_PX, f32::floor),
            x1: column(hi.x + MARGIN_PX, f32::ceil),
            y0: column(lo.y - MARGIN_PX, f32::floor),
            y1: column(hi.y + MARGIN_PX, f32::ceil),
        };
        pixels.meet(shown)
    }
}

/// A primitive's unit box, widened, carried into the solid's space: its
/// half-spaces, its corners, the least distance by which it was widened
/// there, and its axis-aligned bounds.
#[derive(Debug, Clone)]
struct Parallelepiped {
    slabs: Slabs,
    corners: [DVec3; 8],
    widened: f64,
    bounds: (Vec3A, Vec3A),
}

impl Parallelepiped {
    /// Primitive `i`'s.
    fn of(solid: &CsgSolid, caster: &CsgCaster, i: usize) -> Parallelepiped {
        let (lo, hi) = caster.unit_box(i);
        let m = solid.primitives[i].transform;
        let inv = m.inverse();
        let mut slabs = [(DVec3::ZERO, 0.0); 6];
        let mut widened = f64::INFINITY;
        let (mut l, mut h) = ([0.0f64; 3], [0.0f64; 3]);
        for k in 0..3 {
            // Unit coordinate k of x: row k of the inverse map, plus its offset.
            let row = DVec3::new(
                f64::from(inv.matrix3.x_axis[k]),
                f64::from(inv.matrix3.y_axis[k]),
                f64::from(inv.matrix3.z_axis[k]),
            );
            let t = f64::from(inv.translation[k]);
            let w = WIDENING * f64::from(hi[k] - lo[k]);
            (l[k], h[k]) = (f64::from(lo[k]) - w, f64::from(hi[k]) + w);
            slabs[2 * k] = (row, h[k] - t);
            slabs[2 * k + 1] = (-row, t - l[k]);
            widened = widened.min(w / row.length());
        }
        let (m3, t) = (m.matrix3.as_dmat3(), m.translation.as_dvec3());
        let corners: [DVec3; 8] = std::array::from_fn(|c| {
            let pick = |k: usize| if c >> k & 1 == 0 { l[k] } else { h[k] };
            m3 * DVec3::new(pick(0), pick(1), pick(2)) + t
        });
        let (min, max) = corners.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &c| (a.min(c), b.max(c)));
        Parallelepiped { slabs, corners, widened, bounds: (min.as_vec3().into(), max.as_vec3().into()) }
    }

    /// Whether it has volume: its half-spaces and widening are finite.
    fn solid(&self) -> bool {
        self.widened.is_finite() && self.widened > 0.0 && self.slabs.iter().all(|(n, d)| n.is_finite() && d.is_finite())
    }

    /// Whether `x` lies inside, or outside by no more than the rounding of
    /// the transforms (in `f32`) that placed both: points of a face the two
    /// share (a part and a cutter of the same size, side by side) count as
    /// inside, and the region is never cut short by them.
    fn holds(&self, x: DVec3) -> bool {
        self.slabs.iter().all(|(n, d)| n.dot(x) <= d + ROUNDING * (1.0 + d.abs() + n.length() * x.length()))
    }

    /// The corners of the region inside both `self` and `other`, pushed onto
    /// `out`: each one's corners inside the other, and where each one's
    /// edges cross the other's faces inside it.
    fn meet(&self, other: &Parallelepiped, out: &mut Vec<Vec3>) {
        for (a, b) in [(self, other), (other, self)] {
            out.extend(a.corners.iter().filter(|&&c| b.holds(c)).map(|c| c.as_vec3()));
            for (p, q) in a.edges() {
                for (n, d) in &b.slabs {
                    let along = n.dot(q - p);
                    if along == 0.0 {
                        continue;
                    }
                    let s = (d - n.dot(p)) / along;
                    let x = p + (q - p) * s;
                    if (0.0..=1.0).contains(&s) && b.holds(x) {
                        out.push(x.as_vec3());
                    }
                }
            }
        }
    }

    /// Its twelve edges.
    fn edges(&self) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
        (0..8usize).flat_map(move |c| {
            (0..3).filter(move |k| c >> k & 1 == 0).map(move |k| (self.corners[c], self.corners[c | 1 << k]))
        })
    }
}
