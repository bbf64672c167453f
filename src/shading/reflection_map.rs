//! The reflection-map pass of seed 002 eq. 4, run once per frame:
//! Ie(x, y) = Km · Mape(R), the environment image looked up along the view's
//! mirror direction R = 2(N·V)N − V at each surface whose material has a Km — a
//! reflection with no ray traced, which is all the paper's hardware could do.
//! The same pass writes the environment as the background where it is visible.
//! Each pixel's lookup is filtered over the directions its neighbours see (the
//! map's mip level matching that spread): a curved mirror seen small shows the
//! map's average there, not moiré.

use std::ops::Range;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::{Component, ObjectFrames, SurfacePoint, Target, TriangleCache};
use crate::camera::PixelRays;
use crate::scene::{Material, Scene, SharedFootprint};
use crate::visibility::VisibilityBuffer;

/// Adds Km · Mape(R) to every target holding the reflection component, and the
/// visible environment's background to every target holding the emission
/// component (the first pass left those pixels black).
pub fn add_reflection_map(scene: &Scene, vb: &VisibilityBuffer, targets: &mut [Target]) {
    let Some(env) = &scene.environment else { return };
    let reflecting: Vec<bool> = scene.materials.iter().map(|m| m.km.max_element() > 0.0).collect();
    if !env.visible && !reflecting.contains(&true) {
        return;
    }
    let w = vb.width() as usize;
    let frames = ObjectFrames::new(scene);
    let rays = scene.camera.pixel_rays(Vec2::new(w as f32, vb.height() as f32));
    let mirrors = Mirrors { scene, vb, frames: &frames, rays: &rays, reflecting: &reflecting };
    for t in targets {
        let (reflection, background) = (t.parts.contains(Component::Reflection), t.parts.contains(Component::Emission));
        if !(reflection || background && env.visible) {
            continue;
        }
        let bands = t.image.pixels_mut().par_chunks_mut(w * BAND).enumerate();
        let scratch = || (TriangleCache::new(512), Vec::new());
        bands.for_each_init(scratch, |(cache, band), (k, out)| {
            let rows = k * BAND..k * BAND + out.len() / w;
            if reflection {
                mirrors.fill(rows.clone(), cache, band);
            }
            // Row y of the band is row y + 1 of `band` (it holds one more
            // row above and below).
            let top = rows.start as i64;
            let at = |x: i64, y: i64| {
                let (x, y) = (usize::try_from(x).ok().filter(|&x| x < w)?, usize::try_from(y + 1 - top).ok()?);
                band.get(y * w + x).copied().flatten()
            };
            for (y, row) in rows.clone().zip(out.chunks_mut(w)) {
                let items = &vb.items()[y * w..(y + 1) * w];
                for (x, (px, &item)) in row.iter_mut().zip(items).enumerate() {
                    if item.is_none() {
                        if background && env.visible {
                            let dir = |x: usize, y: usize| {
                                rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).dir.normalize()
                            };
                            *px += env.radiance_over(dir(x, y), dir(x + 1, y), dir(x, y + 1));
                        }
                        continue;
                    }
                    let Some(here) = at(x as i64, y as i64).filter(|_| reflection) else { continue };
                    // The spread of mirror directions to the pixels beside and
                    // below, taken from the other side where they show another object.
                    let beside = |dx: i64, dy: i64| {
                        [1, -1].into_iter().map(|k| (x as i64 + k * dx, y as i64 + k * dy)).find(|&(nx, ny)| {
                            nx >= 0
                                && ny >= 0
                                && (nx as u32) < vb.width()
                                && (ny as u32) < vb.height()
                                && vb.item(nx as u32, ny as u32).object == item.object
                        })
                    };
                    let spread = |n: Option<(i64, i64)>| n.and_then(|(nx, ny)| at(nx, ny)).map_or(here.r, |m| m.r);
                    *px += here.km * env.radiance_over(here.r, spread(beside(1, 0)), spread(beside(0, 1)));
                }
            }
        });
    }
}

/// Rows shaded together by the pass: each pixel's Km and mirror direction
/// are found once for the band and read by its neighbours too.
const BAND: usize = 16;

/// What the pass needs of a reflecting pixel.
#[derive(Debug, Clone, Copy)]
struct Mirror {
    /// Km there, its map applied.
    km: Vec3,
    /// The view's mirror direction there (the normal map's normal).
    r: Vec3,
}

/// Finds the [`Mirror`] of each pixel of a band of rows.
struct Mirrors<'a> {
    scene: &'a Scene,
    vb: &'a VisibilityBuffer,
    frames: &'a ObjectFrames,
    rays: &'a PixelRays,
    reflecting: &'a [bool],
}

impl Mirrors<'_> {
    /// The mirrors of `rows` and of the rows above and below them, row by
    /// row into `out` (`None` where a pixel shows nothing that reflects).
    fn fill(&self, rows: Range<usize>, cache: &mut TriangleCache, out: &mut Vec<Option<Mirror>>) {
        let (scene, vb) = (self.scene, self.vb);
        let w = vb.width() as usize;
        let (first, last) = (rows.start.saturating_sub(1), (rows.end + 1).min(vb.height() as usize));
        out.clear();
        out.resize((rows.len() + 2) * w, None);
        for y in first..last {
            let row = &mut out[(y + 1 - rows.start) * w..][..w];
            for (x, slot) in row.iter_mut().enumerate() {
                let item = vb.item(x as u32, y as u32);
                if item.is_none() || !self.reflecting[item.material(scene)] {
                    continue;
                }
                let ray = self.rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                let mut s = match item.primitive() {
                    Some(_) => self.frames.surface_at(scene, vb, x as u32, y as u32, &ray),
                    None => cache.get(scene, self.frames, item).surface(&ray),
                };
                let m = &scene.materials[s.material];
                let mut shared = SharedFootprint::default();
                super::normal_map::apply_shared(m, &mut s, &mut shared);
                let km = m.km
                    * m.maps.mirror.as_ref().map_or(Vec3::ONE, |t| {
                        let (uv, duv) = s.coords(t.set);
                        shared.sample(t, m.maps.filter, uv, duv)
                    });
                *slot = Some(Mirror { km, r: mirror_direction(&s) });
            }
        }
    }
}

/// Ie at one surface point: Km times the environment in the view's mirror
/// direction R = 2(N·V)N − V (zero without an environment or a Km), one
/// lookup of the map's finest level (a sample, not a pixel: the frame's pass
/// filters over each pixel's spread of directions).
#[must_use]
pub fn reflection_map(scene: &Scene, s: &SurfacePoint) -> Vec3 {
    let km = mirrored_share(&scene.materials[s.material], s);
    match &scene.environment {
        Some(env) if km.max_element() > 0.0 => km * env.radiance(mirror_direction(s)),
        _ => Vec3::ZERO,
    }
}

/// Km at `s`: the material's, times its mirror map there.
fn mirrored_share(m: &Material, s: &SurfacePoint) -> Vec3 {
    m.km * m.maps.mirror.as_ref().map_or(Vec3::ONE, |t| {
        let (uv, duv) = s.coords(t.set);
        t.sample_filtered(m.maps.filter, uv, duv)
    })
}

/// R = 2(N·V)N − V.
fn mirror_direction(s: &SurfacePoint) -> Vec3 {
    2.0 * s.normal.dot(s.to_eye) * s.normal - s.to_eye
}

/// What the first pass writes where no object is seen in a target holding the
/// emission component: the background colour, or black when the environment
/// shows there instead (added by [`add_reflection_map`]).
#[must_use]
pub fn flat_background(scene: &Scene) -> Vec3 {
    match &scene.environment {
        Some(env) if env.visible => Vec3::ZERO,
        _ => scene.background,
    }
}
