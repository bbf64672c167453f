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
//! each fragment is added with its weight. Lights nothing shadows are added while
//! the fragments are prepared (one pass over them, which is all an x-ray view
//! needs: its lights cast no shadows); each other light is added in a pass of its
//! own, its shadow maps rendered and dropped as in the opaque passes. Each fragment
//! gets its own fog.
//!
//! Preparing the fragments is most of the cost (208 k fragments on the milk
//! truck's x-ray, about 23 ms of a 31 ms frame on the 2-core machine of
//! `docs/benchmarks.md`), so it is kept lean: the fragments are put in pixel
//! order by a counting sort (a comparison sort of the whole list took four
//! times as long), each triangle's ray intersection is set up once as affine
//! forms of the pixel ([`ScreenTriangle`]: a fragment costs three forms and a
//! division, and its texture footprint — the same triangle one pixel over —
//! two more divisions), and a layer keeps a few dozen bytes: the passes over
//! all of them (weights, blending) read little memory.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::phong::{self, Coefficients, Components};
use super::reflection_map::reflection_map;
use super::surface::{PreparedTriangle, TriangleGeometry};
use super::{frame_lights_within, Component, FrameLight, ObjectFrames, SurfacePoint, Target, TriangleCache};
use crate::camera::{PixelRays, Ray};
use crate::scene::{Scene, TranslucencyOrder};
use crate::shadows::{MapPool, Receiver, ShadowTerm};
use crate::visibility::{Fragment, ItemId, VisibilityBuffer};

/// The translucent fragments of a frame ready to be added, kept from frame to
/// frame so that their memory is reused (allocated afresh for each frame, it
/// cost more in page faults than preparing the fragments did).
#[derive(Debug, Default)]
pub struct Layers {
    layers: Vec<Layer>,
    /// Each layer's surface and coefficients, kept only while lights with
    /// shadow maps are still to be added.
    details: Vec<Detail>,
}

/// One translucent fragment, ready to be added: a few dozen bytes, so that
/// the passes over all of them (weights, blending) read little memory.
#[derive(Debug)]
struct Layer {
    /// Its pixel ([`VisibilityBuffer::index`] of the opaque buffer).
    pixel: u32,
    /// Its object.
    object: u32,
    /// Its opacity.
    alpha: f32,
    /// Its share of the pixel: its opacity times what the nearer layers let
    /// through.
    weight: f32,
    fog: f32,
    lit: Components,
    /// The environment's reflection in it (zero unless a target adds it).
    reflection: Vec3,
}

/// What lighting a [`Layer`] by one more light reads.
#[derive(Debug)]
struct Detail {
    surface: SurfacePoint,
    k: Coefficients,
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
    fragments: Vec<Fragment>,
    targets: &mut [Target],
    pool: &mut MapPool,
    kept: &mut Layers,
) -> (usize, Option<Vec<f32>>) {
    if fragments.is_empty() {
        return (0, None);
    }
    // Nearest first within each pixel: by depth, or the last drawn first.
    let fragments = by_pixel(&fragments, opaque.depths().len(), scene.translucency);
    let mut transmittance = vec![1.0f32; opaque.depths().len()];
    let bounds = scene.caster_bounds().unwrap_or_default();
    // Lights nothing shadows are added as the fragments are prepared (one
    // pass over them); each of the others needs its shadow maps, rendered
    // and dropped one light at a time.
    let (unshadowed, shadowed): (Vec<FrameLight>, Vec<FrameLight>) =
        frame_lights_within(scene, bounds).into_iter().partition(|l| !l.light.casts_shadows());
    let reflect = targets.iter().any(|t| t.parts.contains(Component::Reflection));
    let keep = !shadowed.is_empty();
    prepare(scene, &fragments, opaque, (&unshadowed, reflect, keep), kept);
    let layers = &mut kept.layers;
    let width = opaque.rect().width().max(1) as usize;
    let rows = Rows::of(layers, width, transmittance.len() / width);
    front_to_back_weights(layers, &rows, &mut transmittance);
    for t in targets.iter_mut() {
        t.image.pixels_mut().par_iter_mut().zip(transmittance.par_iter()).for_each(|(p, &tr)| *p *= tr);
    }
    // Where a texture's alpha is 0 the fragment adds nothing.
    let adds = |l: &Layer| l.weight > 0.0;
    for FrameLight { light, samples } in &shadowed {
        let terms = pool.terms(scene, samples, bounds);
        let lit = |(l, _): &(&mut Layer, &Detail)| {
            adds(l) && light.only.as_ref().is_none_or(|o| o.contains(&(l.object as usize)))
        };
        let each = layers.par_iter_mut().zip(kept.details.par_iter()).with_min_len(256);
        each.filter(lit).for_each(|(l, Detail { surface: s, k })| {
            let cos = s.normal.dot(light.incident(s.position).to_light);
            let shadow = if cos > 0.0 {
                ShadowTerm::mean_lit(&terms, s.position, cos, &Receiver::of_object(l.object))
            } else {
                1.0
            };
            phong::add_light(&mut l.lit, light, k, s, shadow);
        });
        terms.into_iter().for_each(|t| pool.recycle(t));
    }
    for t in targets.iter_mut() {
        add_layers(scene, layers, &rows, t);
    }
    (layers.iter().filter(|l| adds(l)).count(), Some(transmittance))
}

/// `fragments` (in drawing order) sorted by pixel, each pixel's in `order`:
/// nearest first ([`nearest_first`]), or the last drawn first. A counting
/// sort by pixel (stable, so each pixel's stay in drawing order), then each
/// pixel's few sorted on their own: a comparison sort of the whole list by
/// one key took four times as long.
fn by_pixel(fragments: &[Fragment], pixels: usize, order: TranslucencyOrder) -> Vec<Fragment> {
    let mut starts = vec![0u32; pixels + 1];
    for f in fragments {
        starts[f.pixel as usize + 1] += 1;
    }
    for i in 0..pixels {
        starts[i + 1] += starts[i];
    }
    let mut next = starts.clone();
    let mut sorted = fragments.to_vec();
    for f in fragments {
        let at = &mut next[f.pixel as usize];
        sorted[*at as usize] = *f;
        *at += 1;
    }
    // Each pixel's run of two or more, cut off the list in turn.
    let (mut runs, mut rest, mut cut) = (Vec::new(), sorted.as_mut_slice(), 0);
    for w in starts.windows(2).filter(|w| w[1] - w[0] > 1) {
        let (start, end) = (w[0] as usize, w[1] as usize);
        let (run, tail) = std::mem::take(&mut rest)[start - cut..].split_at_mut(end - start);
        runs.push(run);
        (rest, cut) = (tail, end);
    }
    runs.into_par_iter().with_min_len(1024).for_each(|run| match order {
        TranslucencyOrder::Sorted => run.sort_unstable_by_key(nearest_first),
        TranslucencyOrder::Unsorted => run.reverse(),
    });
    sorted
}

/// A fragment's place in a pixel's sorted order: nearest (largest reversed
/// depth) first, then by item, so that the order is the same whatever order
/// the fragments came in. One number, compared at once.
fn nearest_first(f: &Fragment) -> u128 {
    // Reversed depth is positive: its bits order as the numbers do.
    let farther = u32::MAX - f.depth.to_bits();
    (u128::from(farther) << 64) | (u128::from(f.item.object) << 32) | u128::from(f.item.triangle)
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
        let starts = (0..=rows).map(|r| layers.partition_point(|l| (l.pixel as usize) < r * width)).collect();
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
            let t = &mut transmittance[l.pixel as usize - r * width];
            l.weight = l.alpha * *t;
            *t *= 1.0 - l.alpha;
        }
    });
}

/// Triangles a worker keeps prepared (and their [`ScreenTriangle`]s).
const FORMS: usize = 512;

/// The opacity (the material's, times its alpha map's), emission, fog,
/// reflection (if `reflect`) and light from the `unshadowed` lights of every
/// fragment (found in front of `opaque`), into `kept`'s layers; their surfaces
/// and coefficients into its details too if `keep` (for the lights still to
/// add).
fn prepare(
    scene: &Scene,
    fragments: &[Fragment],
    opaque: &VisibilityBuffer,
    (unshadowed, reflect, keep): (&[FrameLight], bool, bool),
    kept: &mut Layers,
) {
    let frames = ObjectFrames::new(scene);
    let rays = ScreenRays::new(&scene.camera.pixel_rays(Vec2::new(opaque.width() as f32, opaque.height() as f32)));
    let held = opaque.rect();
    let stride = held.width().max(1);
    let one = |(cache, forms): &mut (TriangleCache, Vec<Option<(ItemId, ScreenTriangle)>>), f: &Fragment| {
        let (x, y) = (held.x0 + f.pixel % stride, held.y0 + f.pixel / stride);
        let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let triangle = cache.get(scene, &frames, f.item);
        let slot = &mut forms[TriangleCache::slot(f.item, FORMS)];
        let form = match slot {
            Some((item, form)) if *item == f.item => *form,
            _ => slot.insert((f.item, ScreenTriangle::new(&rays, &triangle.geometry()))).1,
        };
        let mut surface = form.surface(triangle, &rays, centre);
        // Ray differentials, as the opaque surfaces get them: the same
        // triangle's plane met one pixel right and one below (so a
        // texture is read at the level that matches the pixel).
        let uv = |d: Vec2| form.weights(centre + d).map_or(surface.uv, |w| triangle.uv_at(w));
        surface.duv = [uv(Vec2::X) - surface.uv, uv(Vec2::Y) - surface.uv];
        let material = &scene.materials[surface.material];
        let (uv, duv) = surface.coords(material.alpha_set());
        let alpha = material.alpha_at(uv, duv);
        let k = phong::sample_maps(material, &mut surface);
        let fog = scene.fog.map_or(0.0, |fog| fog.amount_at(&scene.camera, surface.position));
        let mut lit = Components { emission: k.parts().3, ..Default::default() };
        for FrameLight { light, .. } in unshadowed {
            if light.only.as_ref().is_none_or(|o| o.contains(&(f.item.object as usize))) {
                phong::add_light(&mut lit, light, &k, &surface, 1.0);
            }
        }
        let reflection = if reflect { reflection_map(scene, &surface) } else { Vec3::ZERO };
        let layer = Layer { pixel: f.pixel, object: f.item.object, alpha, weight: 0.0, fog, lit, reflection };
        (layer, Detail { surface, k })
    };
    let each = fragments.par_iter().with_min_len(256);
    let caches = || (TriangleCache::new(FORMS), vec![None; FORMS]);
    if keep {
        each.map_init(caches, one).unzip_into_vecs(&mut kept.layers, &mut kept.details);
    } else {
        // Without the details: no surface or coefficients written.
        each.map_init(caches, |c, f| one(c, f).0).collect_into_vec(&mut kept.layers);
        kept.details.clear();
    }
}

/// A value affine in a pixel's position `p`: `c + p.x · dx + p.y · dy`.
#[derive(Debug, Clone, Copy)]
struct Affine {
    c: f32,
    dx: f32,
    dy: f32,
}

impl Affine {
    fn at(self, p: Vec2) -> f32 {
        self.c + p.x * self.dx + p.y * self.dy
    }
}

/// A vector affine in a pixel's position: `v + p.x · dx + p.y · dy`.
#[derive(Debug, Clone, Copy)]
struct AffineVec {
    v: Vec3,
    dx: Vec3,
    dy: Vec3,
}

impl AffineVec {
    /// The same vector at every pixel.
    fn constant(v: Vec3) -> Self {
        AffineVec { v, dx: Vec3::ZERO, dy: Vec3::ZERO }
    }

    fn at(&self, p: Vec2) -> Vec3 {
        self.v + p.x * self.dx + p.y * self.dy
    }

    fn dot(&self, c: Vec3) -> Affine {
        Affine { c: self.v.dot(c), dx: self.dx.dot(c), dy: self.dy.dot(c) }
    }
}

/// A camera's pixel rays ([`PixelRays::ray`]) as affine functions of the
/// pixel's position: through a perspective camera the origin is fixed and
/// the (unnormalised) direction affine, through an orthographic one the
/// origin is affine and the direction fixed.
#[derive(Debug, Clone, Copy)]
struct ScreenRays {
    origin: AffineVec,
    dir: AffineVec,
    ortho: bool,
}

impl ScreenRays {
    fn new(rays: &PixelRays) -> Self {
        // The image plane's offset from its centre.
        let (dx, dy) = (2.0 * rays.right / rays.size.x, -2.0 * rays.up / rays.size.y);
        let offset = |at: Vec3| AffineVec { v: at + rays.up - rays.right, dx, dy };
        if rays.ortho {
            let dir = AffineVec::constant(rays.forward.normalize());
            ScreenRays { origin: offset(rays.origin), dir, ortho: true }
        } else {
            ScreenRays { origin: AffineVec::constant(rays.origin), dir: offset(rays.forward), ortho: false }
        }
    }

    /// The ray through pixel position `p` (a unit direction) and the length
    /// of its unnormalised direction.
    fn ray(&self, p: Vec2) -> (Ray, f32) {
        let d = self.dir.at(p);
        let length = d.length();
        (Ray { origin: self.origin.at(p), dir: d / length }, length)
    }
}

/// A triangle's ray intersection (Möller–Trumbore) as a function of the
/// pixel: the determinant and the two barycentric numerators are affine in
/// the pixel's position ([`ScreenRays`]: one of the ray's origin and
/// direction is fixed, the other affine), and so is the distance's
/// numerator. Set up once a triangle, a pixel then costs three affine forms
/// and a division instead of two cross products, four dot products and a
/// division — and the differentials one pixel over, a division each.
#[derive(Debug, Clone, Copy)]
struct ScreenTriangle {
    det: Affine,
    b1: Affine,
    b2: Affine,
    /// The distance's numerator (along the unnormalised direction).
    t: Affine,
}

impl ScreenTriangle {
    fn new(rays: &ScreenRays, g: &TriangleGeometry) -> Self {
        let (e1, e2) = (g.e1, g.e2);
        let det = rays.dir.dot(e2.cross(e1));
        if rays.ortho {
            let (dir, from_a) = (rays.dir.v, AffineVec { v: rays.origin.v - g.a, ..rays.origin });
            let (b1, b2, t) = (from_a.dot(dir.cross(e2)), from_a.dot(e1.cross(dir)), from_a.dot(e1.cross(e2)));
            ScreenTriangle { det, b1, b2, t }
        } else {
            let from_a = rays.origin.v - g.a;
            let q = from_a.cross(e1);
            let t = AffineVec::constant(e2).dot(q);
            ScreenTriangle { det, b1: rays.dir.dot(e2.cross(from_a)), b2: rays.dir.dot(q), t }
        }
    }

    /// The reciprocal of the determinant and the barycentric weights at
    /// pixel position `p` (`None` edge-on).
    fn hit(&self, p: Vec2) -> Option<(f32, [f32; 3])> {
        let det = self.det.at(p);
        if det.abs() < f32::MIN_POSITIVE {
            return None;
        }
        let inv = 1.0 / det;
        let (b1, b2) = (self.b1.at(p) * inv, self.b2.at(p) * inv);
        Some((inv, [1.0 - b1 - b2, b1, b2]))
    }

    /// The barycentric weights at pixel position `p` (`None` edge-on).
    fn weights(&self, p: Vec2) -> Option<[f32; 3]> {
        self.hit(p).map(|(_, w)| w)
    }

    /// `triangle`'s surface point at pixel position `p`.
    fn surface(&self, triangle: &PreparedTriangle, rays: &ScreenRays, p: Vec2) -> SurfacePoint {
        let (ray, length) = rays.ray(p);
        match self.hit(p) {
            // `t` is along the unnormalised direction.
            Some((inv, w)) => triangle.surface_at(&ray, self.t.at(p) * inv * length, w),
            None => triangle.surface(&ray),
        }
    }
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
                colour += l.reflection;
            }
            row[l.pixel as usize - r * width] += l.weight * (colour * (1.0 - l.fog) + fog_colour * l.fog);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Projection;

    /// A triangle's point and texture coordinates found through its
    /// [`ScreenTriangle`] are those the ray through the pixel finds
    /// (Möller–Trumbore, [`PreparedTriangle::surface`]), through a
    /// perspective and an orthographic camera.
    #[test]
    fn screen_forms_meet_the_triangle_where_the_pixels_ray_does() {
        let mut scene = crate::scene::demo::demo_scene().expect("the demo");
        let frames = ObjectFrames::new(&scene);
        let size = Vec2::new(320.0, 180.0);
        let mut checked = 0;
        for projection in [Projection::Perspective { fov_y_deg: 50.0 }, Projection::Orthographic { height: 6.0 }] {
            scene.camera.projection = projection;
            let rays = scene.camera.pixel_rays(size);
            let screen = ScreenRays::new(&rays);
            for (object, o) in scene.objects.iter().enumerate() {
                let Some(mesh) = o.triangles() else { continue };
                for triangle in (0..mesh.triangles.len()).step_by(97) {
                    let item = ItemId { object: object as u32, triangle: triangle as u32 };
                    let prepared = frames.prepare(&scene, item);
                    let form = ScreenTriangle::new(&screen, &prepared.geometry());
                    for k in 0..8u32 {
                        let p = Vec2::new((37 * k + triangle as u32) as f32 % size.x, (23 * k) as f32 % size.y);
                        let ray = rays.ray(p);
                        // Not at a grazing angle, where both lose precision.
                        if prepared.geometry().geometric.dot(ray.dir).abs() < 0.2 {
                            continue;
                        }
                        let (want, got) = (prepared.surface(&ray), form.surface(&prepared, &screen, p));
                        let reach = (want.position - ray.origin).length().max(1.0);
                        assert!(
                            (got.position - want.position).length() < 1e-4 * reach,
                            "{projection:?} {item:?} at {p}: {} vs {}",
                            got.position,
                            want.position
                        );
                        assert!((got.uv - want.uv).length() < 1e-3, "{item:?} at {p}: uv {} vs {}", got.uv, want.uv);
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 100, "{checked} points checked");
    }
}
