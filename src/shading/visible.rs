//! The surfaces a frame's pixels show, for a per-pixel shadow term
//! ([`crate::shadows::ScreenSurfaces`]): a band of rows at a time, each run
//! of pixels on one triangle found eight at a time as the shading pass finds
//! them ([`super::lanes::run_surfaces`]).

use std::ops::Range;

use glam::Vec2;

use super::lanes::{run_surfaces, RowRays};
use super::surface::ObjectFrames;
use super::{run_end, TriangleCache};
use crate::camera::PixelRays;
use crate::image::PixelRect;
use crate::scene::Scene;
use crate::shadows::{Receiver, ScreenSurfaces, SurfaceRows, VisibleSurface};
use crate::visibility::VisibilityBuffer;

/// The surface each pixel of `vb` shows (at the pixel's centre: position,
/// shading normal, and its object and triangle plane as a shadow's
/// receiver), seen through `scene`'s camera: what a per-pixel shadow term is
/// computed from, found a band of rows at a time as the term asks.
#[must_use]
pub fn screen_surfaces<'a>(scene: &'a Scene, vb: &'a VisibilityBuffer) -> ScreenSurfaces<'a> {
    let rays = scene.camera.pixel_rays(Vec2::new(vb.width() as f32, vb.height() as f32));
    let source = PixelSurfaces { scene, vb, frames: ObjectFrames::new(scene), rays };
    ScreenSurfaces::new(scene.camera, vb.width(), vb.height(), Box::new(source))
}

/// What [`screen_surfaces`] finds the surfaces from.
struct PixelSurfaces<'a> {
    scene: &'a Scene,
    vb: &'a VisibilityBuffer,
    frames: ObjectFrames,
    rays: PixelRays,
}

impl SurfaceRows for PixelSurfaces<'_> {
    fn fill(&self, rows: Range<usize>, out: &mut Vec<Option<VisibleSurface>>) {
        let (scene, vb) = (self.scene, self.vb);
        // Rows and columns are the image's; `row` and `items` hold the
        // columns `x0..x1` alone.
        let held = vb.rect();
        let (x0, w) = (held.x0 as usize, held.x1 as usize);
        out.clear();
        out.resize(rows.len() * held.width() as usize, None);
        // A mesh triangle is prepared once for the pixels of the band that
        // show it (a solid's tangent plane is each pixel's own).
        let mut cache = TriangleCache::new(64);
        for (y, row) in rows.zip(out.chunks_mut((w - x0).max(1))) {
            let items = vb.item_row(y as u32);
            let line = RowRays::new(&self.rays, y);
            let mut x = x0;
            while x < w {
                let item = items[x - x0];
                if item.is_none() {
                    x += 1;
                    continue;
                }
                let receiver = |plane| Receiver { object: item.object, plane };
                let end = x0 + run_end(items, x - x0);
                if item.primitive().is_some() {
                    // A solid: each pixel's own tangent plane.
                    let ray = self.rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                    let tangent = self.frames.prepare_at(scene, vb, x as u32, y as u32, &ray);
                    let (position, normal) = tangent.position_normal(&ray);
                    row[x - x0] =
                        Some(VisibleSurface { position, normal, receiver: receiver(tangent.geometry().geometric) });
                    x += 1;
                    continue;
                }
                let triangle = cache.get(scene, &self.frames, item);
                let plane = triangle.geometry().geometric;
                run_surfaces(triangle, &line, x, end - x, |i, position, normal| {
                    row[x - x0 + i] = Some(VisibleSurface { position, normal, receiver: receiver(plane) });
                });
                x = end;
            }
        }
    }

    fn held(&self) -> PixelRect {
        self.vb.rect()
    }
}
