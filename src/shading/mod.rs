//! Shading passes over the visibility buffer (seed 002: Kawabata, Watanabe &
//! Sakai, Hitachi, §3; `docs/papers.md`): in each pass every
//! visible pixel's surface is reconstructed from its item id and lit by eq. 1, and
//! the passes are summed in a linear float accumulation buffer (eq. 4).
//!
//! `passes.rs` decides which lights share a pass ([`shade_lit`] runs a frame's);
//! [`shade_pass`] runs one, eight pixels at a time (`lanes.rs`); `phong.rs` is the
//! scalar statement of eq. 1 the lanes are tested against (with
//! `normal_map.rs`, the maps that tilt its normal); `reflection_map.rs`,
//! `fog.rs` and `translucency.rs` are the once-per-frame passes of §3.4, §3.5 and
//! eq. 4's Ie; `shadow_images.rs` writes each light's shadow term on its own.

pub(crate) mod fog;
// Public rather than crate-private: crate-private, its entry points were
// inlined otherwise into the shading row loop, and shadowed passes ran about
// 5% slower (`kage-bench raster`, kept-map rows, two builds alternated).
pub mod lanes;
pub(crate) mod normal_map;
pub(crate) mod passes;
pub(crate) mod phong;
pub(crate) mod reflection_map;
pub mod screen_occlusion;
pub(crate) mod shadow_images;
pub(crate) mod subpixel;
pub(crate) mod surface;
pub(crate) mod translucency;
pub(crate) mod visible;

use glam::{Vec2, Vec3};
use rayon::iter::Either;
use rayon::prelude::*;

use crate::image::LinearImage;
use crate::scene::{Material, Scene};
use crate::shadows::{Receiver, ShadowTerm};
use crate::visibility::{ItemId, VisibilityBuffer};

pub use lanes::{Blend, Lighting, OpenShares};
pub(crate) use passes::frame_lights_within;
pub use passes::{frame_lights, shade_lit, shade_lit_beside, FrameLight, PassStats, Target};
pub use phong::{Component, ComponentSet, Components};
pub use reflection_map::Mirror;
pub use subpixel::{SubpixelSample, SubpixelShading};
pub use surface::{ObjectFrames, PreparedTriangle, SurfacePoint};
pub use visible::screen_surfaces;

use phong::Coefficients;

/// One pass over the visibility buffer (seed 002 §3): what it adds, how it writes,
/// and which objects receive it.
#[derive(Debug, Clone)]
pub struct ShadingPass<'a> {
    /// The terms this pass computes.
    pub lighting: lanes::Lighting<'a>,
    /// Replace (the frame's first pass, which also writes the background) or add.
    pub blend: Blend,
    /// What a replacing pass writes where no object is seen.
    pub background: Vec3,
    /// Per object: whether it receives this pass (`None`: all do). Selective
    /// lighting (§3.3): the visibility buffer already holds the depth of ALL
    /// objects, so a light that lists some objects only reaches the pixels where
    /// one of them is the visible surface.
    pub receivers: Option<Vec<bool>>,
}

impl ShadingPass<'_> {
    fn receives(&self, item: ItemId) -> bool {
        !item.is_none() && self.receivers.as_ref().is_none_or(|r| r[item.object as usize])
    }
}

/// Runs one pass over `vb` into `image`, rows in parallel, eight pixels at a
/// time (`lanes.rs`): the pixels the buffer holds ([`VisibilityBuffer::rect`]),
/// which `image` holds too.
///
/// # Panics
///
/// If `image` and the pixels `vb` holds differ in size.
pub fn shade_pass(scene: &Scene, vb: &VisibilityBuffer, image: &mut LinearImage, pass: &ShadingPass) {
    shade_pass_finding_mirrors(scene, vb, image, pass, None);
}

/// [`shade_pass`], which also writes each pixel's [`Mirror`] into `mirrors`
/// (one a pixel, row by row; pixels that show no reflecting material are
/// left as they are), for the reflection-map pass: the shading finds each
/// pixel's normal-mapped normal and Km already.
///
/// # Panics
///
/// If `image` and the pixels `vb` holds differ in size, or `mirrors` from them.
pub fn shade_pass_finding_mirrors(
    scene: &Scene,
    vb: &VisibilityBuffer,
    image: &mut LinearImage,
    pass: &ShadingPass,
    mirrors: Option<&mut [Mirror]>,
) {
    // Pixels are named by the image's coordinates; the image, the buffer and
    // `mirrors` hold the columns x0.. of the held rows alone.
    let held = vb.rect();
    assert_eq!((image.width(), image.height()), (held.width(), held.height()), "image and buffer sizes");
    let (w, x0) = (held.width() as usize, held.x0 as usize);
    let frames = ObjectFrames::new(scene);
    let rays = scene.camera.pixel_rays(Vec2::new(vb.width() as f32, vb.height() as f32));
    let constants: Vec<Option<Coefficients>> = scene.materials.iter().map(Coefficients::constant).collect();
    // A triangle's coefficients are its material's constants unless a map
    // or its vertex colours vary them over it.
    let constant = |tri: &PreparedTriangle| constants[tri.material].as_ref().filter(|_| !tri.coloured());
    let sample = |s: &mut SurfacePoint| phong::sample_maps(&scene.materials[s.material], s);
    let (lighting, blend) = (&pass.lighting, pass.blend);
    // Whole rows of what a replacing pass writes where it shades nothing, copied
    // from (a block copy is faster than writing one 12-byte pixel at a time).
    let (background, black) = (vec![pass.background; w], vec![Vec3::ZERO; w]);
    let reflects: Vec<bool> = scene.materials.iter().map(Material::reflects_environment).collect();
    let mirror_rows = match mirrors {
        Some(m) => {
            assert_eq!(m.len(), image.pixels().len(), "a mirror a pixel");
            Either::Left(m.par_chunks_mut(w).map(Some))
        }
        None => Either::Right((0..held.height()).into_par_iter().map(|_| None)),
    };
    let rows = image.pixels_mut().par_chunks_mut(w).zip(vb.items().par_chunks(w)).zip(mirror_rows);
    let caches = || (TriangleCache::new(512), lanes::Block::default());
    rows.enumerate().for_each_init(caches, |(cache, block), (y, ((out, items), mut mirror_row))| {
        let y = y + held.y0 as usize;
        let row = lanes::RowRays::new(&rays, y);
        let (mut x, w) = (x0, held.x1 as usize);
        // Row slices are indexed by column − x0.
        let at = |x: usize| x - x0;
        while x < w {
            // Runs stop at every SEGMENT-th column, so the pixels of a segment
            // are shaded alike whatever lies outside it (a tile of the frame
            // shades them as the whole frame does).
            let segment_end = ((x / SEGMENT + 1) * SEGMENT).min(w);
            let items = &items[..at(segment_end)];
            let first = items[at(x)];
            let run = x0 + run_end(items, at(x));
            if !pass.receives(first) {
                // Background, or objects this pass does not light: written once by a
                // replacing pass, left alone by an adding one.
                if blend == Blend::Replace {
                    let fill = if first.is_none() { &background } else { &black };
                    out[at(x)..at(run)].copy_from_slice(&fill[..run - x]);
                }
                x = run;
                continue;
            }
            // A run of one triangle shares its plane. A solid's pixels share one
            // where they show one flat face (the same primitive and normal: a
            // polyhedron's face, a cylinder's cap); on a curved surface each
            // pixel has its own tangent plane.
            let run = match first.primitive() {
                None => run,
                Some(_) => {
                    let n = vb.normal(x as u32, y as u32);
                    x + (x..run).take_while(|&k| vb.normal(k as u32, y as u32) == n).count()
                }
            };
            let whole = x + (run - x) / lanes::LANES * lanes::LANES;
            if whole > x {
                let tangent;
                let tri = if first.primitive().is_some() {
                    let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                    tangent = frames.prepare_at(scene, vb, x as u32, y as u32, &ray);
                    &tangent
                } else {
                    cache.get(scene, &frames, first)
                };
                if let Some(k) = constant(tri) {
                    let mirrors =
                        mirror_row.as_deref_mut().filter(|_| reflects[tri.material]).map(|m| &mut m[at(x)..at(whole)]);
                    lanes::shade_run(tri, k, &row, x, lighting, blend, &mut out[at(x)..at(whole)], mirrors);
                    x = whole;
                    continue;
                }
            }
            let end = (x + lanes::LANES).min(segment_end);
            block.clear();
            for (i, (&item, px)) in items[at(x)..at(end)].iter().zip(out[at(x)..at(end)].iter_mut()).enumerate() {
                if !pass.receives(item) {
                    if blend == Blend::Replace {
                        *px = if item.is_none() { pass.background } else { Vec3::ZERO };
                    }
                    continue;
                }
                let tangent;
                let tri = if item.primitive().is_some() {
                    let ray = rays.ray(Vec2::new((x + i) as f32 + 0.5, y as f32 + 0.5));
                    tangent = frames.prepare_at(scene, vb, (x + i) as u32, y as u32, &ray);
                    &tangent
                } else {
                    cache.get(scene, &frames, item)
                };
                block.set(i, tri, constant(tri));
            }
            if block.live.iter().any(|&l| l) {
                let mirrors = mirror_row.as_deref_mut().map(|m| (&mut m[at(x)..at(end)], &reflects[..]));
                block.shade(&row, x, lighting, sample, blend, &mut out[at(x)..at(end)], mirrors);
            }
            x = end;
        }
    });
}

/// Columns of a row shaded on their own: runs of one triangle and blocks of
/// eight are cut at multiples of it, so a pixel's arithmetic depends only on
/// the items of its own segment. A tile of a frame whose columns start and end
/// on segment borders is shaded bit for bit as the whole frame is.
pub const SEGMENT: usize = 64;

/// End of the run of pixels from `x` that show the same item as pixel `x`.
fn run_end(items: &[ItemId], x: usize) -> usize {
    let key = items[x].key();
    let rest = &items[x..];
    // Whole groups of eight first: comparing a group without stopping early lets
    // the compiler compare several ids per instruction.
    let same = |group: &[ItemId]| group.iter().fold(true, |all, i| all & (i.key() == key));
    let whole = rest.chunks_exact(8).take_while(|g| same(g)).count() * 8;
    x + whole + rest[whole..].iter().position(|i| i.key() != key).unwrap_or(rest.len() - whole)
}

/// A small direct-mapped cache of prepared triangles, one per worker: the rows
/// a worker shades in turn keep meeting the same triangles, and so do the
/// sub-pixel samples it sets up along an edge.
pub(crate) struct TriangleCache {
    slots: Vec<Option<PreparedTriangle>>,
}

impl TriangleCache {
    /// A cache of `slots` entries.
    pub(crate) fn new(slots: usize) -> Self {
        TriangleCache { slots: vec![None; slots.max(1)] }
    }

    /// Where among `slots` slots `item` is held (by this cache, or by a
    /// cache of something else per triangle kept beside it).
    pub(crate) fn slot(item: ItemId, slots: usize) -> usize {
        (item.triangle as usize ^ (item.object as usize).wrapping_mul(0x9E37)) % slots
    }

    /// `item`'s triangle (a mesh's), prepared now unless it is held.
    pub(crate) fn get(&mut self, scene: &Scene, frames: &ObjectFrames, item: ItemId) -> &PreparedTriangle {
        let at = Self::slot(item, self.slots.len());
        let slot = &mut self.slots[at];
        match slot {
            Some(t) if t.item == item => {}
            _ => *slot = Some(frames.prepare(scene, item)),
        }
        slot.as_ref().expect("filled above")
    }
}

/// The scalar reference of [`shade_lit`]: one pixel at a time through
/// [`PreparedTriangle::surface`] and `phong::add_light`, with the frame's
/// lights ([`passes::frame_lights`]), each one's shadow term (the mean of its
/// samples') and its selective-lighting list.
pub fn shade_into_scalar(scene: &Scene, vb: &VisibilityBuffer, image: &mut LinearImage) {
    let bounds = scene.caster_bounds().unwrap_or_default();
    let lights = passes::frame_lights_within(scene, bounds);
    let mut frame = passes::ShadowFrame::within(scene, vb, bounds);
    let terms: Vec<Vec<ShadowTerm>> = lights
        .iter()
        .map(|l| {
            let mut terms: Vec<ShadowTerm> = l.samples.iter().map(|s| ShadowTerm::build(scene, s)).collect();
            terms.iter_mut().for_each(|t| frame.ready(l, t));
            terms
        })
        .collect();
    let held = vb.rect();
    let w = held.width() as usize;
    let frames = ObjectFrames::new(scene);
    let rays = scene.camera.pixel_rays(Vec2::new(vb.width() as f32, vb.height() as f32));
    let rows = image.pixels_mut().par_chunks_mut(w).zip(vb.items().par_chunks(w));
    rows.enumerate().for_each(|(y, (out, items))| {
        let y = y + held.y0 as usize;
        for (x, (px, &item)) in (held.x0 as usize..).zip(out.iter_mut().zip(items)) {
            if item.is_none() {
                *px = scene.background;
                continue;
            }
            let at = |dx: f32, dy: f32| {
                let ray = rays.ray(Vec2::new(x as f32 + 0.5 + dx, y as f32 + 0.5 + dy));
                frames.surface_at(scene, vb, x as u32, y as u32, &ray)
            };
            let centre = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let triangle = frames.prepare_at(scene, vb, x as u32, y as u32, &centre);
            let receiver = Receiver { object: item.object, plane: triangle.geometry().geometric };
            let mut s = triangle.surface(&centre);
            // Ray differentials: the same triangle met one pixel right and one below.
            s.duv = [at(1.0, 0.0).uv - s.uv, at(0.0, 1.0).uv - s.uv];
            let k = phong::sample_maps(&scene.materials[s.material], &mut s);
            let mut acc = Components { emission: k.parts().3, ..Default::default() };
            for (light, terms) in lights.iter().map(|l| &l.light).zip(&terms) {
                if light.only.as_ref().is_some_and(|o| !o.contains(&(item.object as usize))) {
                    continue;
                }
                let cos_theta = s.normal.dot(light.incident(s.position).to_light);
                let shadow =
                    if cos_theta > 0.0 { ShadowTerm::mean_lit(terms, s.position, cos_theta, &receiver) } else { 1.0 };
                phong::add_light(&mut acc, light, &k, &s, shadow);
            }
            *px = acc.total();
        }
    });
}
