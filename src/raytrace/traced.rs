//! The traced term (seed 002 §4, eq. 5's IrayTracing): reflections and
//! refraction for the pixels that need them, starting from the item buffer.
//!
//! The primary hit of every pixel is already known — the item id the polygon pass
//! left there — so it costs one ray/plane intersection with that triangle, no
//! traversal. Only pixels whose material reflects or refracts spawn secondary rays
//! (and the shadow rays seen in them), traced through the BVH to `depth` bounces;
//! their light, shaded by the [`Tracer`] with one shadow ray per light, is added
//! to the image.
//!
//! Beyond the paper: what a mirror shows is aliased like any image sampled once
//! per pixel (a reflected horizon in steps, a thin seam as dots), and neither
//! the polygon pass nor the edge pass sees it. With [`Refine::Contrast`] (the
//! edge-antialiased frame's), a traced pixel whose value differs from a
//! neighbour's by more than [`REFINE_CONTRAST`] is traced again at four points
//! of a rotated grid and the five samples averaged (adaptive supersampling,
//! Whitted 1980): only the edges inside reflections pay. On `reflections.toml`
//! at 960×540 it refines 8,677 of 341,834 traced pixels, the traced term takes
//! about 1.25× as long, and inside the chrome ball the error against a 16-ray
//! ray-traced truth falls from 0.037 to 0.013 RMSE (at 320×180: the test
//! `reflections_are_refined_where_what_they_show_has_edges`).
//!
//! Neighbouring traced pixels of a row are traced eight at a time: their
//! mirror rays, then their refracted rays, walk the BVH together
//! ([`Tracer::bounces_packet`]), each pixel getting the light it gets alone.
//! The traced term at 1920×1080 (`kage-bench hybrid --frames 5`, one run,
//! alternated with pixels traced one at a time, 2-core EPYC VM): 72 → 69.5
//! ms on `showroom.toml`, 89 → 77 ms on `reflections.toml`, 154 → 130 ms
//! with its eye at 0.8× (shading and shadow rays, one ray at a time, are
//! the rest).
//!
//! The other way, for a preview whose camera moves: [`Refine::Sparse`]
//! traces one pixel of each 2 × 2 block and gives the others the mean of
//! the nearest traced pixels that show the same object (a bilinear
//! enlargement that stops at objects' outlines), tracing a pixel itself only
//! where no such neighbour was traced. On `reflections.toml` at 320×180 it
//! traces 25% of the rays, 0.026 RMSE from the full term and 0.029 from a
//! ray-traced truth (the full term: 0.025; the test
//! `a_sparse_traced_term_traces_fewer_rays_for_nearly_the_same_image`); on
//! `showroom.toml` at 1280×720 the traced term of a frame falls from 46 to
//! 16 ms on 2 cores.

use std::ops::Range;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::tracer::{ShadowRay, Tracer};
use super::TraceCache;
use crate::bvh::PACKET;
use crate::image::LinearImage;
use crate::scene::Scene;
use crate::shading::subpixel::SampleSurface;
use crate::shading::{normal_map, ObjectFrames, SubpixelShading};
use crate::visibility::VisibilityBuffer;

/// Linear difference (in any channel) between neighbouring traced pixels above
/// which both are traced again at sub-pixel points.
pub const REFINE_CONTRAST: f32 = 0.05;

/// Offsets from the pixel centre of the extra samples of a refined pixel: a
/// rotated 2 × 2 grid (no two share a row or a column).
const REFINE_OFFSETS: [Vec2; 4] =
    [Vec2::new(-0.375, -0.125), Vec2::new(0.125, -0.375), Vec2::new(0.375, 0.125), Vec2::new(-0.125, 0.375)];

/// Whether traced pixels are refined where what they show has edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refine {
    /// One sample per pixel, at its centre (an aliased frame, or one of
    /// several jittered frames, whose average antialiases).
    Never,
    /// Pixels that differ from a neighbour by more than [`REFINE_CONTRAST`]
    /// get four more samples.
    Contrast,
    /// Fewer samples than pixels: one at the top-left pixel of each 2 × 2
    /// block, and the others interpolated from those of the same object
    /// (traced where there are none): about a quarter of the rays, for the
    /// frames of a moving camera.
    Sparse,
}

/// Adds traced reflection and refraction to `image`, refined as `refine`
/// says; returns how many pixels were traced (0, without building a BVH, when
/// no material reflects or refracts) and how many of them were refined. The
/// BVH comes from `cache` (built there when the geometry changed).
pub fn add_traced(
    scene: &Scene,
    vb: &VisibilityBuffer,
    image: &mut LinearImage,
    depth: u32,
    cache: &mut TraceCache,
    refine: Refine,
) -> (usize, usize) {
    if depth == 0 || !scene.materials.iter().any(|m| m.traces()) {
        return (0, 0);
    }
    let trace = cache.get(scene);
    let frames = ObjectFrames::new(scene);
    let tracer = Tracer::new(scene, trace, &frames, ShadowRay);
    let (w, h) = (vb.width() as usize, vb.height() as usize);
    let rays = scene.camera.pixel_rays(Vec2::new(w as f32, h as f32));
    let traces = |x: usize, y: usize| {
        let item = vb.item(x as u32, y as u32);
        !item.is_none() && scene.materials[item.material(scene)].traces()
    };
    let surface = |x: usize, y: usize, offset: Vec2| {
        let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + offset);
        let mut s = frames.surface_at(scene, vb, x as u32, y as u32, &ray);
        normal_map::apply(&scene.materials[s.material], &mut s);
        (ray, s)
    };
    let sample = |x: usize, y: usize, offset: Vec2| {
        let (ray, s) = surface(x, y, offset);
        tracer.bounces(&ray, &s, depth)
    };
    // The centre samples of pixels `xs` of row `y`, handed to `put(i, light)`
    // (`i` indexing `xs`): up to eight neighbours' secondary rays walked
    // together (coherent where they leave one mirror).
    let samples_in_row = |y: usize, xs: &[usize], put: &mut dyn FnMut(usize, Vec3)| {
        for (c, chunk) in xs.chunks(PACKET).enumerate() {
            let (mut rays, mut surfaces) = (Vec::with_capacity(PACKET), Vec::with_capacity(PACKET));
            for &x in chunk {
                let (ray, s) = surface(x, y, Vec2::ZERO);
                rays.push(ray);
                surfaces.push(s);
            }
            let light = tracer.bounces_packet(&rays, &surfaces, depth);
            (0..chunk.len()).for_each(|k| put(c * PACKET + k, light[k]));
        }
    };
    // The pixels the buffer holds are traced (the whole image but for a
    // tile), into `image`, which holds them too.
    let window = vb.rect();
    let (x0, y0) = (window.x0 as usize, window.y0 as usize);
    let (ww, wh) = (window.width() as usize, window.height() as usize);
    // Each traced pixel's sample, combined into `out` by `put`: `out` holds
    // rows of `stride` pixels, its pixel (x, y) the image's (x + origin.0,
    // y + origin.1); the columns `cols` of each row are traced.
    let trace_into = |out: &mut [Vec3],
                      stride: usize,
                      origin: (usize, usize),
                      cols: Range<usize>,
                      put: fn(&mut Vec3, Vec3)|
     -> usize {
        let rows = out.par_chunks_mut(stride).enumerate();
        rows.map(|(y, row)| {
            let y = y + origin.1;
            let xs: Vec<usize> = cols.clone().map(|x| x + origin.0).filter(|&x| traces(x, y)).collect();
            samples_in_row(y, &xs, &mut |i, light| put(&mut row[xs[i] - origin.0], light));
            xs.len()
        })
        .sum()
    };
    match refine {
        // One sample a pixel: straight into the image.
        Refine::Never => (trace_into(image.pixels_mut(), ww, (x0, y0), 0..ww, |px, t| *px += t), 0),
        Refine::Contrast => {
            // The samples apart first, NaN where nothing is traced: refining
            // compares neighbours' traced light alone.
            let mut traced = vec![Vec3::NAN; ww * wh];
            let count = trace_into(&mut traced, ww, (x0, y0), 0..ww, |px, t| *px = t);
            let refined = refine_edges(&mut traced, ww, |x, y, o| sample(x + x0, y + y0, o));
            let rows = image.pixels_mut().par_chunks_mut(ww.max(1)).zip(traced.par_chunks(ww.max(1)));
            rows.for_each(|(row, traced)| {
                for (px, t) in row.iter_mut().zip(traced).filter(|(_, t)| !t.x.is_nan()) {
                    *px += *t;
                }
            });
            (count, refined)
        }
        Refine::Sparse => {
            // The samples at the image's even pixels among those held, a
            // grid of half the size from corner (cx0, cy0).
            let (cx0, cy0) = (x0 / 2, y0 / 2);
            let cw = (x0 + ww).div_ceil(2) - cx0;
            let mut corners = vec![Vec3::NAN; cw * ((y0 + wh).div_ceil(2) - cy0)];
            let held = |x: usize, y: usize| window.contains(x as u32, y as u32);
            let traced: usize = corners
                .par_chunks_mut(cw.max(1))
                .enumerate()
                .map(|(cy, row)| {
                    let y = 2 * (cy + cy0);
                    let xs: Vec<usize> =
                        (2 * cx0..).step_by(2).take(row.len()).filter(|&x| held(x, y) && traces(x, y)).collect();
                    samples_in_row(y, &xs, &mut |i, light| row[xs[i] / 2 - cx0] = light);
                    xs.len()
                })
                .sum();
            let object = |x: usize, y: usize| vb.item(x as u32, y as u32).object;
            let corner = |cx: usize, cy: usize| corners[(cy / 2 - cy0) * cw + cx / 2 - cx0];
            let rows = image.pixels_mut().par_chunks_mut(ww.max(1)).enumerate();
            let filled_by_rays: usize = rows
                .map(|(y, row)| {
                    let (mut count, y) = (0, y + y0);
                    for (x, px) in (x0..).zip(row).filter(|&(x, _)| traces(x, y)) {
                        let same = |cx: usize, cy: usize| held(cx, cy) && object(cx, cy) == object(x, y);
                        *px += interpolated((w, h), x, y, |cx, cy| same(cx, cy).then(|| corner(cx, cy)))
                            .unwrap_or_else(|| {
                                count += 1;
                                sample(x, y, Vec2::ZERO)
                            });
                    }
                    count
                })
                .sum();
            (traced + filled_by_rays, 0)
        }
    }
}

/// Pixel (`x`, `y`)'s value (of an image `size` pixels) from the traced
/// block corners around it (`corner(cx, cy)`: the sample at even pixel
/// (cx, cy), NaN where none was traced, `None` where the pixel does not
/// accept it): its own sample at a corner, else the mean of the accepted
/// corners beside it (two along a row or column, four inside a block);
/// `None` when none is accepted.
fn interpolated(
    size: (usize, usize),
    x: usize,
    y: usize,
    corner: impl Fn(usize, usize) -> Option<Vec3>,
) -> Option<Vec3> {
    let (w, h) = size;
    let around = |v: usize, n: usize| {
        if v.is_multiple_of(2) {
            [Some(v), None]
        } else {
            [Some(v - 1), (v + 1 < n).then_some(v + 1)]
        }
    };
    let (mut sum, mut count) = (Vec3::ZERO, 0u32);
    for cy in around(y, h).into_iter().flatten() {
        for cx in around(x, w).into_iter().flatten() {
            if let Some(c) = corner(cx, cy).filter(|c| !c.x.is_nan()) {
                sum += c;
                count += 1;
            }
        }
    }
    (count > 0).then(|| sum / count as f32)
}

/// Traces again, at [`REFINE_OFFSETS`], every traced pixel of `traced` (rows
/// of `w`; NaN: not traced) that differs from its right or lower traced
/// neighbour by more than [`REFINE_CONTRAST`], both of the pair, through
/// `sample(x, y, offset)`; each refined pixel becomes the mean of its five
/// samples. Returns how many were refined.
fn refine_edges(traced: &mut [Vec3], w: usize, sample: impl Fn(usize, usize, Vec2) -> Vec3 + Sync) -> usize {
    let h = traced.len() / w.max(1);
    let differs = |a: Vec3, b: Vec3| !a.x.is_nan() && !b.x.is_nan() && (a - b).abs().max_element() > REFINE_CONTRAST;
    let marked: Vec<bool> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let t = traced[i];
            let near = [
                (x > 0).then(|| i - 1),
                (x + 1 < w).then(|| i + 1),
                (y > 0).then(|| i - w),
                (y + 1 < h).then(|| i + w),
            ];
            near.into_iter().flatten().any(|j| differs(t, traced[j]))
        })
        .collect();
    traced.par_chunks_mut(w).zip(marked.par_chunks(w)).enumerate().for_each(|(y, (row, marks))| {
        for (x, (t, &m)) in row.iter_mut().zip(marks).enumerate() {
            if m {
                let extra: Vec3 = REFINE_OFFSETS.iter().map(|&o| sample(x, y, o)).sum();
                *t = (*t + extra) / (1 + REFINE_OFFSETS.len()) as f32;
            }
        }
    });
    marked.iter().filter(|&&m| m).count()
}

/// The traced term at every sub-pixel sample of `subpixel` whose surface
/// reflects or refracts (as [`add_traced`] traces it at pixel centres).
pub fn trace_subpixel(scene: &Scene, subpixel: &mut SubpixelShading, depth: u32, cache: &mut TraceCache) {
    let traces = |s: &Option<SampleSurface>| s.as_ref().is_some_and(|s| scene.materials[s.point.material].traces());
    let any_material = scene.materials.iter().any(|m| m.traces());
    if depth == 0 || !any_material || !subpixel.surfaces.iter().any(traces) {
        return;
    }
    let trace = cache.get(scene);
    let frames = ObjectFrames::new(scene);
    let tracer = Tracer::new(scene, trace, &frames, ShadowRay);
    let SubpixelShading { surfaces, traced, .. } = subpixel;
    traced.par_iter_mut().zip(surfaces.par_iter()).filter(|(_, s)| traces(s)).for_each(|(out, s)| {
        if let Some(s) = s {
            *out = tracer.bounces(&s.ray, &s.point, depth);
        }
    });
}
