//! Shading passes over the visibility buffer (seed 002 §3): once per visible pixel,
//! the surface is reconstructed from the item id and lit by eq. 1 into a linear
//! float accumulation buffer. Pixels that see nothing get the background colour.

pub mod lanes;
pub mod phong;
pub mod surface;

use glam::Vec2;
use rayon::prelude::*;

use crate::resolve::LinearImage;
use crate::scene::Scene;
use crate::visibility::VisibilityBuffer;

pub use phong::Components;
pub use surface::{ObjectFrames, PreparedTriangle, SurfacePoint};

use phong::Coefficients;

/// Shades every pixel of `vb` into a new linear image.
#[must_use]
pub fn shade_frame(scene: &Scene, vb: &VisibilityBuffer) -> LinearImage {
    let mut image = LinearImage::new(vb.width(), vb.height());
    shade_into(scene, vb, &mut image);
    image
}

/// Shades every pixel of `vb` into `image` (same size), rows in parallel, eight
/// pixels at a time ([`lanes`]).
pub fn shade_into(scene: &Scene, vb: &VisibilityBuffer, image: &mut LinearImage) {
    assert_eq!(
        (image.width(), image.height()),
        (vb.width(), vb.height()),
        "image and buffer sizes"
    );
    let w = vb.width() as usize;
    let frames = ObjectFrames::new(scene);
    let rays = scene
        .camera
        .pixel_rays(Vec2::new(w as f32, vb.height() as f32));
    let constants: Vec<Option<Coefficients>> =
        scene.materials.iter().map(Coefficients::constant).collect();
    let sample = |s: &SurfacePoint| Coefficients::at(&scene.materials[s.material], s);
    let lighting = lanes::Lighting::new(&scene.lights);
    let rows = image
        .pixels_mut()
        .par_chunks_mut(w)
        .zip(vb.items().par_chunks(w));
    rows.enumerate().for_each(|(y, (out, items))| {
        let mut prepared: Option<PreparedTriangle> = None;
        let mut block = lanes::Block::default();
        for (c, (out, items)) in out
            .chunks_mut(lanes::LANES)
            .zip(items.chunks(lanes::LANES))
            .enumerate()
        {
            let first = items[0];
            if items.len() == lanes::LANES && !first.is_none() && items.iter().all(|&i| i == first)
            {
                let tri = match prepared {
                    Some(t) if t.item == first => t,
                    _ => *prepared.insert(frames.prepare(scene, first)),
                };
                if let Some(k) = &constants[tri.material] {
                    lanes::shade_uniform(&tri, k, &rays, (c * lanes::LANES, y), &lighting, out);
                    continue;
                }
            }
            block.clear();
            for (i, (&item, px)) in items.iter().zip(out.iter_mut()).enumerate() {
                if item.is_none() {
                    *px = scene.background;
                    continue;
                }
                let tri = match prepared {
                    Some(t) if t.item == item => t,
                    _ => *prepared.insert(frames.prepare(scene, item)),
                };
                block.set(i, &tri, constants[tri.material].as_ref());
            }
            if block.live.iter().any(|&l| l) {
                block.shade(&rays, (c * lanes::LANES, y), &lighting, sample, out);
            }
        }
    });
}

/// The scalar reference of [`shade_into`]: one pixel at a time through
/// [`PreparedTriangle::surface`] and [`phong::shade`].
pub fn shade_into_scalar(scene: &Scene, vb: &VisibilityBuffer, image: &mut LinearImage) {
    let w = vb.width() as usize;
    let frames = ObjectFrames::new(scene);
    let rays = scene
        .camera
        .pixel_rays(Vec2::new(w as f32, vb.height() as f32));
    let rows = image
        .pixels_mut()
        .par_chunks_mut(w)
        .zip(vb.items().par_chunks(w));
    rows.enumerate().for_each(|(y, (out, items))| {
        for (x, (px, &item)) in out.iter_mut().zip(items).enumerate() {
            *px = if item.is_none() {
                scene.background
            } else {
                let s = frames.surface(
                    scene,
                    item,
                    &rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)),
                );
                phong::shade(&scene.lights, &scene.materials[s.material], &s).total()
            };
        }
    });
}
