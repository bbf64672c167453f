//! The screen-space form of a shadow term: one value per pixel of the frame,
//! computed once from the surfaces the pixels show ([`ScreenSurfaces`]) and
//! read back by every pass that shades a point of those surfaces
//! ([`ScreenTerm::at`]). A point is found in the buffer by projecting it
//! through the eye: the pixel it falls in, or one of its eight neighbours,
//! whose surface lies where the point does; a point no pixel shows (a
//! reflection's, one behind a silhouette) is not in the buffer and the term
//! that owns the buffer answers for it on its own.

use glam::{Mat4, Vec2, Vec3};
use rayon::prelude::*;

use super::Receiver;
use crate::camera::{Camera, Projection};

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

/// The surfaces every pixel of a frame shows, row by row, the camera they
/// are seen through, and where neighbouring pixels' surfaces lie apart.
#[derive(Debug, Clone)]
pub struct ScreenSurfaces {
    /// The frame's camera.
    pub camera: Camera,
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// One per pixel; `None` where no object is seen.
    pub surfaces: Vec<Option<VisibleSurface>>,
    /// Per pixel: bit 0 set where it lies apart from the pixel right of it,
    /// bit 1 from the one below ([`ScreenSurfaces::lie_apart`]).
    cuts: Vec<u8>,
    /// Per pixel: the world size of its footprint on its surface (0 where
    /// none is seen).
    footprints: Vec<f32>,
    /// A pixel's world size per unit distance along the view (perspective)
    /// or absolute (orthographic).
    pixel_scale: f32,
    /// The unit view axis.
    forward: Vec3,
}

impl ScreenSurfaces {
    /// The `width` × `height` pixels' `surfaces` seen through `camera`.
    ///
    /// # Panics
    ///
    /// If `surfaces` does not hold one entry per pixel.
    #[must_use]
    pub fn new(camera: Camera, width: u32, height: u32, surfaces: Vec<Option<VisibleSurface>>) -> ScreenSurfaces {
        assert_eq!(surfaces.len(), width as usize * height as usize, "one surface per pixel");
        let pixel_scale = match camera.projection {
            Projection::Perspective { fov_y_deg } => 2.0 * (fov_y_deg.to_radians() * 0.5).tan(),
            Projection::Orthographic { height } => height,
        } / height.max(1) as f32;
        let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
        let mut s = ScreenSurfaces {
            camera,
            width,
            height,
            surfaces,
            cuts: Vec::new(),
            footprints: Vec::new(),
            pixel_scale,
            forward,
        };
        let footprints: Vec<f32> = s.surfaces.par_iter().map(|v| v.as_ref().map_or(0.0, |v| s.footprint(v))).collect();
        s.footprints = footprints;
        let w = width as usize;
        let cuts: Vec<u8> = (0..s.surfaces.len())
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let right = x + 1 < w && s.lie_apart((x, y), (x + 1, y));
                let down = y + 1 < height as usize && s.lie_apart((x, y), (x, y + 1));
                u8::from(right) | u8::from(down) << 1
            })
            .collect();
        s.cuts = cuts;
        s
    }

    /// Whether pixel `a` and its neighbour `b` (right of it or below it)
    /// show surfaces that lie apart (found once, at [`ScreenSurfaces::new`]).
    #[inline]
    #[must_use]
    pub fn apart(&self, a: (usize, usize), b: (usize, usize)) -> bool {
        let bit = if b.1 > a.1 { 2 } else { 1 };
        self.cuts[a.1 * self.width as usize + a.0] & bit != 0
    }

    /// The surface pixel `(x, y)` shows.
    #[must_use]
    pub fn at(&self, x: usize, y: usize) -> Option<&VisibleSurface> {
        self.surfaces[y * self.width as usize + x].as_ref()
    }

    /// The world size of pixel `i`'s footprint on its surface (row by row;
    /// 0 where no object is seen).
    #[must_use]
    pub fn footprint_at(&self, i: usize) -> f32 {
        self.footprints[i]
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

    /// Whether the surfaces of neighbouring pixels `a` and `b` lie apart: one
    /// shows an object and the other none, or their points are further
    /// apart than four pixel footprints on the surface with the larger one
    /// (a depth discontinuity of the eye's view, not a crease).
    fn lie_apart(&self, a: (usize, usize), b: (usize, usize)) -> bool {
        match (self.at(a.0, a.1), self.at(b.0, b.1)) {
            (None, None) => false,
            (Some(_), None) | (None, Some(_)) => true,
            (Some(s), Some(t)) => {
                let w = self.width as usize;
                let most = self.footprints[a.1 * w + a.0].max(self.footprints[b.1 * w + b.0]);
                (s.position - t.position).length_squared() > 16.0 * most * most
            }
        }
    }
}

/// A per-pixel shadow term and how to find a point's pixel.
#[derive(Debug, Clone)]
pub struct ScreenTerm {
    view_proj: Mat4,
    width: usize,
    height: usize,
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
    /// The term `values` (one per pixel of `surfaces`, row by row).
    ///
    /// # Panics
    ///
    /// If `values` does not hold one value per pixel.
    #[must_use]
    pub fn new(surfaces: &ScreenSurfaces, values: Vec<f32>) -> ScreenTerm {
        assert_eq!(values.len(), surfaces.surfaces.len(), "one value per pixel");
        let (w, h) = (surfaces.width as usize, surfaces.height as usize);
        let c = &surfaces.camera;
        let axis = match c.projection {
            Projection::Perspective { .. } => None,
            Projection::Orthographic { .. } => Some((c.target - c.eye).normalize_or(Vec3::NEG_Z)),
        };
        let distance = |p: Vec3| axis.map_or((p - c.eye).length(), |a| (p - c.eye).dot(a));
        let distances = surfaces.surfaces.par_iter().map(|s| s.map_or(f32::NAN, |s| distance(s.position))).collect();
        let reach = surfaces.footprints.par_iter().map(|f| 2.0 * f).collect();
        let view_proj = surfaces.camera.view_projection(w as f32 / h.max(1) as f32);
        ScreenTerm { view_proj, width: w, height: h, eye: c.eye, axis, distances, reach, values }
    }

    /// The term per pixel, row by row.
    #[must_use]
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The term at world point `p`: the value of the pixel `p` projects into,
    /// or of the one of its eight neighbours whose surface lies nearest `p`'s
    /// distance from the eye, within two footprints; `None` when none does.
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

    /// Bytes held.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        (self.distances.len() + self.reach.len() + self.values.len()) * std::mem::size_of::<f32>()
    }
}
