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

use rayon::prelude::*;

use crate::image::LinearImage;

/// `sum += weight · image` (same sizes).
pub fn accumulate(sum: &mut LinearImage, image: &LinearImage, weight: f32) {
    sum.pixels_mut().par_iter_mut().zip(image.pixels().par_iter()).for_each(|(a, &p)| *a += p * weight);
}
