//! The reflection-map pass of seed 002 eq. 4, run once per frame:
//! Ie(x, y) = Km · Mape(R), the environment image looked up along the view's
//! mirror direction R = 2(N·V)N − V at each surface whose material has a Km — a
//! reflection with no ray traced, which is all the paper's hardware could do.
//! The same pass writes the environment as the background where it is visible.
//! Each pixel's lookup is filtered over the directions its neighbours see (the
//! map's mip level matching that spread): a curved mirror seen small shows the
//! map's average there, not moiré.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::{Component, ObjectFrames, SurfacePoint, Target};
use crate::scene::{Material, Scene};
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
    for t in targets {
        let (reflection, background) = (t.parts.contains(Component::Reflection), t.parts.contains(Component::Emission));
        if !(reflection || background && env.visible) {
            continue;
        }
        let rows = t.image.pixels_mut().par_chunks_mut(w).zip(vb.items().par_chunks(w));
        rows.enumerate().for_each(|(y, (out, items))| {
            for (x, (px, &item)) in out.iter_mut().zip(items).enumerate() {
                let (x, y) = (x as u32, y as u32);
                let ray = |x: u32, y: u32| rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                if item.is_none() {
                    if background && env.visible {
                        let dir = |x: u32, y: u32| ray(x, y).dir.normalize();
                        *px += env.radiance_over(dir(x, y), dir(x + 1, y), dir(x, y + 1));
                    }
                    continue;
                }
                if reflection && reflecting[item.material(scene)] {
                    let surface = |x: u32, y: u32| {
                        let mut s = frames.surface_at(scene, vb, x, y, &ray(x, y));
                        super::normal_map::apply(&scene.materials[s.material], &mut s);
                        s
                    };
                    let s = surface(x, y);
                    let mirror = |x: u32, y: u32| mirror_direction(&surface(x, y));
                    let r = mirror_direction(&s);
                    // The spread of mirror directions to the pixels beside and
                    // below, taken from the other side where they show another object.
                    let beside = |dx: i32, dy: i32| {
                        let at = |k: i32| (x as i32 + k * dx, y as i32 + k * dy);
                        [1, -1].into_iter().map(at).find(|&(nx, ny)| {
                            nx >= 0
                                && ny >= 0
                                && (nx as u32) < vb.width()
                                && (ny as u32) < vb.height()
                                && vb.item(nx as u32, ny as u32).object == item.object
                        })
                    };
                    let spread = |n: Option<(i32, i32)>| n.map_or(r, |(nx, ny)| mirror(nx as u32, ny as u32));
                    let km = mirrored_share(&scene.materials[s.material], &s);
                    *px += km * env.radiance_over(r, spread(beside(1, 0)), spread(beside(0, 1)));
                }
            }
        });
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
