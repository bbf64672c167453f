//! The traced term (seed 002 §4, eq. 5's IrayTracing): reflections and
//! refraction for the pixels that need them, starting from the item buffer.
//!
//! The primary hit of every pixel is already known — the item id the polygon pass
//! left there — so it costs one ray/plane intersection with that triangle, no
//! traversal. Only pixels whose material reflects or refracts spawn secondary rays
//! (and the shadow rays seen in them), traced through the BVH to `depth` bounces;
//! their light, shaded by the [`Tracer`] with one shadow ray per light, is added
//! to the image.

use glam::Vec2;
use rayon::prelude::*;

use super::tracer::{ShadowRay, Tracer};
use super::TraceCache;
use crate::image::LinearImage;
use crate::scene::Scene;
use crate::shading::subpixel::SampleSurface;
use crate::shading::{ObjectFrames, SubpixelShading};
use crate::visibility::VisibilityBuffer;

/// Adds traced reflection and refraction to `image`; returns how many pixels were
/// traced (0, without building a BVH, when no material reflects or refracts). The
/// BVH comes from `cache` (built there when the geometry changed).
pub fn add_traced(
    scene: &Scene,
    vb: &VisibilityBuffer,
    image: &mut LinearImage,
    depth: u32,
    cache: &mut TraceCache,
) -> usize {
    if depth == 0 || !scene.materials.iter().any(|m| m.traces()) {
        return 0;
    }
    let trace = cache.get(scene);
    let frames = ObjectFrames::new(scene);
    let tracer = Tracer::new(scene, trace, &frames, ShadowRay);
    let w = vb.width() as usize;
    let rays = scene.camera.pixel_rays(Vec2::new(w as f32, vb.height() as f32));
    let rows = image.pixels_mut().par_chunks_mut(w).zip(vb.items().par_chunks(w));
    rows.enumerate()
        .map(|(y, (out, items))| {
            let mut traced = 0;
            for (x, (px, &item)) in out.iter_mut().zip(items).enumerate() {
                if item.is_none() || !scene.materials[item.material(scene)].traces() {
                    continue;
                }
                let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                let s = frames.surface_at(scene, vb, x as u32, y as u32, &ray);
                *px += tracer.bounces(&ray, &s, depth);
                traced += 1;
            }
            traced
        })
        .sum()
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
