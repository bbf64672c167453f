//! Each light's shadow term at the surface every pixel shows, as an image of
//! its own (1 lit, 0 in shadow; an area light's is the mean over its
//! samples): the picture to judge a shadow method by, apart from the
//! materials and the light's falloff. Where a surface faces away from the
//! light the term is 0 (the light cannot reach it, whatever the maps say);
//! where no object is seen it is 1.

use glam::Vec3;
use rayon::prelude::*;

use super::passes::{frame_lights_within, ShadowFrame};
use crate::image::LinearImage;
use crate::scene::Scene;
use crate::shadows::MapPool;
use crate::visibility::VisibilityBuffer;

/// Writes every light's shadow term at the pixels of `vb` into `images` (one
/// grey image per light of `scene`, in the scene's order, resized to the
/// pixels `vb` holds),
/// with the terms this frame's shading used (kept in `pool`, or rendered
/// again for lights whose maps the pool does not keep).
pub fn shadow_term_images(scene: &Scene, vb: &VisibilityBuffer, pool: &mut MapPool, images: &mut Vec<LinearImage>) {
    let held = vb.rect();
    let (w, h) = (held.width(), held.height());
    images.resize_with(scene.lights.len(), LinearImage::default);
    let bounds = scene.caster_bounds().unwrap_or_default();
    let mut frame = ShadowFrame::within(scene, vb, bounds);
    for (image, light) in images.iter_mut().zip(frame_lights_within(scene, bounds)) {
        image.resize(w, h);
        image.pixels_mut().fill(Vec3::ZERO);
        let weight = 1.0 / light.samples.len() as f32;
        for sample in &light.samples {
            pool.with_term(scene, sample, bounds, |term| {
                frame.ready(&light, term);
                let surfaces = frame.surfaces();
                let rows = image.pixels_mut().par_chunks_mut(w.max(1) as usize).enumerate();
                rows.for_each_init(Vec::new, |seen, (y, row)| {
                    let y = y + held.y0 as usize;
                    surfaces.rows(y..y + 1, seen);
                    for (px, surface) in row.iter_mut().zip(seen.iter()) {
                        let lit = match surface {
                            None => 1.0,
                            Some(s) => {
                                let cos_theta = s.normal.dot(light.light.incident(s.position).to_light);
                                if cos_theta > 0.0 {
                                    term.lit(s.position, cos_theta, &s.receiver)
                                } else {
                                    0.0
                                }
                            }
                        };
                        *px += Vec3::splat(lit * weight);
                    }
                });
            });
        }
    }
}
