//! The reference renderer: the same scene and the same shading model as the raster
//! pipeline (seed 002 eq. 1), computed by rays — the truth every raster technique
//! is measured against. It shades through the same [`Tracer`] as the traced term
//! and adds only what an oracle needs: primary visibility by n × n stratified,
//! jittered rays per pixel (an antialiased reference), and area-light soft shadows
//! by m × m stratified samples over each light's extent (a disc of radius `size`
//! facing the point). Textures are read at their finest level: the reference
//! filters them by supersampling.
//!
//! It reads the scene exactly as the raster pipeline does, or it would not be
//! an oracle: a light whose shadow method is `none` is shadowed by neither
//! ([`crate::scene::Light::casts_shadows`]); a single-sided back face, which
//! the eye's pass culls, lets the eye's rays through (mirror and refracted rays
//! still meet the inside of the glass they are in); fog is laid on by the distance to
//! the first surface a ray meets, as the fog pass does. A test holds every
//! example scene, the demo and kage-framed models to their reference.
//!
//! With n = m = 1, shadows off and no area lights, every pixel whose primary hit
//! agrees with the visibility buffer gets the rasterizer's colour (a test holds it).

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::tracer::{occluded_towards, LightRays, ShadowRay, Tracer, Unshadowed};
use super::TraceScene;
use crate::bvh::PACKET;
use crate::camera::{PixelRays, Ray};
use crate::image::LinearImage;
use crate::sampling::{concentric_disc, hash3, stratified};
use crate::scene::{Light, LightKind, Scene};
use crate::shading::ObjectFrames;

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
    /// Ambient-occlusion rays at each point shaded, where the scene has
    /// ambient occlusion ([`crate::raytrace::occlusion`]): its truth.
    pub occlusion_rays: u32,
}

impl ReferenceOptions {
    /// One ray through each pixel centre, no shadows, no bounces: what the
    /// raster frame's visibility and unshadowed shading equal pixel for pixel.
    pub const CENTRES: ReferenceOptions =
        ReferenceOptions { pixel_samples: 1, light_samples: 1, shadows: false, max_depth: 0, occlusion_rays: 64 };
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions { pixel_samples: 4, light_samples: 4, shadows: true, max_depth: 4, occlusion_rays: 64 }
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
    let run = Run { scene, opts, progress, stop };
    let ao = opts.occlusion_rays;
    if opts.shadows {
        let lights = AreaLights { per_axis: opts.light_samples.max(1) };
        run.with(Tracer::new(scene, &trace, &frames, lights).with_occlusion_rays(ao))
    } else {
        run.with(Tracer::new(scene, &trace, &frames, Unshadowed).with_occlusion_rays(ao))
    }
}

/// One reference render's settings, before its tracer is chosen.
struct Run<'a> {
    scene: &'a Scene,
    opts: &'a ReferenceOptions,
    progress: &'a (dyn Fn(u32) + Sync),
    stop: &'a AtomicBool,
}

impl Run<'_> {
    /// Every row not stopped, traced by `tracer`.
    fn with<L: LightRays>(&self, tracer: Tracer<L>) -> (LinearImage, u32) {
        let (w, h) = (self.scene.width, self.scene.height);
        let rays = self.scene.camera.pixel_rays(Vec2::new(w as f32, h as f32));
        let done = AtomicU32::new(0);
        let mut image = LinearImage::new(w, h);
        image.pixels_mut().par_chunks_mut(w as usize).enumerate().for_each(|(y, row)| {
            if self.stop.load(Ordering::Relaxed) {
                return;
            }
            for (x, px) in row.iter_mut().enumerate() {
                *px = self.pixel(&tracer, &rays, (x as u32, y as u32));
            }
            (self.progress)(done.fetch_add(1, Ordering::Relaxed) + 1);
        });
        (image, done.into_inner())
    }

    /// Pixel (x, y): the mean of n × n stratified, jittered rays through it,
    /// each fogged by the distance to the first surface it meets (seed 002
    /// §3.5's `lerp(colour, fog, f(d))`, as the raster's fog pass; a ray that
    /// meets nothing keeps the background).
    fn pixel<L: LightRays>(&self, tracer: &Tracer<L>, rays: &PixelRays, (x, y): (u32, u32)) -> Vec3 {
        let n = self.opts.pixel_samples.max(1);
        let mut sum = Vec3::ZERO;
        let samples: Vec<Ray> =
            (0..n * n).map(|k| rays.ray(Vec2::new(x as f32, y as f32) + stratified(k, n, hash3(x, y, k)))).collect();
        // A pixel's samples are coherent: their first hits are found together.
        for packet in samples.chunks(PACKET) {
            let (light, hits) = tracer.radiance_packet(packet, self.opts.max_depth);
            for ((ray, seen), hit) in packet.iter().zip(light).zip(hits) {
                sum += match (&self.scene.fog, hit) {
                    (Some(fog), Some(hit)) => seen.lerp(fog.color, fog.amount_at(&self.scene.camera, ray.at(hit.t))),
                    _ => seen,
                };
            }
        }
        sum / (n * n) as f32
    }
}

/// Area lights seen by m × m stratified shadow rays over each sized light's
/// disc (facing the point); other lights by one ray.
struct AreaLights {
    per_axis: u32,
}

impl LightRays for AreaLights {
    fn lit(&self, trace: &TraceScene, light: &Light, origin: Vec3, at: Vec3, salt: u32) -> f32 {
        let position = match light.kind {
            LightKind::Point { position } | LightKind::Spot { position, .. } if light.size > 0.0 => position,
            _ => return ShadowRay.lit(trace, light, origin, at, salt),
        };
        let m = self.per_axis;
        let (u, v) = (position - at).normalize_or(Vec3::Y).any_orthonormal_pair();
        let lit: u32 = (0..m * m)
            .map(|k| {
                let d = concentric_disc(stratified(k, m, hash3(salt, k, at.x.to_bits())));
                let target = if m == 1 { position } else { position + light.size * (u * d.x + v * d.y) };
                u32::from(!occluded_towards(trace, origin, target))
            })
            .sum();
        lit as f32 / (m * m) as f32
    }
}
