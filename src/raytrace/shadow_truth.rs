//! Exact hard shadows by shadow rays through the BVH, the truth a shadow
//! method is measured against on the same scene:
//! [`ShadowRays::misclassified`] counts the visible points where a method's
//! lit/shadowed decision differs from a shadow ray's,
//! [`ShadowRays::covered_share`] is the exact share of a pixel's n × n rays
//! that reach the light (what an antialiased shadow term estimates).

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::tracer::occluded_towards;
use super::TraceScene;
use crate::camera::{PixelRays, Ray};
use crate::sampling::{concentric_disc, hash3, stratified};
use crate::scene::{Light, LightKind, Scene};
use crate::shading::{ObjectFrames, SurfacePoint};
use crate::shadows::Receiver;
use crate::visibility::VisibilityBuffer;

/// N·L at or below which a point is not compared: the shadow term hardly
/// shows where the light grazes the surface.
pub const GRAZING: f32 = 0.05;

/// A visible point a shadow decision is asked for.
#[derive(Debug, Clone, Copy)]
pub struct ShadowQuery<'a> {
    /// Its pixel.
    pub pixel: (u32, u32),
    /// The surface at the pixel's centre, as the renderer reconstructs it.
    pub surface: &'a SurfacePoint,
    /// Its object.
    pub object: u32,
    /// The unit normal of its triangle's plane, by the triangle's winding (a
    /// solid's: its outward normal).
    pub plane: Vec3,
    /// N·L there.
    pub cos_theta: f32,
}

impl ShadowQuery<'_> {
    /// The receiver a shadow method is asked about: the object and its plane.
    #[must_use]
    pub fn receiver(&self) -> Receiver {
        Receiver { object: self.object, plane: self.plane }
    }
}

/// Shadow rays cast from points of one scene.
pub struct ShadowRays<'a> {
    scene: &'a Scene,
    trace: TraceScene,
    frames: ObjectFrames,
    rays: PixelRays,
    epsilon: f32,
}

impl<'a> ShadowRays<'a> {
    /// The rays of `scene` (its BVH built here), through its camera.
    #[must_use]
    pub fn new(scene: &'a Scene) -> ShadowRays<'a> {
        ShadowRays {
            scene,
            trace: TraceScene::new(scene),
            frames: ObjectFrames::new(scene),
            rays: scene.camera.pixel_rays(Vec2::new(scene.width as f32, scene.height as f32)),
            epsilon: scene.bounds().map_or(1e-4, |(lo, hi)| (hi - lo).length() * 1e-5),
        }
    }

    /// Whether a ray from surface point `s` (lifted off it along its normal)
    /// reaches `light`.
    #[must_use]
    pub fn reaches(&self, s: &SurfacePoint, light: &Light) -> bool {
        let origin = s.position + s.normal * self.epsilon;
        let (dir, dist) = match light.kind {
            LightKind::Directional { direction } => (-direction, f32::INFINITY),
            LightKind::Point { position } | LightKind::Spot { position, .. } => {
                let d = position - origin;
                (d.normalize(), d.length() * (1.0 - 1e-4))
            }
        };
        !self.trace.occluded(&Ray { origin, dir }, dist)
    }

    /// A decision against shadow rays: per pixel of `vb` (the scene's
    /// visibility buffer) that shows an object, and light whose N·L there is
    /// above [`GRAZING`], `decide(light, query)` (`None`: not compared) read
    /// as lit when ≥ 0.5, against whether a shadow ray reaches the light.
    /// Returns (misclassified, compared).
    pub fn misclassified(
        &self,
        vb: &VisibilityBuffer,
        decide: impl Fn(usize, &ShadowQuery) -> Option<f32> + Sync,
    ) -> (usize, usize) {
        let (w, h) = (vb.width(), vb.height());
        (0..h)
            .into_par_iter()
            .map(|y| {
                let (mut wrong, mut total) = (0, 0);
                for x in 0..w {
                    let item = vb.item(x, y);
                    if item.is_none() {
                        continue;
                    }
                    let ray = self.rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                    let triangle = self.frames.prepare_at(self.scene, vb, x, y, &ray);
                    let (s, plane) = (triangle.surface(&ray), triangle.geometry().geometric);
                    for (i, light) in self.scene.lights.iter().enumerate() {
                        let cos_theta = s.normal.dot(light.incident(s.position).to_light);
                        if cos_theta <= GRAZING {
                            continue;
                        }
                        let query = ShadowQuery { pixel: (x, y), surface: &s, object: item.object, plane, cos_theta };
                        let Some(decided) = decide(i, &query) else { continue };
                        wrong += usize::from(self.reaches(&s, light) != (decided >= 0.5));
                        total += 1;
                    }
                }
                (wrong, total)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
    }

    /// Light `light`'s exact shadow term averaged over `n` × `n` rays through
    /// each of `pixels` (x, y, and the object its centre shows), stratified at
    /// sub-pixel cell centres: the share of the rays' hit points from which a
    /// shadow ray reaches the light. `None` for a pixel whose rays do not all
    /// meet that object and surfaces facing the light (an outline, or a
    /// crease to a face turned away), or whose centre's surface the light
    /// grazes (N·L ≤ 0.1).
    #[must_use]
    pub fn covered_share(&self, light: usize, pixels: &[(u32, u32, u32)], n: u32) -> Vec<Option<f32>> {
        let light = &self.scene.lights[light];
        let faces = |s: &SurfacePoint, least: f32| s.normal.dot(light.incident(s.position).to_light) > least;
        pixels
            .par_iter()
            .map(|&(x, y, object)| {
                let centre = self.hit(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), object)?;
                if !faces(&centre, 0.1) {
                    return None;
                }
                let mut lit = 0u32;
                for j in 0..n {
                    for i in 0..n {
                        let at =
                            Vec2::new(x as f32 + (i as f32 + 0.5) / n as f32, y as f32 + (j as f32 + 0.5) / n as f32);
                        let s = self.hit(at, object)?;
                        if !faces(&s, 0.0) {
                            return None;
                        }
                        lit += u32::from(self.reaches(&s, light));
                    }
                }
                Some(lit as f32 / (n * n) as f32)
            })
            .collect()
    }

    /// Light `light`'s area-light term at the centre of every pixel of `vb`
    /// (row by row): the share of `per_axis` × `per_axis` stratified,
    /// jittered points of its disc (radius `size`, facing the point, as the
    /// reference renderer's) that a shadow ray from the pixel's surface
    /// reaches; 0 where the surface faces away from the light's centre,
    /// `None` where no object is seen. A light without a size is one point.
    #[must_use]
    pub fn area_visibility(&self, vb: &VisibilityBuffer, light: usize, per_axis: u32) -> Vec<Option<f32>> {
        let light = &self.scene.lights[light];
        let (w, h) = (vb.width(), vb.height());
        let m = per_axis.max(1);
        (0..w * h)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if vb.item(x, y).is_none() {
                    return None;
                }
                let ray = self.rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                let s = self.frames.prepare_at(self.scene, vb, x, y, &ray).surface(&ray);
                if s.normal.dot(light.incident(s.position).to_light) <= 0.0 {
                    return Some(0.0);
                }
                let position = match light.kind {
                    LightKind::Point { position } | LightKind::Spot { position, .. } if light.size > 0.0 => position,
                    _ => return Some(f32::from(u8::from(self.reaches(&s, light)))),
                };
                let origin = s.position + s.normal * self.epsilon;
                let (u, v) = (position - s.position).normalize_or(Vec3::Y).any_orthonormal_pair();
                let lit: u32 = (0..m * m)
                    .map(|k| {
                        let d = concentric_disc(stratified(k, m, hash3(x, y, k)));
                        u32::from(!occluded_towards(&self.trace, origin, position + light.size * (u * d.x + v * d.y)))
                    })
                    .sum();
                Some(lit as f32 / (m * m) as f32)
            })
            .collect()
    }

    /// The surface the ray through image point `at` meets, if it is on
    /// `object`.
    fn hit(&self, at: Vec2, object: u32) -> Option<SurfacePoint> {
        let ray = self.rays.ray(at);
        let hit = self.trace.intersect(&ray, f32::INFINITY)?;
        if hit.item.object != object {
            return None;
        }
        Some(match hit.item.primitive() {
            // A solid's point: its tangent plane there.
            Some(_) => {
                ObjectFrames::tangent(self.scene, hit.item, ray.origin + ray.dir * hit.t, hit.normal).surface(&ray)
            }
            None => self.frames.surface(self.scene, hit.item, &ray),
        })
    }
}

/// The pixels along `term`'s shadow boundaries in an image of `vb`'s size
/// (`term` one value per pixel, row by row): those that show an object and
/// whose 3 × 3 neighbourhood holds different values, with that object.
#[must_use]
pub fn boundary_pixels(vb: &VisibilityBuffer, term: &[Vec3]) -> Vec<(u32, u32, u32)> {
    let (w, h) = (vb.width(), vb.height());
    let value = |x: u32, y: u32| term[(y * w + x) as usize].x;
    let mut out = Vec::new();
    for y in 1..h.saturating_sub(1) {
        for x in 1..w.saturating_sub(1) {
            let item = vb.item(x, y);
            let around = (y - 1..=y + 1).flat_map(|v| (x - 1..=x + 1).map(move |u| (u, v)));
            let (lo, hi) =
                around.fold((f32::MAX, f32::MIN), |(lo, hi), (u, v)| (lo.min(value(u, v)), hi.max(value(u, v))));
            if !item.is_none() && lo < hi {
                out.push((x, y, item.object));
            }
        }
    }
    out
}

/// The RMSE of `term` (one value per pixel of a `width`-wide image) against
/// `truth` at `pixels`, over those it has a value for, and how many.
#[must_use]
pub fn rmse_at(term: &[Vec3], width: u32, pixels: &[(u32, u32, u32)], truth: &[Option<f32>]) -> (f64, usize) {
    let (sum, n) = pixels.iter().zip(truth).fold((0.0, 0), |(sum, n), (&(x, y, _), t)| match t {
        Some(t) => {
            let d = f64::from(term[(y * width + x) as usize].x - t);
            (sum + d * d, n + 1)
        }
        None => (sum, n),
    });
    ((sum / n.max(1) as f64).sqrt(), n)
}
