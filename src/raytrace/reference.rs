//! The reference renderer: the same scene and the same shading model as the raster
//! pipeline (seed 002 eq. 1), computed by rays. Primary visibility by tracing
//! n × n stratified, jittered rays per pixel (an antialiased reference), hard
//! shadows by shadow rays, area-light soft shadows by m × m stratified samples over
//! each light's extent (a disc of radius `size` facing the point). Textures are
//! read at their finest level: the reference filters them by supersampling.
//!
//! With n = m = 1, shadows off and no area lights, every pixel whose primary hit
//! agrees with the visibility buffer gets the rasterizer's colour (a test holds it).

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::TraceScene;
use crate::camera::Ray;
use crate::image::LinearImage;
use crate::sampling::{concentric_disc, hash3, stratified};
use crate::scene::{Light, LightKind, Scene};
use crate::shading::phong::{self, Coefficients, Components};
use crate::shading::reflection_map::reflection_map;
use crate::shading::{ObjectFrames, SurfacePoint};

/// Most translucent surfaces one ray passes through before it stops looking.
const MAX_LAYERS: u32 = 64;

/// How the reference is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReferenceOptions {
    /// Primary rays per pixel along each axis (n × n per pixel; 1 = the centre).
    pub pixel_samples: u32,
    /// Shadow rays per light along each axis for lights with a size (m × m).
    pub light_samples: u32,
    /// Trace shadow rays (off: every light reaches every point, like the raster
    /// pipeline before shadows).
    pub shadows: bool,
    /// Reflection/refraction bounces followed from a surface (0: none).
    pub max_depth: u32,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions { pixel_samples: 4, light_samples: 4, shadows: true, max_depth: 4 }
    }
}

/// Renders `scene` by rays; `progress` is called with each finished row count.
pub fn render_reference(scene: &Scene, opts: &ReferenceOptions, progress: &(dyn Fn(u32) + Sync)) -> LinearImage {
    render_reference_until(scene, opts, progress, &AtomicBool::new(false)).0
}

/// As [`render_reference`], but rows not yet started when `stop` becomes true are
/// left black: the rows already traced survive an interruption. Returns the image
/// and how many rows were finished.
pub fn render_reference_until(
    scene: &Scene,
    opts: &ReferenceOptions,
    progress: &(dyn Fn(u32) + Sync),
    stop: &AtomicBool,
) -> (LinearImage, u32) {
    let trace = TraceScene::new(scene);
    let frames = ObjectFrames::new(scene);
    let (w, h) = (scene.width, scene.height);
    let rays = scene.camera.pixel_rays(Vec2::new(w as f32, h as f32));
    let cx = Tracer::new(scene, &trace, &frames, *opts);
    let done = AtomicU32::new(0);
    let mut image = LinearImage::new(w, h);
    image.pixels_mut().par_chunks_mut(w as usize).enumerate().for_each(|(y, row)| {
        if stop.load(Ordering::Relaxed) {
            return;
        }
        for (x, px) in row.iter_mut().enumerate() {
            *px = cx.pixel(&rays, x as u32, y as u32);
        }
        progress(done.fetch_add(1, Ordering::Relaxed) + 1);
    });
    (image, done.into_inner())
}

/// Shades points hit by rays: eq. 1 with shadow rays, plus mirror and glass
/// bounces. Shared by the reference renderer and the item-buffer pass.
pub struct Tracer<'a> {
    scene: &'a Scene,
    trace: &'a TraceScene,
    frames: &'a ObjectFrames,
    opts: ReferenceOptions,
    epsilon: f32,
}

impl<'a> Tracer<'a> {
    /// A tracer over `trace` (built from `scene`).
    #[must_use]
    pub fn new(scene: &'a Scene, trace: &'a TraceScene, frames: &'a ObjectFrames, opts: ReferenceOptions) -> Self {
        let epsilon = scene.bounds().map_or(1e-4, |(lo, hi)| (hi - lo).length() * 1e-5);
        Tracer { scene, trace, frames, opts, epsilon }
    }

    fn pixel(&self, rays: &crate::camera::PixelRays, x: u32, y: u32) -> Vec3 {
        let n = self.opts.pixel_samples.max(1);
        let mut sum = Vec3::ZERO;
        for k in 0..n * n {
            let offset = stratified(k, n, hash3(x, y, k));
            sum += self.radiance(&rays.ray(Vec2::new(x as f32, y as f32) + offset), self.opts.max_depth);
        }
        sum / (n * n) as f32
    }

    /// Light arriving along `ray` (unit direction), following `depth` bounces.
    /// Translucent surfaces (opacity α < 1, seed 002 §3.4) are blended over what
    /// the ray meets behind them: α · their colour + (1 − α) · the rest.
    #[must_use]
    pub fn radiance(&self, ray: &Ray, depth: u32) -> Vec3 {
        self.through_layers(ray, depth, MAX_LAYERS)
    }

    fn through_layers(&self, ray: &Ray, depth: u32, layers: u32) -> Vec3 {
        let Some(hit) = self.trace.intersect(ray, f32::INFINITY) else { return self.scene.background_along(ray.dir) };
        let s = match hit.item.primitive() {
            // A solid: its tangent plane at the hit, which the ray meets there.
            Some(_) => ObjectFrames::tangent(self.scene, hit.item, ray.at(hit.t), hit.normal).surface(ray),
            None => self.frames.prepare(self.scene, hit.item).surface(ray),
        };
        let material = &self.scene.materials[s.material];
        let behind = || {
            let next = Ray { origin: s.position + ray.dir * self.epsilon, dir: ray.dir };
            if layers > 0 {
                self.through_layers(&next, depth, layers - 1)
            } else {
                self.scene.background_along(ray.dir)
            }
        };
        if material.translucent() && !material.two_sided && !s.front {
            return behind(); // a culled back face, as the polygon pass draws it
        }
        let k = Coefficients::at(material, &s);
        let mut acc = Components { emission: k.parts().3, ..Default::default() };
        for (i, light) in self.scene.lights.iter().enumerate() {
            if light.only.as_ref().is_some_and(|o| !o.contains(&(hit.item.object as usize))) {
                continue; // selective lighting (seed 002 §3.3)
            }
            let shadow = if self.opts.shadows { self.visibility(light, &s, i as u32) } else { 1.0 };
            phong::add_light(&mut acc, light, &k, &s, shadow);
        }
        let own = acc.total() + reflection_map(self.scene, &s) + self.bounces(ray, &s, depth);
        if material.translucent() {
            material.opacity * own + (1.0 - material.opacity) * behind()
        } else {
            own
        }
    }

    /// IrayTracing of seed 002 eq. 5 at `s`, seen along `ray`: Kr times the light of
    /// the mirror ray plus Kt times the light of the refracted ray (total internal
    /// reflection sends it back in), each followed `depth` bounces.
    #[must_use]
    pub fn bounces(&self, ray: &Ray, s: &SurfacePoint, depth: u32) -> Vec3 {
        let m = &self.scene.materials[s.material];
        if depth == 0 || !m.traces() {
            return Vec3::ZERO;
        }
        let d = ray.dir;
        let mut out = Vec3::ZERO;
        if m.kr.max_element() > 0.0 {
            let r = reflect(d, s.normal);
            out += m.kr * self.radiance(&Ray { origin: s.position + s.normal * self.epsilon, dir: r }, depth - 1);
        }
        if m.kt.max_element() > 0.0 {
            // Entering when the ray meets the front (outward) side of the surface.
            let eta = if s.front { 1.0 / m.ior } else { m.ior };
            let (dir, sign) = match refract(d, s.normal, eta) {
                Some(t) => (t, -1.0),
                None => (reflect(d, s.normal), 1.0),
            };
            let origin = s.position + s.normal * (sign * self.epsilon);
            out += m.kt * self.radiance(&Ray { origin, dir }, depth - 1);
        }
        out
    }

    /// Fraction of the light's samples visible from the surface point.
    fn visibility(&self, light: &Light, s: &SurfacePoint, salt: u32) -> f32 {
        let origin = s.position + s.normal * self.epsilon;
        let position = match light.kind {
            LightKind::Directional { direction } => {
                let ray = Ray { origin, dir: -direction };
                return if self.trace.occluded(&ray, f32::INFINITY) { 0.0 } else { 1.0 };
            }
            LightKind::Point { position } | LightKind::Spot { position, .. } => position,
        };
        let m = if light.size > 0.0 { self.opts.light_samples.max(1) } else { 1 };
        let axis = (position - s.position).normalize_or(Vec3::Y);
        let (u, v) = axis.any_orthonormal_pair();
        let mut lit = 0;
        for k in 0..m * m {
            let d = concentric_disc(stratified(k, m, hash3(salt, k, s.position.x.to_bits())));
            let target = if m == 1 { position } else { position + light.size * (u * d.x + v * d.y) };
            let to = target - origin;
            let dist = to.length();
            let ray = Ray { origin, dir: to / dist };
            lit += u32::from(!self.trace.occluded(&ray, dist * (1.0 - 1e-4)));
        }
        lit as f32 / (m * m) as f32
    }
}

/// The mirror direction of unit `d` about unit normal `n`.
#[must_use]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Snell refraction of unit `d` through a surface with unit normal `n` facing the
/// incoming ray, `eta` = n_from / n_to; `None` past the critical angle (total
/// internal reflection).
#[must_use]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}
