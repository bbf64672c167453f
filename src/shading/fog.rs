//! Fog, done the way seed 002 §3.5 says.
//!
//! Fogging every component as it is drawn would fade a shadowed region towards
//! black: the shadow pass's black is fogged too. The paper instead renders every
//! component with BLACK fog — each scaled by 1 − f(d) — and then one more
//! component: every object in a black material with the fog colour, f(d) · fog,
//! which no shadow suppresses. Their sum is `lerp(colour, fog, f(d))` everywhere,
//! in shadow or not. Scaling is linear, so kage scales each image once after its
//! passes ([`apply`]) rather than every pass: the same sum, one sweep.
//!
//! d is the distance from the eye to the visible surface along the pixel's ray
//! (orthographic views: from the image plane), recovered from the visibility
//! buffer's depth. Pixels that see nothing keep the background.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::{Component, Target};
use crate::image::LinearImage;
use crate::scene::{Fog, Scene};
use crate::visibility::VisibilityBuffer;

/// Fogs every target by the scene's fog, the paper's way: each image scaled
/// by `1 − f(d)`, and the fog colour times `f(d)` added to the image that
/// holds the fog component. Returns each pixel's fog amount (`None`, and
/// nothing changed, without fog).
pub fn fog_targets(scene: &Scene, vb: &VisibilityBuffer, targets: &mut [Target]) -> Option<Vec<f32>> {
    let fog = scene.fog.as_ref()?;
    let amounts = fog_amounts(scene, fog, vb);
    for t in targets {
        let color = if t.parts.contains(Component::Fog) { fog.color } else { Vec3::ZERO };
        apply(t.image, &amounts, color);
    }
    Some(amounts)
}

/// Per pixel `vb` holds, the fog amount f(d) of the surface it sees (0 where
/// it sees nothing).
#[must_use]
pub fn fog_amounts(scene: &Scene, fog: &Fog, vb: &VisibilityBuffer) -> Vec<f32> {
    let held = vb.rect();
    let w = (held.width() as usize).max(1);
    let rays = scene.camera.pixel_rays(Vec2::new(vb.width() as f32, vb.height() as f32));
    let mut out = vec![0.0; vb.depths().len()];
    out.par_chunks_mut(w).zip(vb.depths().par_chunks(w)).enumerate().for_each(|(y, (row, depth))| {
        let y = y + held.y0 as usize;
        for (x, (f, &z)) in (held.x0 as usize..).zip(row.iter_mut().zip(depth)) {
            if z > 0.0 {
                let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                *f = fog.amount(scene.camera.distance_at_depth(&ray, z));
            }
        }
    });
    out
}

/// Black fog on `image` (every component scaled by 1 − f), plus `color` · f, the
/// fog component (black for an image that does not hold it).
pub fn apply(image: &mut LinearImage, amounts: &[f32], color: Vec3) {
    image.pixels_mut().par_iter_mut().zip(amounts.par_iter()).for_each(|(p, &f)| *p = *p * (1.0 - f) + color * f);
}
