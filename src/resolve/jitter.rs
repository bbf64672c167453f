//! Antialiasing by jittered sub-pixel passes: the accumulation buffer of seed
//! 002 §4 (Kawabata, Watanabe & Sakai).
//!
//! The paper antialiases its traced reflections by rendering several item
//! buffers, each with the image shifted by a fraction of a pixel, tracing each
//! and averaging (Fig. 8): every pass samples a different point of each pixel,
//! so small and needle-like polygons are sampled in proportion to their area.
//! kage jitters the whole frame — visibility, shading passes and traced term —
//! so the average is the classic accumulation-buffer antialiasing of
//! everything at once. The offsets are the scene's
//! ([`crate::scene::Antialias::offsets`]).

use glam::Vec2;
use rayon::prelude::*;

use crate::camera::Camera;
use crate::image::LinearImage;

/// `camera` with its image shifted by `offset` pixels (y down) on a `width` ×
/// `height` frame: a pass whose pixel centres sample the points `offset` from
/// the unshifted pixels' centres.
#[must_use]
pub fn shifted(camera: &Camera, offset: Vec2, (width, height): (u32, u32)) -> Camera {
    let pixel = 2.0 / Vec2::new(width as f32, height as f32);
    // Pixel offsets (y down) to NDC (y up).
    Camera { shift: camera.shift + Vec2::new(offset.x, -offset.y) * pixel, ..*camera }
}

/// `sum += weight · image` (same sizes).
pub fn accumulate(sum: &mut LinearImage, image: &LinearImage, weight: f32) {
    sum.pixels_mut().par_iter_mut().zip(image.pixels().par_iter()).for_each(|(a, &p)| *a += p * weight);
}
