//! Each light's shadow term at the surface every pixel shows, as an image of
//! its own (1 lit, 0 in shadow; an area light's is the mean over its
//! samples): the picture to judge a shadow method by, apart from the
//! materials and the light's falloff. Where a surface faces away from the
//! light the term is 0 (the light cannot reach it, whatever the maps say);
//! where no object is seen it is 1.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::passes::{frame_lights, light_view};
use super::surface::{screen_surfaces, ObjectFrames};
use crate::image::LinearImage;
use crate::scene::Scene;
use crate::shadows::{MapPool, Receiver};
use crate::visibility::VisibilityBuffer;

/// Writes every light's shadow term at the pixels of `vb` into `images` (one
/// grey image per light of `scene`, in the scene's order, resized to `vb`),
/// with the terms this frame's shading used (kept in `pool`, or rendered
/// again for lights whose maps the pool does not keep).
pub fn shadow_term_images(scene: &Scene, vb: &VisibilityBuffer, pool: &mut MapPool, images: &mut Vec<LinearImage>) {
    let (w, h) = (vb.width(), vb.height());
    images.resize_with(scene.lights.len(), LinearImage::default);
    let shaded = shaded_surfaces(scene, vb);
    let mut screen = None;
    let bounds = scene.caster_bounds().unwrap_or_default();
    for (image, light) in images.iter_mut().zip(frame_lights(scene)) {
        image.resize(w, h);
        image.pixels_mut().fill(Vec3::ZERO);
        let (weight, view) = (1.0 / light.samples.len() as f32, light_view(scene, &light));
        for sample in &light.samples {
            pool.with_term(scene, sample, bounds, |term| {
                term.set_view(view);
                if term.per_pixel() {
                    term.prepare(screen.get_or_insert_with(|| screen_surfaces(scene, vb)));
                }
                image.pixels_mut().par_iter_mut().zip(&shaded).for_each(|(px, surface)| {
                    let lit = match surface {
                        None => 1.0,
                        Some((p, n, receiver)) => {
                            let cos_theta = n.dot(light.light.incident(*p).to_light);
                            if cos_theta > 0.0 {
                                term.lit(*p, cos_theta, receiver)
                            } else {
                                0.0
                            }
                        }
                    };
                    *px += Vec3::splat(lit * weight);
                });
            });
        }
    }
}

/// The position and shading normal of the surface each pixel of `vb` shows
/// (at the pixel's centre), and that surface as a shadow's receiver (its
/// object and plane), row by row; `None` where no object is seen.
fn shaded_surfaces(scene: &Scene, vb: &VisibilityBuffer) -> Vec<Option<(Vec3, Vec3, Receiver)>> {
    let w = vb.width() as usize;
    let frames = ObjectFrames::new(scene);
    let rays = scene.camera.pixel_rays(Vec2::new(vb.width() as f32, vb.height() as f32));
    let mut out = vec![None; w * vb.height() as usize];
    out.par_chunks_mut(w.max(1)).enumerate().for_each(|(y, row)| {
        for (x, slot) in row.iter_mut().enumerate() {
            let (x, y) = (x as u32, y as u32);
            let item = vb.item(x, y);
            if item.is_none() {
                continue;
            }
            let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let triangle = frames.prepare_at(scene, vb, x, y, &ray);
            let s = triangle.surface(&ray);
            let receiver = Receiver { object: item.object, plane: triangle.geometry().geometric };
            *slot = Some((s.position, s.normal, receiver));
        }
    });
    out
}
