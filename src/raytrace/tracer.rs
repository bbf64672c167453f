//! What a ray sees, shaded: the nearest surface along it lit by seed 002's
//! eq. 1 with shadow rays, its mirror and glass bounces followed, translucent
//! surfaces blended over what lies behind them. The traced term of the raster
//! frame (seed 002 §4, [`super::traced`]) and the ray-traced reference
//! ([`super::reference`]) both shade their rays here; how much of each light
//! reaches a point is the one thing they decide differently ([`LightRays`]).

use std::cell::Cell;

use glam::Vec3;

use super::occlusion::Occlusion;
use super::{ray_epsilon, Hit, TraceScene};
use crate::bvh::PACKET;
use crate::camera::Ray;
use crate::scene::{Light, LightKind, Scene};
use crate::shading::phong::{self, Components};
use crate::shading::reflection_map::reflection_map;
use crate::shading::{ObjectFrames, SurfacePoint};

/// Most translucent surfaces one ray passes through before it stops looking.
const MAX_LAYERS: u32 = 64;

/// Most rays one call of [`Tracer::radiance`] or [`Tracer::bounces`] traces
/// (shadow rays aside): each translucent layer a ray passes goes on behind it
/// and bounces too, so stacked glass mirrors branch as (2 × layers)^depth —
/// five of them took 10 s for a 32 × 24 image. Past the budget a ray sees the
/// background. Ordinary scenes stay far below it (four bounces through glass:
/// 31 rays).
const MAX_RAYS: u32 = 1024;

/// How a tracer finds the share of a light that reaches a surface point.
pub trait LightRays: Sync {
    /// The share of `light` seen from `origin` (the surface point `at`, nudged
    /// off its surface) through `trace`; `salt` tells sample patterns apart.
    fn lit(&self, trace: &TraceScene, light: &Light, origin: Vec3, at: Vec3, salt: u32) -> f32;
}

/// One shadow ray to each light: to its centre, or along a directional light.
#[derive(Debug, Clone, Copy, Default)]
pub struct ShadowRay;

impl LightRays for ShadowRay {
    fn lit(&self, trace: &TraceScene, light: &Light, origin: Vec3, _at: Vec3, _salt: u32) -> f32 {
        match light.kind {
            LightKind::Directional { direction } => {
                f32::from(u8::from(!trace.occluded(&Ray { origin, dir: -direction }, f32::INFINITY)))
            }
            LightKind::Point { position } | LightKind::Spot { position, .. } => {
                f32::from(u8::from(!occluded_towards(trace, origin, position)))
            }
        }
    }
}

/// Every light reaches every point (no shadow rays).
#[derive(Debug, Clone, Copy, Default)]
pub struct Unshadowed;

impl LightRays for Unshadowed {
    fn lit(&self, _: &TraceScene, _: &Light, _: Vec3, _: Vec3, _: u32) -> f32 {
        1.0
    }
}

/// Whether anything lies between `origin` and `target` (short of it by a
/// relative hair, so the light's own position does not count).
#[must_use]
pub fn occluded_towards(trace: &TraceScene, origin: Vec3, target: Vec3) -> bool {
    let to = target - origin;
    let dist = to.length();
    trace.occluded(&Ray { origin, dir: to / dist }, dist * (1.0 - 1e-4))
}

/// Where a ray comes from, which decides whether single-sided back faces
/// stop it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Seen {
    /// From the eye (and on behind translucent layers): what the eye's pass
    /// draws, back faces culled.
    FromEye,
    /// A mirror or refracted ray.
    Bounced,
}

/// Shades points hit by rays: eq. 1 with shadow rays (as `L` casts them),
/// plus mirror and glass bounces.
pub struct Tracer<'a, L: LightRays = ShadowRay> {
    scene: &'a Scene,
    trace: &'a TraceScene,
    frames: &'a ObjectFrames,
    lights: L,
    epsilon: f32,
    /// The scene's ambient occlusion, if any.
    occlusion: Option<Occlusion<'a>>,
}

impl<'a, L: LightRays> Tracer<'a, L> {
    /// A tracer over `trace` (built from `scene`), its shadow rays cast by `lights`.
    #[must_use]
    pub fn new(scene: &'a Scene, trace: &'a TraceScene, frames: &'a ObjectFrames, lights: L) -> Self {
        let occlusion = Occlusion::new(scene, trace);
        Tracer { scene, trace, frames, lights, epsilon: ray_epsilon(scene), occlusion }
    }

    /// The same tracer with `rays` ambient-occlusion rays at each point it
    /// shades (the reference's many), where the scene has ambient occlusion.
    #[must_use]
    pub fn with_occlusion_rays(self, rays: u32) -> Self {
        Tracer { occlusion: self.occlusion.map(|o| o.with_rays(rays)), ..self }
    }

    /// Light arriving along `ray` (unit direction), following `depth` bounces.
    /// Translucent surfaces (opacity α < 1, seed 002 §3.4, times an alpha
    /// map's) are blended over what the ray meets behind them: α · their
    /// colour + (1 − α) · the rest. What an alpha test cuts away is passed
    /// through.
    #[must_use]
    pub fn radiance(&self, ray: &Ray, depth: u32) -> Vec3 {
        self.through_layers(ray, Seen::FromEye, depth, MAX_LAYERS, &Cell::new(MAX_RAYS))
    }

    /// [`Tracer::radiance`] with at most `rays` left of the call's budget.
    fn through_layers(&self, ray: &Ray, seen: Seen, depth: u32, layers: u32, rays: &Cell<u32>) -> Vec3 {
        if rays.get() == 0 {
            return self.scene.background_along(ray.dir);
        }
        rays.set(rays.get() - 1);
        self.shade(ray, self.trace.intersect(ray, f32::INFINITY), seen, depth, layers, rays)
    }

    /// [`Tracer::radiance`] of up to [`PACKET`] coherent rays (a pixel's
    /// samples, a block of pixels), their first hits found together
    /// ([`TraceScene::intersect_packet`]); each lane's light is the one
    /// [`Tracer::radiance`] finds for its ray. Also returns the first hits.
    ///
    /// # Panics
    /// If `rays` is empty or longer than [`PACKET`].
    #[must_use]
    pub fn radiance_packet(&self, rays: &[Ray], depth: u32) -> ([Vec3; PACKET], [Option<Hit>; PACKET]) {
        let hits = self.trace.intersect_packet(rays, f32::INFINITY);
        let light = std::array::from_fn(|k| {
            rays.get(k).map_or(Vec3::ZERO, |ray| {
                self.shade(ray, hits[k], Seen::FromEye, depth, MAX_LAYERS, &Cell::new(MAX_RAYS - 1))
            })
        });
        (light, hits)
    }

    /// The light leaving `hit` (the first surface along `ray`, if any) back
    /// along the ray, with what lies behind a translucent surface and the
    /// bounces.
    fn shade(&self, ray: &Ray, hit: Option<Hit>, seen: Seen, depth: u32, layers: u32, rays: &Cell<u32>) -> Vec3 {
        let Some(hit) = hit else { return self.scene.background_along(ray.dir) };
        let mut s = match hit.item.primitive() {
            // A solid: its tangent plane at the hit, which the ray meets there.
            Some(_) => ObjectFrames::tangent(self.scene, hit.item, ray.at(hit.t), hit.normal).surface(ray),
            None => self.frames.prepare(self.scene, hit.item).surface(ray),
        };
        let material = &self.scene.materials[s.material];
        let (uv, duv) = s.coords(material.alpha_set());
        let alpha = material.alpha_at(uv, duv);
        let k = phong::sample_maps(material, &mut s);
        let behind = || {
            let next = Ray { origin: s.position + ray.dir * self.epsilon, dir: ray.dir };
            if layers > 0 {
                self.through_layers(&next, seen, depth, layers - 1, rays)
            } else {
                self.scene.background_along(ray.dir)
            }
        };
        if !material.two_sided && !s.front && (seen == Seen::FromEye || material.translucent()) {
            // A back face the eye's pass culls; a bounced ray meets the
            // inside of a glass it is in, but not a translucent back face,
            // which the polygon pass never draws.
            return behind();
        }
        let mut acc = Components { emission: k.parts().3, ..Default::default() };
        for (i, light) in self.scene.lights.iter().enumerate() {
            if light.only.as_ref().is_some_and(|o| !o.contains(&(hit.item.object as usize))) {
                continue; // selective lighting (seed 002 §3.3)
            }
            let origin = s.position + s.normal * self.epsilon;
            let shadow = if light.casts_shadows() {
                self.lights.lit(self.trace, light, origin, s.position, i as u32)
            } else {
                1.0
            };
            phong::add_light(&mut acc, light, &k, &s, shadow);
        }
        if let Some(occlusion) = &self.occlusion {
            acc.ambient *= occlusion.open(s.position, s.normal);
        }
        let own = acc.total() + reflection_map(self.scene, &s) + self.bounces_within(ray, &s, depth, rays);
        if material.translucent() {
            alpha * own + (1.0 - alpha) * behind()
        } else {
            own
        }
    }

    /// IrayTracing of seed 002 eq. 5 at `s`, seen along `ray`: Kr times the light of
    /// the mirror ray plus Kt times the light of the refracted ray (total internal
    /// reflection sends it back in), each followed `depth` bounces.
    #[must_use]
    pub fn bounces(&self, ray: &Ray, s: &SurfacePoint, depth: u32) -> Vec3 {
        self.bounces_within(ray, s, depth, &Cell::new(MAX_RAYS))
    }

    /// [`Tracer::bounces`] with at most `rays` left of the call's budget.
    fn bounces_within(&self, ray: &Ray, s: &SurfacePoint, depth: u32, rays: &Cell<u32>) -> Vec3 {
        let mut out = Vec3::ZERO;
        for (next, weight) in self.secondary(ray, s, depth).into_iter().flatten() {
            out += weight * self.through_layers(&next, Seen::Bounced, depth - 1, MAX_LAYERS, rays);
        }
        out
    }

    /// [`Tracer::bounces`] at up to [`PACKET`] surfaces seen along coherent
    /// rays (neighbouring pixels of a mirror): their mirror rays are walked
    /// together, then their refracted rays
    /// ([`TraceScene::intersect_packet`]); each lane's light is the one
    /// [`Tracer::bounces`] finds for it.
    ///
    /// # Panics
    /// If `rays` is empty, longer than [`PACKET`], or not as long as
    /// `surfaces`.
    #[must_use]
    pub fn bounces_packet(&self, rays: &[Ray], surfaces: &[SurfacePoint], depth: u32) -> [Vec3; PACKET] {
        assert!((1..=PACKET).contains(&rays.len()), "{} rays in a packet", rays.len());
        assert_eq!(rays.len(), surfaces.len(), "a surface a ray");
        let mut out = [Vec3::ZERO; PACKET];
        let budgets: [Cell<u32>; PACKET] = std::array::from_fn(|_| Cell::new(MAX_RAYS));
        let secondary: [[Option<(Ray, Vec3)>; 2]; PACKET] =
            std::array::from_fn(|k| rays.get(k).map_or([None, None], |ray| self.secondary(ray, &surfaces[k], depth)));
        // The mirror rays first, then the refracted ones, as one lane's
        // bounces spend its budget.
        for which in 0..2 {
            let (mut lanes, mut packet, mut n) = ([(0, Vec3::ZERO); PACKET], [rays[0]; PACKET], 0);
            for (k, (next, weight)) in secondary.iter().enumerate().filter_map(|(k, pair)| Some((k, pair[which]?))) {
                (lanes[n], packet[n], n) = ((k, weight), next, n + 1);
            }
            if n == 0 {
                continue;
            }
            let hits = self.trace.intersect_packet(&packet[..n], f32::INFINITY);
            for (((k, weight), next), hit) in lanes.into_iter().zip(packet).zip(hits).take(n) {
                // As `through_layers`, with the hit found for the packet.
                let budget = &budgets[k];
                let light = if budget.get() == 0 {
                    self.scene.background_along(next.dir)
                } else {
                    budget.set(budget.get() - 1);
                    self.shade(&next, hit, Seen::Bounced, depth - 1, MAX_LAYERS, budget)
                };
                out[k] += weight * light;
            }
        }
        out
    }

    /// The rays IrayTracing follows from `s` (seen along `ray`) with their
    /// weights: the mirror ray (Kr) and the refracted one (Kt; total
    /// internal reflection sends it back in). None when `depth` is 0 or the
    /// material neither reflects nor refracts.
    fn secondary(&self, ray: &Ray, s: &SurfacePoint, depth: u32) -> [Option<(Ray, Vec3)>; 2] {
        let m = &self.scene.materials[s.material];
        if depth == 0 || !m.traces() {
            return [None, None];
        }
        let d = ray.dir;
        let mirror = (m.kr.max_element() > 0.0).then(|| {
            let n = facing(d, s.normal);
            (Ray { origin: s.position + n * self.epsilon, dir: reflect(d, n) }, m.kr)
        });
        let refracted = (m.kt.max_element() > 0.0).then(|| {
            // Entering when the ray meets the front (outward) side of the surface.
            let eta = if s.front { 1.0 / m.ior } else { m.ior };
            let (dir, sign) = match refract(d, s.normal, eta) {
                Some(t) => (t, -1.0),
                None => (reflect(d, s.normal), 1.0),
            };
            (Ray { origin: s.position + s.normal * (sign * self.epsilon), dir }, m.kt)
        });
        [mirror, refracted]
    }
}

/// The shading normal `n` of a surface seen along `d`, tilted (when it must)
/// until it faces the ray by at least 1°: near a smooth mesh's silhouette the
/// interpolated normal can face away from the eye, and the mirror direction
/// about it would run into the surface — the outline's pixels would mirror the
/// object's own inside, dark.
#[must_use]
pub fn facing(d: Vec3, n: Vec3) -> Vec3 {
    const MIN_COS: f32 = 0.017; // cos 89°
    let d = d.normalize_or_zero();
    let cos = -d.dot(n);
    if cos >= MIN_COS {
        return n;
    }
    (n + (cos - MIN_COS) * d).normalize_or(n)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_normal_facing_away_is_tilted_until_the_mirror_ray_leaves_the_surface() {
        let d = Vec3::new(1.0, -0.02, 0.0).normalize(); // grazing, slightly down
        let away = Vec3::new(0.2, 0.98, 0.0).normalize(); // interpolated, facing away (d·n > 0)
        assert!(d.dot(away) > 0.0);
        let n = facing(d, away);
        assert!((-d.dot(n) - 0.017).abs() < 1e-3, "faces the ray by 1°: {}", -d.dot(n));
        assert!(reflect(d, n).dot(n) > 0.0, "the mirror ray leaves on the eye's side");
        assert!(reflect(d, away).dot(away) < 0.0, "about the untilted normal it would enter the surface");
        let towards = Vec3::new(-0.6, 0.8, 0.0);
        assert_eq!(facing(d, towards), towards, "a normal that faces the ray is kept");
    }

    /// Eight neighbours' bounces walked together equal each one's bounces
    /// alone, bit for bit: a mirror floor, a glass sphere (mirror and
    /// refracted rays, total internal reflection), a diffuse box (no
    /// secondary ray), packets of 1 to 8 rays, at depths 0 to 3.
    #[test]
    fn bounces_in_packets_equal_bounces_one_at_a_time() {
        use crate::scene::mesh::shapes;
        use crate::scene::{Light, Material, Object};
        use glam::{Affine3A, Vec2};
        use std::sync::Arc;
        let camera = crate::camera::Camera {
            eye: Vec3::new(0.3, 2.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            near: 0.1,
            far: 40.0,
            projection: crate::camera::Projection::Perspective { fov_y_deg: 50.0 },
            shift: Vec2::ZERO,
        };
        let mut scene = Scene::new(64, 48, camera);
        let mirror = Material { kr: Vec3::splat(0.8), ..Material::default() };
        let glass = Material { kr: Vec3::splat(0.1), kt: Vec3::splat(0.9), ior: 1.5, ..Material::default() };
        scene.materials = vec![mirror, glass, Material::default()];
        let floor = Affine3A::from_translation(Vec3::new(0.0, -1.0, 0.0)) * Affine3A::from_scale(Vec3::splat(8.0));
        scene.objects.push(Object::mesh("floor", Arc::new(shapes::plane()), floor, 0));
        scene.objects.push(Object::mesh("ball", Arc::new(shapes::sphere(24)), Affine3A::IDENTITY, 1));
        let at = Affine3A::from_translation(Vec3::new(1.8, -0.5, -1.0)) * Affine3A::from_scale(Vec3::splat(0.5));
        scene.objects.push(Object::mesh("box", Arc::new(shapes::cube()), at, 2));
        let lamp = LightKind::Point { position: Vec3::new(2.0, 5.0, 3.0) };
        scene.lights = vec![Light { kind: lamp, ambient: 0.1, ..Light::default() }];
        let trace = TraceScene::new(&scene);
        let frames = ObjectFrames::new(&scene);
        let tracer = Tracer::new(&scene, &trace, &frames, ShadowRay);
        let pixel_rays = scene.camera.pixel_rays(Vec2::new(64.0, 48.0));
        let (mut packets, mut traced) = (0, 0);
        for y in 0..48 {
            for x0 in (0..64).step_by(PACKET) {
                let n = 1 + (x0 / PACKET + y) % PACKET;
                let (mut rays, mut surfaces) = (Vec::new(), Vec::new());
                for x in x0..x0 + n {
                    let ray = pixel_rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                    let Some(hit) = trace.intersect(&ray, f32::INFINITY) else { continue };
                    surfaces.push(frames.prepare(&scene, hit.item).surface(&ray));
                    rays.push(ray);
                }
                if rays.is_empty() {
                    continue;
                }
                for depth in 0..4 {
                    let together = tracer.bounces_packet(&rays, &surfaces, depth);
                    for k in 0..rays.len() {
                        let alone = tracer.bounces(&rays[k], &surfaces[k], depth);
                        assert_eq!(together[k].to_array().map(f32::to_bits), alone.to_array().map(f32::to_bits));
                        traced += usize::from(depth > 0 && alone != Vec3::ZERO);
                    }
                    assert!(together[rays.len()..].iter().all(|&c| c == Vec3::ZERO), "lanes past the rays stay dark");
                }
                packets += 1;
            }
        }
        assert!(packets > 100 && traced > 1000, "{packets} packets, {traced} lanes with light bounced");
    }

    /// Five nested mirror-glass translucent spheres: each layer a ray
    /// passes goes on behind it and bounces, so four bounces take more than
    /// 50 times the budget; one call stops at it, with a finite colour.
    #[test]
    fn stacked_translucent_mirror_glass_stays_within_the_ray_budget() {
        use crate::scene::mesh::shapes;
        use crate::scene::{Material, Object};
        use std::sync::Arc;
        let camera = crate::camera::Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            near: 0.1,
            far: 20.0,
            projection: crate::camera::Projection::Perspective { fov_y_deg: 40.0 },
            shift: glam::Vec2::ZERO,
        };
        let mut scene = Scene::new(32, 24, camera);
        let glass = Material { kr: Vec3::ONE, kt: Vec3::ONE, opacity: 0.5, two_sided: true, ..Material::default() };
        scene.materials = vec![glass];
        let sphere = Arc::new(shapes::sphere(8));
        for k in 0..5 {
            let size = glam::Affine3A::from_scale(Vec3::splat(1.0 - 0.1 * k as f32));
            scene.objects.push(Object::mesh(format!("s{k}"), sphere.clone(), size, 0));
        }
        let trace = TraceScene::new(&scene);
        let frames = ObjectFrames::new(&scene);
        let tracer = Tracer::new(&scene, &trace, &frames, Unshadowed);
        let ray = Ray { origin: Vec3::new(0.1, 0.2, 5.0), dir: Vec3::NEG_Z };
        let unbounded = Cell::new(u32::MAX);
        let _ = tracer.through_layers(&ray, Seen::FromEye, 4, MAX_LAYERS, &unbounded);
        let needed = u32::MAX - unbounded.get();
        assert!(needed > 50 * MAX_RAYS, "the stack needs {needed} rays");
        let budget = Cell::new(MAX_RAYS);
        let c = tracer.through_layers(&ray, Seen::FromEye, 4, MAX_LAYERS, &budget);
        assert!(budget.get() == 0 && c.is_finite(), "{c}, {} rays left", budget.get());
    }
}
