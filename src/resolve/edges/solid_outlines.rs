//! Antialiased outlines of CSG solids: seed 004's idea — after the aliased frame,
//! move each pixel an outline crosses towards the pixels across it by the share
//! of its area on their side — for outlines that are not polygon edges.
//!
//! Seed 004 finds that share from the edge's line equation. A solid's outline is
//! made of curves (a sphere's rim, a hole's wall seen edge-on) and of lines where
//! primitives meet, none of them stored anywhere. So the share is measured: a
//! pixel where a solid meets something else (another object, another primitive,
//! the background) casts `SAMPLES` stratified rays through its area (the ray
//! tracer sees solids by interval arithmetic, [`crate::csg`]), and
//! each ray that sees what a neighbouring pixel shows takes that neighbour's
//! colour; the grid's four corner rays go first, and a pixel whose corners all
//! see what it shows is left as it is ([`CORNERS`]). Only outline pixels are touched, and the frame is never re-shaded:
//! the colours come from the aliased frame, as in seed 004.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::image::LinearImage;
use crate::raytrace::TraceScene;
use crate::sampling::{hash3, stratified};
use crate::scene::Scene;
use crate::visibility::{ItemId, VisibilityBuffer};

/// Rays per outline pixel along each axis.
const SAMPLES: u32 = 3;

/// The corner cells of the `SAMPLES` × `SAMPLES` grid, cast first. Where all
/// four see the pixel's own item the other five are not cast: on the corpus
/// of OpenSCAD parts that is about half of the outline pixels (the side of
/// an outline whose pixel centres lie inside the nearer surface), and those
/// rays were most of the edge pass's time.
const CORNERS: [u32; 4] = [0, SAMPLES - 1, SAMPLES * (SAMPLES - 1), SAMPLES * SAMPLES - 1];

/// One outline pixel's new colour as weights of itself and its neighbours.
#[derive(Debug, Clone, PartialEq)]
pub struct OutlineBlend {
    /// The pixel: its index among those the frame holds
    /// ([`VisibilityBuffer::index`]).
    pub pixel: u32,
    /// Source pixels (indexed as `pixel`) and their weights, summing to 1.
    pub weights: Vec<(u32, f32)>,
}

/// Whether two items meet at an outline a solid takes part in: at least one is
/// a solid's primitive, and they differ in object or primitive.
fn solid_outline(a: ItemId, b: ItemId) -> bool {
    (a.primitive().is_some() || b.primitive().is_some()) && a != b
}

/// Two pieces of one solid's surface that meet without an edge that shows:
/// neighbouring convex pieces of one flat face (an extruded shape's top, cut
/// into convex prisms), or facets a few degrees apart (a revolution's
/// segments): the same object, normals within [`SAME_SURFACE_COS`] and
/// depths within [`SAME_SURFACE_DEPTH`] of each other. No outline runs
/// between them.
fn one_surface(vb: &VisibilityBuffer, a: ItemId, b: ItemId, (ax, ay): (u32, u32), (bx, by): (u32, u32)) -> bool {
    if a.object != b.object || a.primitive().is_none() || b.primitive().is_none() {
        return false;
    }
    let (da, db) = (vb.depth(ax, ay), vb.depth(bx, by));
    vb.normal(ax, ay).dot(vb.normal(bx, by)) > SAME_SURFACE_COS
        && (da - db).abs() <= SAME_SURFACE_DEPTH * da.abs().max(db.abs())
}

/// Cosine of the largest angle between two pieces' normals that still makes
/// them one surface (10°).
const SAME_SURFACE_COS: f32 = 0.985;

/// The largest relative difference of two neighbouring pixels' depths on one
/// surface.
const SAME_SURFACE_DEPTH: f32 = 0.02;

/// Whether the corner rays of a pixel showing `me` all met one surface of
/// its solid: its primitives, normals and distances as close as
/// [`one_surface`] asks of two pixels.
fn corners_on_one_surface(me: ItemId, corners: &[Option<crate::raytrace::Hit>; 4]) -> bool {
    let Some(first) = corners[0] else { return false };
    me.primitive().is_some()
        && corners.iter().all(|c| {
            c.is_some_and(|c| {
                c.item.object == me.object
                    && c.item.primitive().is_some()
                    && c.normal.dot(first.normal) > SAME_SURFACE_COS
                    && (c.t - first.t).abs() <= SAME_SURFACE_DEPTH * c.t.abs().max(first.t.abs())
            })
        })
}

/// Finds the blends of every pixel on a solid's outline in `vb` (the frame of
/// `scene` as the visibility pass left it), with `trace` the scene's rays.
#[must_use]
pub fn find_outline_blends(scene: &Scene, vb: &VisibilityBuffer, trace: &TraceScene) -> Vec<OutlineBlend> {
    let rays = scene.camera.pixel_rays(Vec2::new(vb.width() as f32, vb.height() as f32));
    let item = |x: i64, y: i64| vb.item(x as u32, y as u32);
    // The pixels held alone are looked at (a tile's, with its guard band).
    let held = vb.rect();
    let (columns, rows) = (i64::from(held.x0)..i64::from(held.x1), i64::from(held.y0)..i64::from(held.y1));
    let inside = |(nx, ny): (i64, i64)| columns.contains(&nx) && rows.contains(&ny);
    let index = |x: i64, y: i64| vb.index(x as u32, y as u32) as u32;
    // A pixel lies on an outline when a side neighbour shows another item
    // across a solid's outline.
    let on_outline = |x: i64, y: i64| {
        let me = item(x, y);
        [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)].into_iter().any(|(nx, ny)| {
            inside((nx, ny))
                && solid_outline(me, item(nx, ny))
                && !one_surface(vb, me, item(nx, ny), (x as u32, y as u32), (nx as u32, ny as u32))
        })
    };
    // The pixels to measure, found row by row; then measured one by one on
    // every worker (a row along a solid's top or bottom edge holds hundreds
    // of them, its neighbours a few: rows as the pieces left one worker
    // casting a long row's rays while the other waited).
    let candidates: Vec<(i64, i64)> = rows
        .clone()
        .into_par_iter()
        .flat_map_iter(|y| columns.clone().filter(move |&x| on_outline(x, y)).map(move |x| (x, y)))
        .collect();
    candidates
        .par_iter()
        .with_min_len(8)
        .filter_map(|&(x, y)| {
            let me = item(x, y);
            let near: Vec<(i64, i64)> = (-1..=1)
                .flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
                .filter(|&n| n != (x, y) && inside(n))
                .collect();
            // Each ray takes the colour of the nearest pixel (itself first)
            // that shows what the ray sees; a ray that sees something no
            // neighbour shows keeps the pixel's own colour.
            let hit = |k: u32| {
                let offset = stratified(k, SAMPLES, hash3(x as u32, y as u32, k));
                let ray = rays.ray(Vec2::new(x as f32, y as f32) + offset);
                trace.intersect(&ray, f32::INFINITY)
            };
            let cast = |k: u32| hit(k).map_or(ItemId::NONE, |h| h.item);
            // The four corner cells first: all four on the pixel's own item,
            // or on one surface of its solid, leave it as it is (the outline
            // runs in the neighbour).
            let corners = CORNERS.map(hit);
            if corners.iter().all(|c| c.is_some_and(|c| c.item == me)) || corners_on_one_surface(me, &corners) {
                return None;
            }
            let mut seen = [None; (SAMPLES * SAMPLES) as usize];
            for (k, c) in CORNERS.iter().zip(&corners) {
                seen[*k as usize] = Some(c.map_or(ItemId::NONE, |c| c.item));
            }
            let mut weights: Vec<(u32, f32)> = Vec::new();
            let share = 1.0 / (SAMPLES * SAMPLES) as f32;
            for k in 0..SAMPLES * SAMPLES {
                let seen = seen[k as usize].unwrap_or_else(|| cast(k));
                // The same item, else the same object (another triangle of
                // a mesh, another primitive of a solid), else itself.
                let around = || std::iter::once((x, y)).chain(near.iter().copied());
                let same_object =
                    |i: ItemId| i.object == seen.object && i.primitive().is_some() == seen.primitive().is_some();
                let source = around()
                    .find(|&(nx, ny)| item(nx, ny) == seen)
                    .or_else(|| around().find(|&(nx, ny)| same_object(item(nx, ny))))
                    .unwrap_or((x, y));
                let index = index(source.0, source.1);
                match weights.iter_mut().find(|(p, _)| *p == index) {
                    Some((_, wgt)) => *wgt += share,
                    None => weights.push((index, share)),
                }
            }
            Some(OutlineBlend { pixel: index(x, y), weights })
        })
        .collect()
}

/// Applies `blends` to `image` (every blend reads the image as it was before
/// any of them).
pub fn apply_outline_blends(image: &mut LinearImage, blends: &[OutlineBlend]) {
    let colours: Vec<Vec3> = {
        let px = image.pixels();
        blends.par_iter().map(|b| b.weights.iter().map(|&(p, wgt)| px[p as usize] * wgt).sum()).collect()
    };
    let px = image.pixels_mut();
    for (b, c) in blends.iter().zip(colours) {
        px[b.pixel as usize] = c;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_pairs_with_a_solid_make_outlines() {
        let tri = |o, t| ItemId { object: o, triangle: t };
        let prim = ItemId::primitive_of;
        assert!(!solid_outline(tri(0, 1), tri(1, 2)), "mesh against mesh: seed 004's own edge pass");
        assert!(solid_outline(prim(0, 1), ItemId::NONE), "a solid against the background");
        assert!(solid_outline(prim(0, 1), prim(0, 2)), "two primitives of one solid");
        assert!(!solid_outline(prim(0, 1), prim(0, 1)), "inside one primitive's face");
        assert!(solid_outline(tri(1, 0), prim(0, 0)), "a mesh in front of a solid");
    }
}
