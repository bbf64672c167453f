//! Translucency (seed 002 §3.4): opaque surfaces first, then translucent ones
//! blended over them, far to near, with alpha = the material's opacity (times
//! its alpha map's at the fragment).
//!
//! The paper sorts translucent objects far to near and draws them with alpha
//! blending; where they cannot be sorted it draws them in any order with z-writes
//! off, and notes that overlaps then come out wrong. kage sorts finer than the
//! paper: the polygon pass lists every translucent fragment in front of the opaque
//! surface ([`crate::visibility::fragments`]) and the fragments of each pixel are
//! sorted by depth, so intersecting translucent surfaces blend correctly on each
//! side of their intersection. [`TranslucencyOrder::Unsorted`] keeps the paper's
//! fallback — drawing order, z-write off — for comparison.
//!
//! Blending "over", far to near, gives a pixel
//! `C = T · C_opaque + Σ_k w_k · S_k` with `w_k = α_k · Π_{j nearer} (1 − α_j)` and
//! `T = Π (1 − α_k)`: linear in each fragment's shaded colour S_k. So the opaque
//! image (every component) is scaled by T once, and each light's contribution to
//! each fragment is added with its weight — one light at a time, its shadow maps
//! rendered and dropped as in the opaque passes. Each fragment gets its own fog.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::phong::{self, Coefficients, Components};
use super::reflection_map::reflection_map;
use super::{frame_lights_within, Component, FrameLight, ObjectFrames, SurfacePoint, Target, TriangleCache};
use crate::scene::{Scene, TranslucencyOrder};
use crate::shadows::{MapPool, Receiver, ShadowTerm};
use crate::visibility::{Fragment, VisibilityBuffer};

/// The translucent fragments of a frame ready to be added, kept from frame to
/// frame so that their memory is reused: some hundred bytes a fragment,
/// which allocated afresh for each frame cost more in page faults than
/// preparing the fragments did.
#[derive(Debug, Default)]
pub struct Layers(Vec<Layer>);

/// One translucent fragment, ready to be added.
#[derive(Debug)]
struct Layer {
    pixel: usize,
    /// Its opacity.
    alpha: f32,
    /// Its share of the pixel: its opacity times what the nearer layers let
    /// through.
    weight: f32,
    surface: SurfacePoint,
    k: Coefficients,
    object: usize,
    fog: f32,
    lit: Components,
}

/// Blends `fragments` (in front of the opaque surfaces) into every target, in
/// the scene's [`TranslucencyOrder`], lit by the frame's lights (their shadow
/// maps taken from `pool`). Returns how many fragments were blended and, when
/// there were some, each pixel's transmittance: the share of the opaque
/// surface behind them that it still shows. The targets, the fragments'
/// pixels and the transmittance hold the pixels of the visibility buffer
/// `opaque`, which the fragments were found in front of. The fragments are
/// prepared in `kept`.
pub fn composite(
    scene: &Scene,
    opaque: &VisibilityBuffer,
    mut fragments: Vec<Fragment>,
    targets: &mut [Target],
    pool: &mut MapPool,
    kept: &mut Layers,
) -> (usize, Option<Vec<f32>>) {
    if fragments.is_empty() {
        return (0, None);
    }
    // Nearest first within each pixel: by depth, or the last drawn first.
    match scene.translucency {
        TranslucencyOrder::Sorted => fragments.par_sort_unstable_by_key(nearest_first),
        TranslucencyOrder::Unsorted => {
            let mut indexed: Vec<(usize, Fragment)> = fragments.into_iter().enumerate().collect();
            indexed.par_sort_by(|(i, a), (j, b)| a.pixel.cmp(&b.pixel).then(j.cmp(i)));
            fragments = indexed.into_iter().map(|(_, f)| f).collect();
        }
    }
    let mut transmittance = vec![1.0f32; opaque.depths().len()];
    prepare(scene, &fragments, opaque, &mut kept.0);
    let layers = &mut kept.0;
    let width = opaque.rect().width().max(1) as usize;
    let rows = Rows::of(layers, width, transmittance.len() / width);
    front_to_back_weights(layers, &rows, &mut transmittance);
    for t in targets.iter_mut() {
        t.image.pixels_mut().par_iter_mut().zip(transmittance.par_iter()).for_each(|(p, &tr)| *p *= tr);
    }
    // Where a texture's alpha is 0 the fragment adds nothing.
    let adds = |l: &Layer| l.weight > 0.0;
    let bounds = scene.caster_bounds().unwrap_or_default();
    for FrameLight { light, samples } in &frame_lights_within(scene, bounds) {
        let terms = pool.terms(scene, samples, bounds);
        let lit = |l: &&mut Layer| adds(l) && light.only.as_ref().is_none_or(|o| o.contains(&l.object));
        layers.par_iter_mut().with_min_len(256).filter(lit).for_each(|l| {
            let s = &l.surface;
            let cos = s.normal.dot(light.incident(s.position).to_light);
            let shadow = if cos > 0.0 {
                ShadowTerm::mean_lit(&terms, s.position, cos, &Receiver::of_object(l.object as u32))
            } else {
                1.0
            };
            phong::add_light(&mut l.lit, light, &l.k, s, shadow);
        });
        terms.into_iter().for_each(|t| pool.recycle(t));
    }
    for t in targets.iter_mut() {
        add_layers(scene, layers, &rows, t);
    }
    (layers.iter().filter(|l| adds(l)).count(), Some(transmittance))
}

/// A fragment's place in the sorted order: by pixel, then nearest (largest
/// reversed depth) first, then by item, so that the order is the same
/// whatever order the fragments came in. One number, compared at once.
fn nearest_first(f: &Fragment) -> u128 {
    // Reversed depth is positive: its bits order as the numbers do.
    let farther = u32::MAX - f.depth.to_bits();
    (u128::from(f.pixel) << 96)
        | (u128::from(farther) << 64)
        | (u128::from(f.item.object) << 32)
        | u128::from(f.item.triangle)
}

/// Where each row of pixels' layers start in a list sorted by pixel: row
/// `r`'s are `starts[r]..starts[r + 1]`.
struct Rows {
    starts: Vec<usize>,
    width: usize,
}

impl Rows {
    /// The rows of `rows` rows of `width` pixels.
    fn of(layers: &[Layer], width: usize, rows: usize) -> Self {
        let starts = (0..=rows).map(|r| layers.partition_point(|l| l.pixel < r * width)).collect();
        Rows { starts, width }
    }

    /// `layers` cut into each row's.
    fn split<'a>(&self, mut layers: &'a mut [Layer]) -> Vec<&'a mut [Layer]> {
        let mut out = Vec::with_capacity(self.starts.len());
        for w in self.starts.windows(2) {
            let (row, rest) = layers.split_at_mut(w[1] - w[0]);
            out.push(row);
            layers = rest;
        }
        out
    }
}

/// Each layer's weight α · (transmittance of the layers nearer than it, in
/// the order given); leaves each pixel's total transmittance in
/// `transmittance`. Rows in parallel.
fn front_to_back_weights(layers: &mut [Layer], rows: &Rows, transmittance: &mut [f32]) {
    let width = rows.width;
    let per_row = rows.split(layers).into_par_iter().zip(transmittance.par_chunks_mut(width)).enumerate();
    per_row.for_each(|(r, (layers, transmittance))| {
        for l in layers {
            let t = &mut transmittance[l.pixel - r * width];
            l.weight = l.alpha * *t;
            *t *= 1.0 - l.alpha;
        }
    });
}

/// The surface, opacity (the material's, times its alpha map's),
/// coefficients, emission and fog of every fragment (found in front of
/// `opaque`), into `layers`.
fn prepare(scene: &Scene, fragments: &[Fragment], opaque: &VisibilityBuffer, layers: &mut Vec<Layer>) {
    let frames = ObjectFrames::new(scene);
    let rays = scene.camera.pixel_rays(Vec2::new(opaque.width() as f32, opaque.height() as f32));
    let held = opaque.rect();
    let stride = held.width().max(1);
    layers.clear();
    let prepared = fragments.par_iter().with_min_len(256).map_init(
        || TriangleCache::new(512),
        |cache, f| {
            let (x, y) = (held.x0 + f.pixel % stride, held.y0 + f.pixel / stride);
            let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let mut surface = cache.get(scene, &frames, f.item).surface(&ray);
            let material = &scene.materials[surface.material];
            let (uv, duv) = surface.coords(material.alpha_set());
            let alpha = material.alpha_at(uv, duv);
            let k = phong::sample_maps(material, &mut surface);
            let fog = scene.fog.map_or(0.0, |fog| fog.amount_at(&scene.camera, surface.position));
            let lit = Components { emission: k.parts().3, ..Default::default() };
            Layer { pixel: f.pixel as usize, alpha, weight: 0.0, surface, k, object: f.item.object as usize, fog, lit }
        },
    );
    prepared.collect_into_vec(layers);
}

/// Adds each layer's share of `t`'s components to `t`, rows in parallel.
fn add_layers(scene: &Scene, layers: &[Layer], rows: &Rows, t: &mut Target) {
    let parts = t.parts;
    let want = |c| if parts.contains(c) { 1.0 } else { 0.0 };
    let (ambient, diffuse, specular, emission) =
        (want(Component::Ambient), want(Component::Diffuse), want(Component::Specular), want(Component::Emission));
    let fog_colour = scene.fog.filter(|_| parts.contains(Component::Fog)).map_or(Vec3::ZERO, |f| f.color);
    let width = rows.width;
    t.image.pixels_mut().par_chunks_mut(width).zip(rows.starts.par_windows(2)).enumerate().for_each(|(r, (row, w))| {
        for l in layers[w[0]..w[1]].iter().filter(|l| l.weight > 0.0) {
            let c = l.lit;
            let mut colour = c.ambient * ambient + c.diffuse * diffuse + c.specular * specular + c.emission * emission;
            if parts.contains(Component::Reflection) {
                colour += reflection_map(scene, &l.surface);
            }
            row[l.pixel - r * width] += l.weight * (colour * (1.0 - l.fog) + fog_colour * l.fog);
        }
    });
}
