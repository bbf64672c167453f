//! The eye: a look-at camera with a perspective or orthographic lens.
//!
//! Conventions (see `ARCHITECTURE.md`): world space is right-handed with +y up; the
//! camera looks down its own −z. Clip space follows the reversed-z convention: after
//! the divide by w, depth is 1 at the near plane and falls towards 0 (perspective: at
//! infinity; orthographic: at the far plane). Larger depth is nearer.

use glam::{Mat4, Vec2, Vec3, Vec4};

/// How the camera projects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Pinhole camera with a vertical field of view in degrees.
    Perspective {
        /// Vertical field of view, degrees, in (0, 180).
        fov_y_deg: f32,
    },
    /// Parallel projection showing `height` world units from bottom to top.
    Orthographic {
        /// World-space height of the view.
        height: f32,
    },
}

/// A look-at camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Approximate up direction.
    pub up: Vec3,
    /// Near clipping distance (> 0).
    pub near: f32,
    /// Far clipping distance (> near).
    pub far: f32,
    /// Lens.
    pub projection: Projection,
    /// Image-plane shift in normalised device units: the sample at a pixel centre
    /// sees what the unshifted camera sees at that centre + `shift` (x right, y up).
    /// Zero for a plain camera; jittered passes set a fraction of a pixel.
    pub shift: Vec2,
}

/// A ray with origin and (not necessarily unit) direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction.
    pub dir: Vec3,
}

impl Camera {
    /// This camera with its image shifted by `offset` pixels (y down) on a
    /// `width` × `height` frame: a pass whose pixel centres sample the points
    /// `offset` from the unshifted pixels' centres (a jittered pass).
    #[must_use]
    pub fn shifted(&self, offset: Vec2, (width, height): (u32, u32)) -> Camera {
        let pixel = 2.0 / Vec2::new(width as f32, height as f32);
        // Pixel offsets (y down) to NDC (y up).
        Camera { shift: self.shift + Vec2::new(offset.x, -offset.y) * pixel, ..*self }
    }

    /// The same camera with its eye, target and up moved by `m` (a rigid
    /// motion: a model's frame carried into the world's).
    #[must_use]
    pub fn transformed(&self, m: &glam::Affine3A) -> Camera {
        Camera {
            eye: m.transform_point3(self.eye),
            target: m.transform_point3(self.target),
            up: m.transform_vector3(self.up),
            ..*self
        }
    }

    /// World → view matrix.
    #[must_use]
    pub fn view(&self) -> Mat4 {
        let f = (self.target - self.eye).normalize();
        let s = f.cross(self.up).normalize();
        let u = s.cross(f);
        Mat4::from_cols(
            Vec4::new(s.x, u.x, -f.x, 0.0),
            Vec4::new(s.y, u.y, -f.y, 0.0),
            Vec4::new(s.z, u.z, -f.z, 0.0),
            Vec4::new(-s.dot(self.eye), -u.dot(self.eye), f.dot(self.eye), 1.0),
        )
    }

    /// View → clip matrix for an image of the given aspect (width / height), reversed z.
    #[must_use]
    pub fn projection(&self, aspect: f32) -> Mat4 {
        // What lay at NDC p + shift lands on p: x_ndc −= shift.x, i.e. x_clip −= shift.x·w.
        Mat4::from_translation(-self.shift.extend(0.0)) * self.lens(aspect)
    }

    fn lens(&self, aspect: f32) -> Mat4 {
        match self.projection {
            Projection::Perspective { fov_y_deg } => {
                // z_clip = near, w = −z_view: depth = near / distance, 1 at near, → 0 far.
                let t = (fov_y_deg.to_radians() * 0.5).tan();
                Mat4::from_cols(
                    Vec4::new(1.0 / (t * aspect), 0.0, 0.0, 0.0),
                    Vec4::new(0.0, 1.0 / t, 0.0, 0.0),
                    Vec4::new(0.0, 0.0, 0.0, -1.0),
                    Vec4::new(0.0, 0.0, self.near, 0.0),
                )
            }
            Projection::Orthographic { height } => {
                let (hh, hw) = (height * 0.5, height * 0.5 * aspect);
                // x, y as usual; z_ndc = (far + z_view) / (far - near): 1 at near, 0 at far.
                let k = 1.0 / (self.far - self.near);
                Mat4::from_cols(
                    Vec4::new(1.0 / hw, 0.0, 0.0, 0.0),
                    Vec4::new(0.0, 1.0 / hh, 0.0, 0.0),
                    Vec4::new(0.0, 0.0, k, 0.0),
                    Vec4::new(0.0, 0.0, self.far * k, 1.0),
                )
            }
        }
    }

    /// The far plane as a clip-space half-space `z − f·w ≥ 0`: returns f.
    #[must_use]
    pub fn far_plane_factor(&self) -> f32 {
        match self.projection {
            Projection::Perspective { .. } => self.near / self.far,
            Projection::Orthographic { .. } => 0.0,
        }
    }

    /// World → clip matrix.
    #[must_use]
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }

    /// The ray through image point `pixel` (pixel units, row 0 at the top, pixel
    /// centres at +0.5) of a `size` image. Its direction has unit length.
    #[must_use]
    pub fn ray(&self, pixel: Vec2, size: Vec2) -> Ray {
        self.pixel_rays(size).ray(pixel)
    }

    /// A generator of pixel rays for a `size` image, with the per-image work done once.
    #[must_use]
    pub fn pixel_rays(&self, size: Vec2) -> PixelRays {
        let inv_view = self.view().inverse();
        let aspect = size.x / size.y;
        let (scale, ortho) = match self.projection {
            Projection::Perspective { fov_y_deg } => {
                let t = (fov_y_deg.to_radians() * 0.5).tan();
                (Vec2::new(t * aspect, t), false)
            }
            Projection::Orthographic { height } => (Vec2::new(height * 0.5 * aspect, height * 0.5), true),
        };
        let right = inv_view.transform_vector3(Vec3::X) * scale.x;
        let up = inv_view.transform_vector3(Vec3::Y) * scale.y;
        let (forward, shift) = (inv_view.transform_vector3(Vec3::NEG_Z), right * self.shift.x + up * self.shift.y);
        // The shift moves the image centre: the eye ray's aim (perspective) or the
        // origin of the parallel rays (orthographic).
        let (origin, forward) = if ortho { (self.eye + shift, forward) } else { (self.eye, forward + shift) };
        PixelRays { origin, right, up, forward, size, ortho }
    }

    /// How far along `ray` (a ray of this camera, unit direction) the point of
    /// reversed depth `depth` lies (see [`crate::visibility::VisibilityBuffer`]).
    #[must_use]
    pub fn distance_at_depth(&self, ray: &Ray, depth: f32) -> f32 {
        self.view_distance_at_depth(depth) / ray.dir.dot((self.target - self.eye).normalize()).max(1e-6)
    }

    /// How far along the view axis, from the eye (perspective) or the eye
    /// plane (orthographic), the point of reversed depth `depth` lies: the
    /// inverse of [`Camera::depth_at_view_distance`].
    #[must_use]
    pub fn view_distance_at_depth(&self, depth: f32) -> f32 {
        match self.projection {
            Projection::Perspective { .. } => self.near / depth,
            Projection::Orthographic { .. } => self.far - depth * (self.far - self.near),
        }
    }

    /// The reversed depth (see [`crate::visibility::VisibilityBuffer`]) of a
    /// point `distance` along the view axis from the eye (perspective) or the
    /// eye plane (orthographic): what the projection's `z / w` gives, without
    /// the matrix.
    #[must_use]
    pub fn depth_at_view_distance(&self, distance: f32) -> f32 {
        match self.projection {
            Projection::Perspective { .. } => self.near / distance,
            Projection::Orthographic { .. } => (self.far - distance) / (self.far - self.near),
        }
    }

    /// Checks the camera can form an image; returns what is wrong otherwise.
    ///
    /// # Errors
    ///
    /// What makes the camera unusable: a non-finite eye, target or up, the
    /// eye on its target, `up` along the view, not `0 < near < far`, a field
    /// of view outside (0°, 180°) or a height that is not positive.
    pub fn validate(&self) -> Result<(), String> {
        let finite = self.eye.is_finite() && self.target.is_finite() && self.up.is_finite();
        if !finite {
            return Err("camera eye, target and up must be finite".into());
        }
        let fwd = self.target - self.eye;
        if fwd.length_squared() <= f32::EPSILON {
            return Err("camera eye and target coincide".into());
        }
        if fwd.normalize().cross(self.up).length_squared() <= 1e-10 {
            return Err("camera up is parallel to the view direction".into());
        }
        if !(self.near > 0.0 && self.far > self.near && self.far.is_finite()) {
            return Err(format!("need 0 < near < far, got near {} far {}", self.near, self.far));
        }
        match self.projection {
            Projection::Perspective { fov_y_deg } if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) => {
                Err(format!("fov must be in (0, 180) degrees, got {fov_y_deg}"))
            }
            Projection::Orthographic { height } if !(height > 0.0 && height.is_finite()) => {
                Err(format!("orthographic height must be > 0, got {height}"))
            }
            _ => Ok(()),
        }
    }
}

impl Ray {
    /// The point at distance `t` along the ray.
    #[must_use]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// The rays through the pixel centres of one image row as affine functions of
/// the column `x`: origin `origin + x·origin_step`, direction `dir +
/// x·dir_step`, the direction NOT normalised — its component along the view
/// axis is 1, so a distance `t` along it is the view-axis distance from the
/// eye (perspective) or the eye plane (orthographic).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RowLine {
    /// Origin of column 0's ray.
    pub origin: Vec3,
    /// Change of the origin per column (orthographic; zero in perspective).
    pub origin_step: Vec3,
    /// Direction of column 0's ray.
    pub dir: Vec3,
    /// Change of the direction per column (perspective; zero orthographic).
    pub dir_step: Vec3,
}

impl RowLine {
    /// Column `x`'s ray, direction not normalised.
    #[must_use]
    pub fn at(&self, x: f32) -> Ray {
        Ray { origin: self.origin + self.origin_step * x, dir: self.dir + self.dir_step * x }
    }

    /// `at(x).dir.length()` of the eight columns `x0..x0 + 8`, in lanes (each
    /// to the bit).
    #[must_use]
    pub fn dir_lengths(&self, x0: usize) -> [f32; 8] {
        let x = wide::f32x8::new(std::array::from_fn(|j| (x0 + j) as f32));
        let d: [wide::f32x8; 3] =
            std::array::from_fn(|k| wide::f32x8::splat(self.dir[k]) + wide::f32x8::splat(self.dir_step[k]) * x);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().to_array()
    }
}

/// Rays through the pixels of one image (see [`Camera::pixel_rays`]).
#[derive(Debug, Clone, Copy)]
pub struct PixelRays {
    /// Eye (perspective) or the image centre on the eye plane (orthographic).
    pub origin: Vec3,
    /// World offset from the image centre to its right edge.
    pub right: Vec3,
    /// World offset from the image centre to its top edge.
    pub up: Vec3,
    /// From the eye to the image centre at unit viewing distance (orthographic:
    /// the unit viewing direction).
    pub forward: Vec3,
    /// Image size in pixels.
    pub size: Vec2,
    /// Parallel rays (orthographic) rather than rays from one point.
    pub ortho: bool,
}

impl PixelRays {
    /// Row `y`'s pixel-centre rays as a [`RowLine`].
    #[must_use]
    pub fn row_line(&self, y: usize) -> RowLine {
        let v = 1.0 - 2.0 * (y as f32 + 0.5) / self.size.y;
        let step = self.right * (2.0 / self.size.x);
        let first = self.right * (1.0 / self.size.x - 1.0) + self.up * v;
        if self.ortho {
            RowLine { origin: self.origin + first, origin_step: step, dir: self.forward, dir_step: Vec3::ZERO }
        } else {
            RowLine { origin: self.origin, origin_step: Vec3::ZERO, dir: self.forward + first, dir_step: step }
        }
    }

    /// The ray through image point `pixel`; unit direction.
    #[must_use]
    pub fn ray(&self, pixel: Vec2) -> Ray {
        let ndc = Vec2::new(2.0 * pixel.x / self.size.x - 1.0, 1.0 - 2.0 * pixel.y / self.size.y);
        let offset = self.right * ndc.x + self.up * ndc.y;
        if self.ortho {
            Ray { origin: self.origin + offset, dir: self.forward.normalize() }
        } else {
            Ray { origin: self.origin, dir: (self.forward + offset).normalize() }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(projection: Projection) -> Camera {
        Camera {
            eye: Vec3::new(1.0, 2.0, 5.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            near: 0.1,
            far: 50.0,
            projection,
            shift: Vec2::ZERO,
        }
    }

    /// A point on the ray through a pixel projects back onto that pixel, and its
    /// reversed-z depth lies in (0, 1].
    #[test]
    fn ray_and_projection_agree() {
        let size = Vec2::new(64.0, 48.0);
        for p in [Projection::Perspective { fov_y_deg: 50.0 }, Projection::Orthographic { height: 4.0 }] {
            let c = cam(p);
            let m = c.view_projection(size.x / size.y);
            for pix in [Vec2::new(0.5, 0.5), Vec2::new(31.0, 20.25), Vec2::new(63.5, 47.5)] {
                let r = c.ray(pix, size);
                let w = r.origin + r.dir * 3.0;
                let clip = m * w.extend(1.0);
                let ndc = clip.truncate() / clip.w;
                let back = Vec2::new((ndc.x + 1.0) * 0.5 * size.x, (1.0 - ndc.y) * 0.5 * size.y);
                assert!((back - pix).length() < 1e-3, "{p:?} {pix} -> {back}");
                assert!(ndc.z > 0.0 && ndc.z <= 1.0, "depth {}", ndc.z);
                let t = c.distance_at_depth(&r, ndc.z);
                assert!((t - 3.0).abs() < 1e-3, "{p:?} {pix}: depth {} back to distance {t}, not 3", ndc.z);
            }
        }
    }

    /// The lengths of eight columns' directions in lanes are each column's
    /// `at(x).dir.length()` to the bit, on every row of both projections.
    #[test]
    fn eight_direction_lengths_are_each_columns() {
        let size = Vec2::new(100.0, 30.0);
        for p in [Projection::Perspective { fov_y_deg: 50.0 }, Projection::Orthographic { height: 4.0 }] {
            let rays = cam(p).pixel_rays(size);
            for y in 0..30 {
                let line = rays.row_line(y);
                for x0 in (0..100).step_by(8) {
                    let lanes = line.dir_lengths(x0).map(f32::to_bits);
                    let one: [u32; 8] = std::array::from_fn(|j| line.at((x0 + j) as f32).dir.length().to_bits());
                    assert_eq!(lanes, one, "{p:?} row {y} columns {x0}..");
                }
            }
        }
    }
}
