//! Shading passes over the visibility buffer (seed 002 §3): once per visible pixel,
//! the surface is reconstructed from the item id and lit by eq. 1 into a linear
//! float accumulation buffer. Pixels that see nothing get the background colour.

pub mod phong;
pub mod surface;

use glam::Vec2;
use rayon::prelude::*;

use crate::resolve::LinearImage;
use crate::scene::Scene;
use crate::visibility::VisibilityBuffer;

pub use phong::Components;
pub use surface::{ObjectFrames, SurfacePoint};

/// Shades every pixel of `vb` into a new linear image.
#[must_use]
pub fn shade_frame(scene: &Scene, vb: &VisibilityBuffer) -> LinearImage {
    let (w, h) = (vb.width(), vb.height());
    let frames = ObjectFrames::new(scene);
    let rays = scene.camera.pixel_rays(Vec2::new(w as f32, h as f32));
    let mut image = LinearImage::new(w, h);
    image
        .pixels_mut()
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let item = vb.item(x as u32, y as u32);
                *px = if item.is_none() {
                    scene.background
                } else {
                    let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                    let s = frames.surface(scene, item, &ray);
                    phong::shade(&scene.lights, &scene.materials[s.material], &s).total()
                };
            }
        });
    image
}
