//! One shadow map (Williams 1978; seed 002 §3.3's shadow pass): the depth of the
//! surfaces nearest a light, rendered by the same polygon pass as the eye's view,
//! and the test that decides whether a point lies behind them.
//!
//! Depth is compared as distance along the light's view axis, recovered from the
//! reversed depth the rasterizer stores, so the bias is in world units: one texel's
//! world size at the receiver times (constant + slope · tan θ), θ the angle between
//! the surface normal and the light. The constant term absorbs depth quantisation;
//! the slope term the depth change across one texel of a surface the light grazes.

use glam::{Mat4, Vec3};

use crate::scene::{Camera, Projection, Scene, ShadowSettings};
use crate::visibility::{rasterize_from, Faces, VisibilityBuffer};

/// Largest tan θ the slope bias uses (θ ≈ 84°); beyond it the bias would push
/// shadows off their casters.
const MAX_SLOPE: f32 = 8.0;

/// Depths seen from a light through one camera.
#[derive(Debug, Clone)]
pub struct DepthMap {
    view_proj: Mat4,
    eye: Vec3,
    axis: Vec3,
    resolution: u32,
    /// World size of a texel per unit distance (perspective) or absolute (orthographic).
    texel: f32,
    ortho: bool,
    near: f32,
    far: f32,
    /// Reversed depth of the nearest surface per texel (0: none).
    depth: VisibilityBuffer,
}

impl DepthMap {
    /// Renders the depth of every object of `scene` seen by `camera` into a square
    /// map of `resolution` texels.
    #[must_use]
    pub fn render(scene: &Scene, camera: &Camera, resolution: u32) -> DepthMap {
        let mut depth = VisibilityBuffer::depth_only(resolution, resolution);
        rasterize_from(scene, camera, Faces::All, &mut depth);
        let (ortho, texel) = match camera.projection {
            Projection::Perspective { fov_y_deg } => (false, 2.0 * (fov_y_deg.to_radians() * 0.5).tan()),
            Projection::Orthographic { height } => (true, height),
        };
        let (near, far) = (camera.near, camera.far);
        DepthMap {
            view_proj: camera.view_projection(1.0),
            eye: camera.eye,
            axis: (camera.target - camera.eye).normalize(),
            resolution,
            texel: texel / resolution as f32,
            ortho,
            near,
            far,
            depth,
        }
    }

    /// Whether `p` projects inside this map (in front of the light, within its
    /// square); the texel position if so.
    #[must_use]
    pub fn texel_of(&self, p: Vec3) -> Option<(f32, f32)> {
        let c = self.view_proj * p.extend(1.0);
        if c.w <= 0.0 {
            return None;
        }
        let (x, y) = (c.x / c.w, c.y / c.w);
        let n = self.resolution as f32;
        let (u, v) = ((x * 0.5 + 0.5) * n, (0.5 - y * 0.5) * n);
        (u >= 0.0 && v >= 0.0 && u < n && v < n).then_some((u, v))
    }

    /// Fraction of the k × k texels around `p`'s projection whose surface does not
    /// hide `p`, with `cos_theta` = N·L at `p` (for the slope bias). Points outside
    /// the map are lit.
    #[must_use]
    pub fn lit(&self, p: Vec3, cos_theta: f32, settings: &ShadowSettings) -> f32 {
        let Some((u, v)) = self.texel_of(p) else { return 1.0 };
        let d = (p - self.eye).dot(self.axis);
        if !self.ortho && d < self.near {
            return 1.0;
        }
        let texel = if self.ortho { self.texel } else { self.texel * d };
        let c = cos_theta.clamp(1e-3, 1.0);
        let tan = ((1.0 - c * c).sqrt() / c).min(MAX_SLOPE);
        let k = settings.pcf.max(1) as i32;
        // A wider filter reaches texels further from the receiver's own, where a
        // sloped receiver is deeper: scale the slope term with the filter radius.
        let reach = 1.0 + (k - 1) as f32 * 0.5;
        let limit = d - texel * (settings.bias + settings.slope * tan * reach);
        let (cu, cv) = (u as i32, v as i32);
        let last = self.resolution as i32 - 1;
        let mut lit = 0u32;
        for dy in 0..k {
            for dx in 0..k {
                let x = (cu + dx - k / 2).clamp(0, last) as usize;
                let y = (cv + dy - k / 2).clamp(0, last) as usize;
                lit += u32::from(self.distance(self.depth.depths()[y * self.resolution as usize + x]) >= limit);
            }
        }
        lit as f32 / (k * k) as f32
    }

    /// Distance along the axis of a texel holding reversed depth `z` (∞: empty).
    #[inline]
    fn distance(&self, z: f32) -> f32 {
        match (z > 0.0, self.ortho) {
            (false, _) => f32::INFINITY,
            (true, false) => self.near / z,
            (true, true) => self.far - z * (self.far - self.near),
        }
    }

    /// Bytes held by the map.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.depth.memory_bytes()
    }
}
