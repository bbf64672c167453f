//! Scanline visibility of CSG solids (seed 003 §5; issue 6), first form.
//!
//! The frame is walked the paper's way: primitives are bucket-sorted by their
//! top scanline into the y-entry table; each scanline moves entering primitives
//! into the y-occupancy list and drops those whose bottom it passed, bucket-sorts
//! the occupants by left end into the x-entry table, and walks its pixels keeping
//! the x-occupancy list: primitives enter at their left end and leave after their
//! right end. A pixel with occupants gets its visible surface from the depth
//! intervals of the occupants only ([`crate::raytrace::csg::primitive_span`],
//! seed 003's procedure 3 in closed form).
//!
//! Beyond the paper (its own named defect, and OpenSCAD's aborted previews past
//! 100,000 terms): the boolean tree is not expanded into a sum of products up
//! front. Whenever the x-occupancy list changes, the tree is cut down to the
//! occupants ([`CsgTree::restricted`]) and the pixels until the next change share
//! that small tree — seed 003's coherence (§5.2.2) applied to the expression
//! instead of the visible-segment list. Intervals are combined along the cut-down
//! tree, so a difference costs no more than an intersection.
//!
//! What is not the paper's yet: a primitive's extent on the screen is the
//! projection of its bounding corners (exact for polyhedra, conservative for
//! spheres and frustums, and the whole screen when a corner lies behind the eye),
//! the same on every scanline it spans, rather than the paper's tangent-plane
//! procedures 1 and 2. A too-wide extent only costs time: where a primitive does
//! not reach, its interval is empty.

use glam::{Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::raytrace::csg::{Crossing, CsgCaster, SpanScratch};
use crate::scene::csg::{CsgSolid, CsgTree, Shape};
use crate::scene::Camera;

/// Rows scanned by one worker in turn.
const BAND_ROWS: usize = 16;

/// Pixels a primitive may cover: rows `y0..=y1`, columns `x0..=x1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Extent {
    x0: i64,
    x1: i64,
    y0: i64,
    y1: i64,
}

/// The visible surface of `solid` (in world space) at each pixel centre of a
/// `width` x `height` image seen by `camera`, rows top to bottom: the first
/// crossing in front of the eye, or `None`.
#[must_use]
pub fn scan_solid(solid: &CsgSolid, camera: &Camera, width: u32, height: u32) -> Vec<Option<Crossing>> {
    let (w, h) = (width as usize, height as usize);
    let mut out = vec![None; w * h];
    let Some(tree) = &solid.tree else { return out };
    let vp = camera.view_projection(width as f32 / height as f32);
    let extents: Vec<Option<Extent>> =
        solid.primitives.iter().map(|p| extent(&corners(&p.shape, &p.transform), vp, width, height)).collect();
    // The y-entry table: primitives by top scanline.
    let mut entry: Vec<usize> = (0..extents.len()).filter(|&i| extents[i].is_some()).collect();
    entry.sort_by_key(|&i| extents[i].map_or(0, |e| e.y0));
    let rays = camera.pixel_rays(Vec2::new(width as f32, height as f32));
    let caster = CsgCaster::new(solid);
    let band_len = w * BAND_ROWS;
    out.par_chunks_mut(band_len).enumerate().for_each(|(band, rows)| {
        let first = band * BAND_ROWS;
        // The y-occupancy list as the band's first scanline finds it, then kept
        // row by row.
        let mut next = entry.partition_point(|&i| extents[i].map_or(0, |e| e.y0) <= first as i64);
        let mut occupied: Vec<usize> =
            entry[..next].iter().copied().filter(|&i| extents[i].is_some_and(|e| e.y1 >= first as i64)).collect();
        for (dy, row) in rows.chunks_mut(w).enumerate() {
            let y = (first + dy) as i64;
            while next < entry.len() && extents[entry[next]].is_some_and(|e| e.y0 <= y) {
                occupied.push(entry[next]);
                next += 1;
            }
            occupied.retain(|&i| extents[i].is_some_and(|e| e.y1 >= y));
            scan_row(&caster, tree, &extents, &occupied, |x| rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)), row);
        }
    });
    out
}

/// One scanline: the x-entry table of the occupants, the x-occupancy list, and
/// each occupied pixel's surface from the tree cut down to the occupants.
fn scan_row(
    caster: &CsgCaster,
    tree: &CsgTree,
    extents: &[Option<Extent>],
    occupied: &[usize],
    ray_at: impl Fn(usize) -> crate::scene::Ray,
    row: &mut [Option<Crossing>],
) {
    let x0 = |i: usize| extents[i].map_or(0, |e| e.x0);
    let mut entry: Vec<usize> = occupied.to_vec();
    entry.sort_by_key(|&i| x0(i));
    let (mut next, mut inside): (usize, Vec<usize>) = (0, Vec::new());
    let mut cut: Option<CsgTree> = None;
    let mut active = vec![false; extents.len()];
    let mut scratch = SpanScratch::default();
    for (x, px) in row.iter_mut().enumerate() {
        let mut changed = false;
        while next < entry.len() && x0(entry[next]) <= x as i64 {
            inside.push(entry[next]);
            active[entry[next]] = true;
            next += 1;
            changed = true;
        }
        if changed {
            cut = tree.restricted(&|i| active[i]);
        }
        if let Some(tree) = &cut {
            let ray = ray_at(x);
            *px = caster.first_hit_with(tree, &ray, 0.0, &mut scratch);
        }
        // Primitives whose right end is this pixel leave the x-occupancy list.
        let before = inside.len();
        inside.retain(|&i| {
            let stays = extents[i].is_some_and(|e| e.x1 > x as i64);
            active[i] = stays;
            stays
        });
        if inside.len() != before {
            cut = tree.restricted(&|i| active[i]);
        }
    }
}

/// Corners of a box around the primitive's unit shape, in solid space.
fn corners(shape: &Shape, m: &glam::Affine3A) -> Vec<Vec3> {
    let unit_box = |z0: f32| -> Vec<Vec3> {
        (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { z0 } else { 1.0 },
                )
            })
            .collect()
    };
    let local = match shape {
        Shape::Sphere => unit_box(-1.0),
        Shape::Frustum { .. } => unit_box(0.0),
        Shape::Polyhedron(p) => p.vertices.clone(),
    };
    local.into_iter().map(|c| m.transform_point3(c)).collect()
}

/// The pixels whose centres the projection of `points` can cover; the whole
/// image if a point lies at or behind the eye; `None` if off screen.
fn extent(points: &[Vec3], vp: Mat4, width: u32, height: u32) -> Option<Extent> {
    let (w, h) = (f64::from(width), f64::from(height));
    let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
    for p in points {
        let c: Vec4 = vp * p.extend(1.0);
        if c.w <= 1e-6 {
            return Some(Extent { x0: 0, x1: i64::from(width) - 1, y0: 0, y1: i64::from(height) - 1 });
        }
        let ndc = glam::DVec2::new(f64::from(c.x / c.w), f64::from(c.y / c.w));
        let px = glam::DVec2::new((ndc.x * 0.5 + 0.5) * w, (0.5 - ndc.y * 0.5) * h);
        (lo, hi) = (lo.min(px), hi.max(px));
    }
    // Pixel x is covered when its centre x + ½ lies in [lo, hi]; a hair wider so
    // rounding never drops a pixel the primitive reaches.
    let first = |v: f64| (v - 0.5 - 1e-3).ceil() as i64;
    let last = |v: f64| (v - 0.5 + 1e-3).floor() as i64;
    let e = Extent {
        x0: first(lo.x).max(0),
        x1: last(hi.x).min(i64::from(width) - 1),
        y0: first(lo.y).max(0),
        y1: last(hi.y).min(i64::from(height) - 1),
    };
    (e.x0 <= e.x1 && e.y0 <= e.y1).then_some(e)
}
