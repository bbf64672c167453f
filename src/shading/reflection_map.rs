//! The reflection-map pass of seed 002 eq. 4, run once per frame:
//! Ie(x, y) = Km · Mape(R), the environment image looked up along the view's
//! mirror direction R = 2(N·V)N − V at each surface whose material has a Km — a
//! reflection with no ray traced, which is all the paper's hardware could do.
//! The same pass writes the environment as the background where it is visible.
//! Each pixel's lookup is filtered over the directions its neighbours see (the
//! map's mip level matching that spread): a curved mirror seen small shows the
//! map's average there, not moiré.
//!
//! Each pixel's Km and mirror direction come from the frame's first shading
//! pass, which finds its normal-mapped normal and its maps anyway (the normal
//! and the mirror map filtered over the pixel's footprint, as the rest of its
//! shading reads them); a frame past `MIRROR_PIXELS` (`passes.rs`), or one
//! drawn in part, finds them here a band of rows at a time. On the
//! DamagedHelmet (every pixel a normal-mapped metal) handing them on took the
//! viewer's quick frame from 64.3–65.6 ms to 45.9–47.7 ms (1280×720, 2
//! threads, alternated).

use std::ops::Range;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::{Component, ObjectFrames, SurfacePoint, Target, TriangleCache};
use crate::camera::PixelRays;
use crate::scene::{Material, Scene, SharedFootprint};
use crate::visibility::VisibilityBuffer;

/// Adds Km · Mape(R) to every target holding the reflection component, and the
/// visible environment's background to every target holding the emission
/// component (the first pass left those pixels black). `found`: each pixel's
/// [`Mirror`], as the first shading pass found it (row by row, the pixels `vb`
/// holds); without it the pass finds them itself, a band of rows at a time.
/// The targets hold the pixels `vb` holds.
pub fn add_reflection_map(scene: &Scene, vb: &VisibilityBuffer, targets: &mut [Target], found: Option<&[Mirror]>) {
    let Some(env) = &scene.environment else { return };
    let reflecting: Vec<bool> = scene.materials.iter().map(Material::reflects_environment).collect();
    if !env.visible && !reflecting.contains(&true) {
        return;
    }
    // Pixels are named by the image's coordinates, stored from the held
    // rectangle's top left pixel.
    let held = vb.rect();
    let (w, x0, y0) = (held.width() as usize, i64::from(held.x0), held.y0 as usize);
    let frames = ObjectFrames::new(scene);
    let rays = scene.camera.pixel_rays(Vec2::new(vb.width() as f32, vb.height() as f32));
    let mirrors = Mirrors { scene, vb, frames: &frames, rays: &rays, reflecting: &reflecting };
    for t in targets {
        let (reflection, background) = (t.parts.contains(Component::Reflection), t.parts.contains(Component::Emission));
        if !(reflection || background && env.visible) {
            continue;
        }
        let bands = t.image.pixels_mut().par_chunks_mut(w * BAND).enumerate();
        let scratch = || (TriangleCache::new(512), Vec::new());
        bands.for_each_init(scratch, |(cache, band), (k, out)| {
            let rows = y0 + k * BAND..y0 + k * BAND + out.len() / w;
            // Row y of the band is row y + 1 of `band` (it holds one more
            // row above and below); of `found`, row y − y0.
            let (source, top) = match found {
                Some(all) => (all, y0 as i64),
                None => {
                    if reflection {
                        mirrors.fill(rows.clone(), cache, band);
                    }
                    (&band[..], rows.start as i64 - 1)
                }
            };
            let at = |x: i64, y: i64| {
                let (x, y) = (usize::try_from(x - x0).ok().filter(|&x| x < w)?, usize::try_from(y - top).ok()?);
                source.get(y * w + x).copied().filter(Mirror::reflects)
            };
            for (y, row) in rows.clone().zip(out.chunks_mut(w)) {
                let items = vb.item_row(y as u32);
                for (x, (px, &item)) in (held.x0 as usize..).zip(row.iter_mut().zip(items)) {
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
                            let (Ok(nx), Ok(ny)) = (u32::try_from(nx), u32::try_from(ny)) else { return false };
                            held.contains(nx, ny) && vb.item(nx, ny).object == item.object
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

/// What the pass needs of a pixel that shows a reflecting material.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Mirror {
    /// Km there, its map applied.
    pub km: Vec3,
    /// The view's unit mirror direction there (the normal map's normal);
    /// zero where the pixel shows nothing that reflects.
    pub r: Vec3,
}

impl Mirror {
    /// A pixel that shows nothing reflecting.
    pub const NONE: Mirror = Mirror { km: Vec3::ZERO, r: Vec3::ZERO };

    /// Whether the pixel shows a reflecting material.
    #[must_use]
    pub fn reflects(&self) -> bool {
        self.r != Vec3::ZERO
    }
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
    /// The mirrors of `rows` and of the rows above and below them (those
    /// held), row by row into `out`, the held columns of each
    /// ([`Mirror::NONE`] where a pixel shows nothing that reflects).
    fn fill(&self, rows: Range<usize>, cache: &mut TriangleCache, out: &mut Vec<Mirror>) {
        let (scene, vb) = (self.scene, self.vb);
        let held = vb.rect();
        let w = held.width() as usize;
        let first = rows.start.saturating_sub(1).max(held.y0 as usize);
        let last = (rows.end + 1).min(held.y1 as usize);
        out.clear();
        out.resize((rows.len() + 2) * w, Mirror::NONE);
        for y in first..last {
            let row = &mut out[(y + 1 - rows.start) * w..][..w];
            for (x, slot) in (held.x0 as usize..).zip(row.iter_mut()) {
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
                *slot = Mirror { km: mirrored_share(m, &s, &mut shared), r: mirror_direction(&s) };
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
    let km = mirrored_share(&scene.materials[s.material], s, &mut SharedFootprint::default());
    match &scene.environment {
        Some(env) if km.max_element() > 0.0 => km * env.radiance(mirror_direction(s)),
        _ => Vec3::ZERO,
    }
}

/// Km at `s`: the material's, times its mirror map there (read through
/// the point's `shared` footprint).
fn mirrored_share<'a>(m: &'a Material, s: &SurfacePoint, shared: &mut SharedFootprint<'a>) -> Vec3 {
    m.km * m.maps.mirror.as_ref().map_or(Vec3::ONE, |t| {
        let (uv, duv) = s.coords(t.set);
        shared.sample(t, m.maps.filter, uv, duv)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::LinearImage;
    use crate::shading::{shade_pass_finding_mirrors, Blend, ComponentSet, Lighting, ShadingPass};

    /// The mirrors the first shading pass hands on (found eight pixels at a
    /// time) are the ones the pass finds for itself a band at a time (one
    /// pixel at a time), so the reflection is the same either way; and the
    /// scene's chrome shows in it.
    #[test]
    fn the_mirrors_the_shading_pass_hands_on_are_the_ones_the_pass_finds() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/environment.toml");
        let scene = crate::scene::file::load_scene(&path).expect("environment.toml loads");
        let (w, h) = (160, 90);
        let mut vb = VisibilityBuffer::new(w, h);
        crate::visibility::rasterize(&scene, &mut vb);
        let mut found = vec![Mirror::NONE; (w * h) as usize];
        let lighting = Lighting::pass(scene.lights.iter(), Vec::new(), true);
        let pass = ShadingPass { lighting, blend: Blend::Replace, background: Vec3::ZERO, receivers: None };
        shade_pass_finding_mirrors(&scene, &vb, &mut LinearImage::new(w, h), &pass, Some(&mut found));
        let reflection = |found: Option<&[Mirror]>| {
            let mut image = LinearImage::new(w, h);
            let parts = ComponentSet::only(Component::Reflection);
            add_reflection_map(&scene, &vb, &mut [Target { parts, image: &mut image }], found);
            image
        };
        let (handed, own) = (reflection(Some(&found)), reflection(None));
        let mirrors = found.iter().filter(|m| m.reflects()).count();
        assert!(mirrors > 1000, "{mirrors} reflecting pixels");
        let lit = handed.pixels().iter().filter(|p| p.max_element() > 0.05).count();
        assert!(lit > 1000, "{lit} pixels show the environment");
        let worst =
            handed.pixels().iter().zip(own.pixels()).map(|(a, b)| (*a - *b).abs().max_element()).fold(0.0, f32::max);
        assert!(worst < 1e-3, "largest difference {worst}");
    }
}
