//! Cameras that move: a scene file's camera path (keyframes of eye, target
//! and field of view, joined by straight lines or Catmull–Rom curves) and the
//! turntable orbit of `kage render --turntable`. Frame `i` of either is a
//! pure function of `i`, so one frame rendered on its own equals the same
//! frame of the whole run, bit for bit.

use glam::{Affine3A, Vec3};

use crate::camera::{Camera, Projection};
use crate::scene::light::Light;

/// How a camera path joins its keyframes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interpolation {
    /// Straight lines between keys: constant speed, a corner at each key.
    Linear,
    /// A Catmull–Rom curve through the keys: smooth through each key, its
    /// tangent there the slope between the keys either side.
    #[default]
    CatmullRom,
}

/// One keyframe: where the camera is at frame `frame`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Key {
    /// The frame it holds at (0 is the first).
    pub frame: u32,
    /// The eye.
    pub eye: Vec3,
    /// The point looked at.
    pub target: Vec3,
    /// Vertical field of view, degrees (a perspective camera's).
    pub fov_deg: f32,
}

/// A camera path of `frames` frames through `keys` (sorted by frame, at
/// least one).
#[derive(Debug, Clone, PartialEq)]
pub struct CameraPath {
    /// Frames in the path: 0 to `frames − 1`.
    pub frames: u32,
    /// The keyframes, by frame.
    pub keys: Vec<Key>,
    /// How keys are joined.
    pub interpolation: Interpolation,
}

impl CameraPath {
    /// `base` (the scene's camera: its up, planes and projection) moved to
    /// frame `frame`: before the first key it stands at the first, after
    /// the last at the last.
    ///
    /// # Panics
    ///
    /// If the path has no key.
    #[must_use]
    pub fn camera_at(&self, frame: u32, base: &Camera) -> Camera {
        let keys = &self.keys;
        let t = frame as f32;
        let next = keys.partition_point(|k| k.frame as f32 <= t);
        let (eye, target, fov) = if next == 0 {
            let k = keys[0];
            (k.eye, k.target, k.fov_deg)
        } else if next == keys.len() {
            let k = keys[keys.len() - 1];
            (k.eye, k.target, k.fov_deg)
        } else {
            let (i, j) = (next - 1, next);
            let s = (t - keys[i].frame as f32) / (keys[j].frame - keys[i].frame) as f32;
            match self.interpolation {
                Interpolation::Linear => {
                    let (a, b) = (keys[i], keys[j]);
                    (a.eye.lerp(b.eye, s), a.target.lerp(b.target, s), a.fov_deg + (b.fov_deg - a.fov_deg) * s)
                }
                Interpolation::CatmullRom => {
                    let curve = |f: fn(&Key) -> Vec3| hermite(keys, i, s, f);
                    let fov = hermite(keys, i, s, |k| Vec3::splat(k.fov_deg)).x;
                    (curve(|k| k.eye), curve(|k| k.target), fov)
                }
            }
        };
        let projection = match base.projection {
            Projection::Perspective { .. } => Projection::Perspective { fov_y_deg: fov.clamp(0.01, 179.0) },
            p => p,
        };
        Camera { eye, target, projection, ..*base }
    }
}

/// The Catmull–Rom curve between keys `i` and `i + 1` at `s` in [0, 1], of
/// the value `f` picks: a cubic Hermite segment whose tangent at each key is
/// the slope between its neighbours (one-sided at the path's ends), scaled
/// to the segment's length in frames, so unevenly spaced keys keep a smooth
/// speed.
fn hermite(keys: &[Key], i: usize, s: f32, f: fn(&Key) -> Vec3) -> Vec3 {
    let slope = |k: usize| {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(keys.len() - 1));
        (f(&keys[b]) - f(&keys[a])) / (keys[b].frame - keys[a].frame).max(1) as f32
    };
    let h = (keys[i + 1].frame - keys[i].frame) as f32;
    let (p0, p1, m0, m1) = (f(&keys[i]), f(&keys[i + 1]), slope(i) * h, slope(i + 1) * h);
    let (s2, s3) = (s * s, s * s * s);
    p0 * (2.0 * s3 - 3.0 * s2 + 1.0) + m0 * (s3 - 2.0 * s2 + s) + p1 * (-2.0 * s3 + 3.0 * s2) + m1 * (s3 - s2)
}

/// Frame `frame` of a turntable of `frames` frames: `camera`'s eye turned
/// about the vertical line through its target by 360·frame/frames degrees,
/// from the front towards the right (a camera in front, on +z, looks from
/// +x a quarter of the way round). Frame 0 is `camera` itself.
///
/// # Panics
///
/// If `frames` is 0.
#[must_use]
pub fn turntable(camera: &Camera, frame: u32, frames: u32) -> Camera {
    assert!(frames > 0, "a turntable has at least one frame");
    if frame.is_multiple_of(frames) {
        return *camera;
    }
    let angle = f64::from(frame % frames) / f64::from(frames) * std::f64::consts::TAU;
    let (sin, cos) = (angle.sin() as f32, angle.cos() as f32);
    let d = camera.eye - camera.target;
    // Turned in the horizontal plane only: the height is kept exactly.
    let turned = Vec3::new(d.x * cos + d.z * sin, d.y, d.z * cos - d.x * sin);
    Camera { eye: camera.target + turned, ..*camera }
}

/// `lights` turned with the camera of turntable frame `frame` of `frames`:
/// about the vertical axis through `target`, by the camera's angle, so a
/// model lit by a rig placed from the camera is lit alike from every side.
#[must_use]
pub fn turntable_lights(lights: &[Light], target: Vec3, frame: u32, frames: u32) -> Vec<Light> {
    assert!(frames > 0, "a turntable has at least one frame");
    let angle = f64::from(frame % frames) / f64::from(frames) * std::f64::consts::TAU;
    let turn = Affine3A::from_translation(target)
        * Affine3A::from_rotation_y(angle as f32)
        * Affine3A::from_translation(-target);
    lights.iter().map(|l| Light { kind: l.kind.transformed(&turn), ..l.clone() }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> Camera {
        Camera {
            eye: Vec3::new(0.0, 1.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            near: 0.1,
            far: 100.0,
            projection: Projection::Perspective { fov_y_deg: 40.0 },
            shift: glam::Vec2::ZERO,
        }
    }

    fn key(frame: u32, x: f32, fov: f32) -> Key {
        Key { frame, eye: Vec3::new(x, 1.0, 5.0), target: Vec3::new(x, 0.0, 0.0), fov_deg: fov }
    }

    fn path(interpolation: Interpolation) -> CameraPath {
        CameraPath { frames: 40, keys: vec![key(0, 0.0, 30.0), key(10, 2.0, 40.0), key(30, 3.0, 40.0)], interpolation }
    }

    #[test]
    fn both_interpolations_pass_through_every_key_and_hold_past_the_ends() {
        for interpolation in [Interpolation::Linear, Interpolation::CatmullRom] {
            let p = path(interpolation);
            for k in &p.keys {
                let c = p.camera_at(k.frame, &base());
                assert!(c.eye.abs_diff_eq(k.eye, 1e-6) && c.target.abs_diff_eq(k.target, 1e-6), "{k:?}");
                assert_eq!(c.projection, Projection::Perspective { fov_y_deg: k.fov_deg });
            }
            assert_eq!(p.camera_at(39, &base()).eye, p.keys[2].eye);
        }
    }

    #[test]
    fn linear_paths_move_at_constant_speed_between_keys() {
        let p = path(Interpolation::Linear);
        let c = p.camera_at(5, &base());
        assert!(c.eye.abs_diff_eq(Vec3::new(1.0, 1.0, 5.0), 1e-6), "{c:?}");
        assert_eq!(c.projection, Projection::Perspective { fov_y_deg: 35.0 });
    }

    #[test]
    fn catmull_rom_paths_have_no_corner_at_a_key() {
        let p = path(Interpolation::CatmullRom);
        let x = |f: f32| {
            // Between frames, through the same function at a fractional frame.
            let keys = &p.keys;
            let i = if f < 10.0 { 0 } else { 1 };
            let s = (f - keys[i].frame as f32) / (keys[i + 1].frame - keys[i].frame) as f32;
            hermite(keys, i, s, |k| k.eye).x
        };
        let (before, after) = ((x(10.0) - x(9.99)) / 0.01, (x(10.01) - x(10.0)) / 0.01);
        assert!((before - after).abs() < 1e-2, "speed {before} then {after} through key 1");
        // The slope from key 0 to key 2 (3 over 30 frames), where the linear
        // path has a corner: 0.2 per frame, then 0.05.
        assert!((before - 0.1).abs() < 1e-3, "{before}: the slope between the keys either side");
    }

    #[test]
    fn a_turntable_keeps_distance_and_height_and_comes_round() {
        let c = base();
        for i in 0..12 {
            let t = turntable(&c, i, 12);
            assert!(((t.eye - t.target).length() - (c.eye - c.target).length()).abs() < 1e-5);
            assert_eq!(t.eye.y, c.eye.y);
        }
        let quarter = turntable(&c, 3, 12);
        assert!(quarter.eye.abs_diff_eq(Vec3::new(5.0, 1.0, 0.0), 1e-5), "{:?}", quarter.eye);
        assert_eq!(turntable(&c, 12, 12).eye, turntable(&c, 0, 12).eye);
    }

    /// A light turned with the turntable keeps its place as the camera sees
    /// it: its position relative to the eye and target turns with them.
    #[test]
    fn turntable_lights_turn_with_the_camera() {
        use crate::scene::light::LightKind;
        let camera = base();
        let light = Light { kind: LightKind::Point { position: Vec3::new(3.0, 4.0, 2.0) }, ..Light::default() };
        for frame in 0..8 {
            let eye = turntable(&camera, frame, 8).eye;
            let turned = turntable_lights(std::slice::from_ref(&light), camera.target, frame, 8);
            let LightKind::Point { position } = turned[0].kind else { panic!("a point light stays one") };
            assert!((position.distance(eye) - Vec3::new(3.0, 4.0, 2.0).distance(camera.eye)).abs() < 1e-4);
            assert!((position.length() - Vec3::new(3.0, 4.0, 2.0).length()).abs() < 1e-4);
        }
    }
}
