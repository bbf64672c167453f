//! The frame's screen as the edge pass reads it: clip space to pixels (as the
//! polygon pass maps it), each object's map into clip space, and a surface's
//! stored depth as a plane over the screen.

use glam::{DVec4, Mat4};

use crate::camera::Camera;
use crate::scene::{Mesh, Scene};

/// Clip space to the pixel grid, as the polygon pass maps it.
pub(super) struct Screen {
    width: f64,
    height: f64,
    /// The far plane `z = far·w` (reversed depth).
    far: f64,
}

impl Screen {
    /// The part of segment `a`–`b` (clip space) between the near (`z ≤ w`) and far
    /// (`z ≥ far·w`) planes, as screen points (x, y in pixels, z = depth).
    pub(super) fn clip_and_project(&self, mut a: DVec4, mut b: DVec4) -> Option<(glam::DVec3, glam::DVec3)> {
        for plane in [DVec4::new(0.0, 0.0, -1.0, 1.0), DVec4::new(0.0, 0.0, 1.0, -self.far)] {
            let (da, db) = (plane.dot(a), plane.dot(b));
            if da < 0.0 && db < 0.0 {
                return None;
            }
            if da < 0.0 {
                a = b + (a - b) * (db / (db - da));
            } else if db < 0.0 {
                b = a + (b - a) * (da / (da - db));
            }
        }
        (a.w > 0.0 && b.w > 0.0).then(|| (self.project(a), self.project(b)))
    }

    /// A clip-space point in front of the eye as a screen point (x, y in pixels,
    /// z = depth).
    pub(super) fn project(&self, c: DVec4) -> glam::DVec3 {
        let inv_w = 1.0 / c.w;
        glam::DVec3::new((c.x * inv_w * 0.5 + 0.5) * self.width, (0.5 - c.y * inv_w * 0.5) * self.height, c.z * inv_w)
    }

    /// The screen from `scene`'s camera onto a `width` × `height` image.
    pub(super) fn of(camera: &Camera, width: u32, height: u32) -> Screen {
        Screen { width: f64::from(width), height: f64::from(height), far: f64::from(camera.far_plane_factor()) }
    }

    /// Triangle `t`'s plane as the depth it stores over the screen (depth is
    /// affine in screen x, y over a plane, in perspective too: z/w and 1/w
    /// are), found from the plane itself, so a triangle reaching behind the eye
    /// (a large floor) has one too. `None` if the plane is seen edge-on.
    pub(super) fn depth_plane(&self, clip: &ClipMap, mesh: &Mesh, t: u32) -> Option<DepthPlane> {
        let [a, b, c] = mesh.triangles.get(t as usize)?.map(|v| mesh.positions[v as usize].as_dvec3());
        let n = (b - a).cross(c - a);
        // The plane a·x + b·y + c·z + d = 0 in clip space over NDC (x, y, z).
        let p = clip.planes * n.extend(-n.dot(a));
        if p.z.abs() < 1e-12 * p.truncate().length().max(f64::MIN_POSITIVE) {
            return None;
        }
        // NDC x = 2·sx/width − 1, y = 1 − 2·sy/height; z = −(p.x·x + p.y·y + p.w)/p.z.
        let gx = -2.0 * p.x / (p.z * self.width);
        let gy = 2.0 * p.y / (p.z * self.height);
        Some(DepthPlane { z0: (p.x - p.y - p.w) / p.z, gx, gy })
    }
}

/// An object's map from its own space to clip space, for points and for
/// planes (`n·x + d = 0` as (n, d): the inverse transpose).
#[derive(Debug, Clone, Copy)]
pub(super) struct ClipMap {
    pub(super) points: glam::DMat4,
    pub(super) planes: glam::DMat4,
}

impl ClipMap {
    /// Every object's, for a `width` × `height` view of `scene`.
    pub(super) fn of_objects(scene: &Scene, width: u32, height: u32) -> Vec<ClipMap> {
        let view_proj = scene.camera.view_projection(width as f32 / height as f32);
        let clip = |o: &crate::scene::Object| (view_proj * Mat4::from(o.transform)).as_dmat4();
        scene.objects.iter().map(clip).map(|points| ClipMap { points, planes: points.inverse().transpose() }).collect()
    }
}

/// A surface's stored depth over the screen: `z0 + gx·x + gy·y` (pixels).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct DepthPlane {
    pub(super) z0: f64,
    pub(super) gx: f64,
    pub(super) gy: f64,
}

impl DepthPlane {
    /// The depth at screen point (x, y).
    pub(super) fn at(&self, x: f64, y: f64) -> f64 {
        self.z0 + self.gx * x + self.gy * y
    }
}
