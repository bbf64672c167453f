//! A pixel's footprint on the surface it shows: how far the surface point
//! moves, in world space, when the pixel ray moves one pixel right and one
//! down. A shadow whose edge is known exactly (the silhouette-line buffer)
//! averages its term over this footprint, so a pixel the shadow's edge
//! crosses gets the share of it that is lit instead of a 0/1 at its centre.

use glam::{Vec2, Vec3};
use wide::f32x8;

use crate::camera::PixelRays;

/// The receiver of a lookup whose object is not known: every surface is held
/// to the full depth bias.
pub const UNKNOWN_RECEIVER: u32 = u32::MAX;

/// The surface a shadow lookup is for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Receiver {
    /// Its object: an index into the scene's objects, or
    /// [`UNKNOWN_RECEIVER`] (the silhouette-line buffer then holds every
    /// caster to the bias of the receiver's own surface).
    pub object: u32,
    /// The unit normal of its plane (the triangle's, not the interpolated
    /// shading normal), for the pixel's footprint; zero when not known, and
    /// the lookup is then not averaged over a footprint.
    pub plane: Vec3,
}

impl Receiver {
    /// Nothing known of the receiver.
    pub const UNKNOWN: Receiver = Receiver { object: UNKNOWN_RECEIVER, plane: Vec3::ZERO };

    /// A point of `object`, its plane not known.
    #[must_use]
    pub const fn of_object(object: u32) -> Receiver {
        Receiver { object, plane: Vec3::ZERO }
    }
}

/// Eight receivers ([`Receiver`] per lane).
#[derive(Debug, Clone, Copy)]
pub struct ReceiverLanes {
    /// Each lane's object.
    pub objects: [u32; 8],
    /// Each lane's plane normal (x, y, z lanes; zero: not known).
    pub planes: [f32x8; 3],
}

impl ReceiverLanes {
    /// Lane `i`'s receiver.
    #[inline]
    #[must_use]
    pub fn lane(&self, i: usize) -> Receiver {
        let [x, y, z] = self.planes.map(|c| c.to_array()[i]);
        Receiver { object: self.objects[i], plane: Vec3::new(x, y, z) }
    }

    /// Eight receivers of unknown objects and planes.
    pub const UNKNOWN: ReceiverLanes = ReceiverLanes { objects: [UNKNOWN_RECEIVER; 8], planes: [f32x8::ZERO; 3] };
}

/// Longest footprint side, in units of the pixel's size across the view at
/// the point's distance: a surface seen nearly edge-on stretches its
/// footprint towards infinity, and past this it is cut.
const MAX_STRETCH: f32 = 16.0;

/// The camera's pixel rays as a footprint needs them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelView {
    /// The eye (perspective) or a point of the view plane (orthographic).
    origin: Vec3,
    /// Unit viewing direction.
    axis: Vec3,
    /// Change of the ray direction at unit distance along the axis
    /// (perspective) or of the ray origin (orthographic) from one pixel to
    /// the next on a row.
    right: Vec3,
    /// The same from one row to the next (down the image).
    down: Vec3,
    ortho: bool,
}

impl PixelView {
    /// The view of `rays`.
    #[must_use]
    pub fn new(rays: &PixelRays) -> PixelView {
        let axis = rays.up.cross(rays.right).normalize_or(rays.forward.normalize_or(Vec3::NEG_Z));
        let size = rays.size.max(Vec2::ONE);
        PixelView {
            origin: rays.origin,
            axis,
            right: rays.right * (2.0 / size.x),
            down: -rays.up * (2.0 / size.y),
            ortho: rays.ortho,
        }
    }

    /// How point `p` of a plane with unit normal `n` moves when its pixel
    /// ray moves one pixel right, and one pixel down.
    #[must_use]
    pub fn footprint(&self, p: Vec3, n: Vec3) -> [Vec3; 2] {
        // The ray to p is origin + t·dir, and p stays on the plane as the ray
        // moves: ∂p = w − dir·(n·w)/(n·dir), w the ray's own move at p.
        let (dir, scale) = if self.ortho {
            (self.axis, 1.0)
        } else {
            let e = p - self.origin;
            (e, e.dot(self.axis).max(0.0))
        };
        let facing = n.dot(dir);
        [self.right, self.down].map(|step| {
            let w = step * scale;
            let limit = w.length() * MAX_STRETCH;
            if facing.abs() <= f32::MIN_POSITIVE {
                return w;
            }
            let moved = w - dir * (n.dot(w) / facing);
            let len = moved.length();
            if len > limit {
                moved * (limit / len)
            } else {
                moved
            }
        })
    }

    /// The lengths of [`PixelView::footprint`]'s two sides added, for eight
    /// points `p` (x, y, z lanes) on planes of unit normals `n`.
    #[must_use]
    pub fn footprint_span_lanes(&self, p: [f32x8; 3], n: [f32x8; 3]) -> f32x8 {
        let splat = |v: Vec3| [v.x, v.y, v.z].map(f32x8::splat);
        let dot = |a: &[f32x8; 3], b: &[f32x8; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let (dir, scale) = if self.ortho {
            (splat(self.axis), f32x8::ONE)
        } else {
            let o = splat(self.origin);
            let e = [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
            let scale = dot(&e, &splat(self.axis)).max(f32x8::ZERO);
            (e, scale)
        };
        let facing = dot(&n, &dir);
        let edge_on = facing.abs().simd_le(f32x8::splat(f32::MIN_POSITIVE));
        let side = |step: Vec3| {
            let w = splat(step).map(|c| c * scale);
            let plain = dot(&w, &w).sqrt();
            let k = dot(&n, &w) / facing;
            let moved = [w[0] - dir[0] * k, w[1] - dir[1] * k, w[2] - dir[2] * k];
            let len = dot(&moved, &moved).sqrt().min(plain * f32x8::splat(MAX_STRETCH));
            edge_on.select(plain, len)
        };
        side(self.right) + side(self.down)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection};

    /// Where the ray through image point `at` meets the plane through `p0`
    /// with normal `n`.
    fn hit(rays: &PixelRays, at: Vec2, p0: Vec3, n: Vec3) -> Vec3 {
        let ray = rays.ray(at);
        ray.origin + ray.dir * ((p0 - ray.origin).dot(n) / ray.dir.dot(n))
    }

    /// The footprint equals the moves of the ray/plane intersection between
    /// neighbouring pixel centres (to first order: a centred difference),
    /// for perspective (with a shifted image) and orthographic cameras.
    #[test]
    fn the_footprint_is_the_move_of_the_pixel_rays_hit() {
        let size = Vec2::new(320.0, 200.0);
        for projection in [Projection::Perspective { fov_y_deg: 50.0 }, Projection::Orthographic { height: 6.0 }] {
            let camera = Camera {
                eye: Vec3::new(1.0, 3.0, 6.0),
                target: Vec3::new(0.0, 0.5, 0.0),
                up: Vec3::Y,
                near: 0.1,
                far: 50.0,
                projection,
                shift: Vec2::new(0.1, -0.05),
            };
            let rays = camera.pixel_rays(size);
            let view = PixelView::new(&rays);
            let n = Vec3::new(0.2, 1.0, 0.3).normalize();
            let p0 = Vec3::new(0.0, 0.2, 0.0);
            for at in [Vec2::new(160.5, 100.5), Vec2::new(20.5, 180.5), Vec2::new(300.5, 15.5)] {
                let p = hit(&rays, at, p0, n);
                let [dx, dy] = view.footprint(p, n);
                let h = 0.25;
                let want_x =
                    (hit(&rays, at + Vec2::new(h, 0.0), p0, n) - hit(&rays, at - Vec2::new(h, 0.0), p0, n)) / (2.0 * h);
                let want_y =
                    (hit(&rays, at + Vec2::new(0.0, h), p0, n) - hit(&rays, at - Vec2::new(0.0, h), p0, n)) / (2.0 * h);
                for (got, want) in [(dx, want_x), (dy, want_y)] {
                    assert!(
                        (got - want).length() < 5e-3 * want.length().max(1e-3),
                        "{projection:?} at {at}: {got} vs {want}"
                    );
                }
            }
        }
    }
}
