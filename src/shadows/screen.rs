//! The screen-space form of a shadow term: one value per pixel of the frame,
//! computed once from the surfaces the pixels show ([`ScreenSurfaces`]) and
//! read back by every pass that shades a point of those surfaces
//! ([`ScreenTerm::at`]). A point is found in the buffer by projecting it
//! through the eye: the pixel it falls in, or one of its eight neighbours,
//! whose surface lies where the point does; a point no pixel shows (a
//! reflection's, one behind a silhouette) is not in the buffer and the term
//! that owns the buffer answers for it on its own.

use std::ops::Range;

use glam::{Mat4, Vec2, Vec3};
use wide::f32x8;

use super::Receiver;
use crate::camera::{Camera, Projection};
use crate::image::PixelRect;

/// The surface one pixel shows, at its centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VisibleSurface {
    /// World position.
    pub position: Vec3,
    /// Unit shading normal, on the side the eye sees.
    pub normal: Vec3,
    /// Its object and plane, as a shadow's receiver.
    pub receiver: Receiver,
}

/// Finds the surfaces a frame's pixels show, a band of rows at a time: what
/// a per-pixel term is computed from. Implemented by the shading stage,
/// which knows the frame's visibility buffer and the scene's geometry.
pub trait SurfaceRows: Sync {
    /// Fills `out` (cleared first) with the surfaces of the frame's rows
    /// `rows` (of those [`SurfaceRows::held`] holds), row by row, one entry
    /// per pixel held; `None` where no object is seen.
    fn fill(&self, rows: Range<usize>, out: &mut Vec<Option<VisibleSurface>>);

    /// The pixels whose surfaces are known: the whole frame but for a tile.
    fn held(&self) -> PixelRect;
}

/// The surfaces a frame's pixels show — found on demand, a band of rows at a
/// time ([`ScreenSurfaces::rows`]), so that no whole-frame copy of them is
/// kept — and the camera they are seen through.
pub struct ScreenSurfaces<'a> {
    /// The frame's camera.
    pub camera: Camera,
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    source: Box<dyn SurfaceRows + 'a>,
    /// A pixel's world size per unit distance along the view (perspective)
    /// or absolute (orthographic).
    pixel_scale: f32,
    /// The unit view axis.
    forward: Vec3,
}

impl std::fmt::Debug for ScreenSurfaces<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ScreenSurfaces").field("width", &self.width).field("height", &self.height).finish()
    }
}

impl<'a> ScreenSurfaces<'a> {
    /// The `width` × `height` pixels seen through `camera`, their surfaces
    /// found by `source`.
    #[must_use]
    pub fn new(camera: Camera, width: u32, height: u32, source: Box<dyn SurfaceRows + 'a>) -> ScreenSurfaces<'a> {
        let pixel_scale = match camera.projection {
            Projection::Perspective { fov_y_deg } => 2.0 * (fov_y_deg.to_radians() * 0.5).tan(),
            Projection::Orthographic { height } => height,
        } / height.max(1) as f32;
        let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
        ScreenSurfaces { camera, width, height, source, pixel_scale, forward }
    }

    /// The pixels whose surfaces are known ([`ScreenSurfaces::rows`]): the
    /// whole frame but for a tile of it.
    #[must_use]
    pub fn held(&self) -> PixelRect {
        self.source.held()
    }

    /// The surfaces of rows `rows` (clamped to those held), row by row, one
    /// entry per column held, into `out`.
    pub fn rows(&self, rows: Range<usize>, out: &mut Vec<Option<VisibleSurface>>) {
        let held = self.held();
        let (y0, y1) = (held.y0 as usize, held.y1 as usize);
        let rows = rows.start.clamp(y0, y1)..rows.end.clamp(y0, y1);
        self.source.fill(rows, out);
    }

    /// The surfaces of every pixel held, row by row.
    #[must_use]
    pub fn all(&self) -> Vec<Option<VisibleSurface>> {
        let mut out = Vec::new();
        self.rows(0..self.height as usize, &mut out);
        out
    }

    /// The world size of one pixel's footprint on `v`'s surface: a pixel
    /// across the view, stretched where the surface turns away from the eye.
    #[must_use]
    pub fn footprint(&self, v: &VisibleSurface) -> f32 {
        let to_eye = match self.camera.projection {
            Projection::Perspective { .. } => (self.camera.eye - v.position).normalize_or(Vec3::Z),
            Projection::Orthographic { .. } => -self.forward,
        };
        self.pixel_size(v.position) / v.normal.dot(to_eye).abs().max(0.2)
    }

    /// [`ScreenSurfaces::footprint`] of eight surfaces at once (their points
    /// `p` and unit normals `n`, x, y, z lanes), and their distances from
    /// the eye as [`ScreenTerm::at`] measures them: from the eye itself
    /// (perspective) or along the view axis (orthographic).
    #[must_use]
    pub fn footprint_lanes(&self, p: [f32x8; 3], n: [f32x8; 3]) -> (f32x8, f32x8) {
        let c = &self.camera;
        let (eye, forward) = ([c.eye.x, c.eye.y, c.eye.z].map(f32x8::splat), self.forward);
        let d = [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
        let along = d[0] * forward.x + d[1] * forward.y + d[2] * forward.z;
        let (size, facing, distance) = match c.projection {
            Projection::Perspective { .. } => {
                let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let facing = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / length.max(f32x8::splat(f32::MIN_POSITIVE));
                (along.max(f32x8::splat(c.near)) * f32x8::splat(self.pixel_scale), facing, length)
            }
            Projection::Orthographic { .. } => {
                let facing = n[0] * forward.x + n[1] * forward.y + n[2] * forward.z;
                (f32x8::splat(self.pixel_scale), facing, along)
            }
        };
        (size / facing.abs().max(f32x8::splat(0.2)), distance)
    }

    /// The world size of one pixel at point `p`, across the view.
    #[must_use]
    pub fn pixel_size(&self, p: Vec3) -> f32 {
        match self.camera.projection {
            Projection::Perspective { .. } => {
                (p - self.camera.eye).dot(self.forward).max(self.camera.near) * self.pixel_scale
            }
            Projection::Orthographic { .. } => self.pixel_scale,
        }
    }

    /// Whether neighbouring pixels' surfaces `a` and `b` (their footprints
    /// `fa`, `fb`) lie apart: one shows an object and the other none, or
    /// their points are further apart than four pixel footprints on the
    /// surface with the larger one (a depth discontinuity of the eye's view,
    /// not a crease).
    #[must_use]
    pub fn lie_apart(a: Option<&VisibleSurface>, fa: f32, b: Option<&VisibleSurface>, fb: f32) -> bool {
        match (a, b) {
            (None, None) => false,
            (Some(_), None) | (None, Some(_)) => true,
            (Some(s), Some(t)) => {
                let most = fa.max(fb);
                (s.position - t.position).length_squared() > 16.0 * most * most
            }
        }
    }

    /// The term `values` of these surfaces on a `grid` of `(w, h)` points
    /// spread over the frame (the pixels themselves, or fewer: each grid
    /// cell covers as many pixels): `distances` from the eye (as
    /// [`ScreenSurfaces::footprint_lanes`] gives them; NaN where no object
    /// is seen) and
    /// `reach` (how far a point may lie from a cell's surface point and
    /// still be read there), one each per cell, row by row.
    ///
    /// # Panics
    ///
    /// If the three do not hold one value per cell.
    #[must_use]
    pub fn term(&self, grid: (usize, usize), distances: Vec<f32>, reach: Vec<f32>, values: Vec<f32>) -> ScreenTerm {
        let (w, h) = grid;
        assert!(
            [distances.len(), reach.len(), values.len()].iter().all(|&n| n == w * h),
            "one distance, reach and value per cell"
        );
        let c = &self.camera;
        let axis = match c.projection {
            Projection::Perspective { .. } => None,
            Projection::Orthographic { .. } => Some(self.forward),
        };
        let view_proj = c.view_projection(self.width as f32 / self.height.max(1) as f32);
        // Where each cell's sample lies within it: at its first pixel's centre.
        let sample = 0.5 * w as f32 / self.width.max(1) as f32;
        ScreenTerm { view_proj, width: w, height: h, sample, eye: c.eye, axis, distances, reach, values }
    }
}

/// A per-pixel shadow term and how to find a point's pixel.
#[derive(Debug, Clone)]
pub struct ScreenTerm {
    view_proj: Mat4,
    width: usize,
    height: usize,
    /// Where in its cell each value was sampled (0.5: the centre, a cell per
    /// pixel; less: a cell of several pixels, sampled at its first).
    sample: f32,
    /// The eye, and the view axis of an orthographic camera (distances are
    /// measured along it; a perspective camera's from the eye).
    eye: Vec3,
    axis: Option<Vec3>,
    /// How far from the eye each pixel's surface lies (NaN where none is
    /// seen): a point projected into the pixel lies on its surface when its
    /// own distance is within the pixel's reach of this.
    distances: Vec<f32>,
    /// How far a point may lie from a pixel's surface point and still be
    /// read there: the pixel's footprint, per pixel.
    reach: Vec<f32>,
    /// The term per pixel.
    values: Vec<f32>,
}

impl ScreenTerm {
    /// The term per pixel, row by row.
    #[must_use]
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The term at world point `p`: the value of the pixel `p` projects into,
    /// or of the one of its eight neighbours whose surface lies nearest `p`'s
    /// distance from the eye, within two footprints; `None` when none does.
    /// On a grid coarser than the pixels, the four samples round `p` on its
    /// surface weighted bilinearly first (depth-aware upsampling).
    #[must_use]
    pub fn at(&self, p: Vec3) -> Option<f32> {
        let c = self.view_proj * p.extend(1.0);
        if c.w <= 0.0 {
            return None;
        }
        let ndc = Vec2::new(c.x / c.w, c.y / c.w);
        let (fx, fy) = ((ndc.x * 0.5 + 0.5) * self.width as f32, (0.5 - ndc.y * 0.5) * self.height as f32);
        let (x, y) = (fx.floor() as i64, fy.floor() as i64);
        let along = self.axis.map_or((p - self.eye).length(), |a| (p - self.eye).dot(a));
        if self.sample < 0.5 {
            if let Some(v) = self.bilinear(fx - self.sample, fy - self.sample, along) {
                return Some(v);
            }
        }
        let mut best: Option<(f32, usize)> = None;
        for (dx, dy) in [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1)] {
            let (u, v) = (x + dx, y + dy);
            if u < 0 || v < 0 || u >= self.width as i64 || v >= self.height as i64 {
                continue;
            }
            let i = v as usize * self.width + u as usize;
            let d = (self.distances[i] - along).abs();
            if d <= self.reach[i] && best.is_none_or(|(b, _)| d < b) {
                best = Some((d, i));
                if dx == 0 && dy == 0 && d <= self.reach[i] * 0.25 {
                    break;
                }
            }
        }
        best.map(|(_, i)| self.values[i])
    }

    /// The values of the four samples round grid point `(u, v)` (in cells,
    /// samples at whole numbers) weighted bilinearly, those not on the
    /// surface at distance `along` from the eye left out; `None` when none
    /// is.
    fn bilinear(&self, u: f32, v: f32, along: f32) -> Option<f32> {
        let (x0, y0) = (u.floor(), v.floor());
        let (tx, ty) = (u - x0, v - y0);
        let (mut sum, mut weight) = (0.0, 0.0);
        for (dx, dy, w) in
            [(0, 0, (1.0 - tx) * (1.0 - ty)), (1, 0, tx * (1.0 - ty)), (0, 1, (1.0 - tx) * ty), (1, 1, tx * ty)]
        {
            let (x, y) = (x0 as i64 + dx, y0 as i64 + dy);
            if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
                continue;
            }
            let i = y as usize * self.width + x as usize;
            if (self.distances[i] - along).abs() <= self.reach[i] {
                sum += w * self.values[i];
                weight += w;
            }
        }
        (weight > 1e-3).then(|| sum / weight)
    }

    /// Bytes held.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        (self.distances.len() + self.reach.len() + self.values.len()) * std::mem::size_of::<f32>()
    }
}
