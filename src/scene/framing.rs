//! Cameras and lights chosen for what is to be seen: a view that frames a
//! model's bounds from a named direction or an orbit angle, the command
//! line's camera overrides, and a light rig placed relative to the camera, so
//! that whatever side the camera looks from is lit.

use glam::Vec3;

use crate::camera::{Camera, Projection};
use crate::scene::{Falloff, Light, LightKind, ShadowSettings};

/// Where a framing camera looks from: degrees about the framed bounds'
/// centre. Azimuth turns about +y from the front (+z) towards the right
/// (+x); elevation rises from the horizon towards +y (negative: from below).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Degrees about +y, 0 in front (+z), 90 from the right (+x).
    pub azimuth_deg: f32,
    /// Degrees above the horizon, in [−90, 90].
    pub elevation_deg: f32,
}

impl View {
    /// From the front (+z), level.
    pub const FRONT: View = View { azimuth_deg: 0.0, elevation_deg: 0.0 };
    /// From the right (+x), level.
    pub const RIGHT: View = View { azimuth_deg: 90.0, elevation_deg: 0.0 };
    /// From straight above, front at the bottom of the image.
    pub const TOP: View = View { azimuth_deg: 0.0, elevation_deg: 90.0 };
    /// The isometric view: front-right, 35.26° up (each axis equally short).
    pub const ISO: View = View { azimuth_deg: 45.0, elevation_deg: 35.264_39 };
    /// The default: a little right of the front and a little above, as a
    /// product shot (24° round, 24° up).
    pub const DEFAULT: View = View { azimuth_deg: 24.23, elevation_deg: 24.43 };

    /// The unit vector from the centre towards the eye.
    #[must_use]
    pub fn direction(self) -> Vec3 {
        let (az, el) = (self.azimuth_deg.to_radians(), self.elevation_deg.to_radians());
        Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos())
    }
}

impl Default for View {
    fn default() -> Self {
        View::DEFAULT
    }
}

/// Vertical field of view of framing cameras, degrees.
pub const FRAMING_FOV_DEG: f32 = 40.0;

/// A perspective camera looking at the centre of `bounds` from `view`, far
/// enough that the bounding sphere fits the field of view `fov_y_deg` (both
/// ways, for an image `aspect` wide for its height).
#[must_use]
pub fn framed_camera(bounds: (Vec3, Vec3), aspect: f32, view: View, fov_y_deg: f32) -> Camera {
    let (c, r) = sphere(bounds);
    let half_v = fov_y_deg.to_radians() * 0.5;
    let half = half_v.min((half_v.tan() * aspect).atan());
    let dist = 1.05 * r / half.sin();
    let dir = view.direction();
    let camera = Camera {
        eye: c + dist * dir,
        target: c,
        up: up_for(dir, view),
        near: 1.0,
        far: 2.0,
        projection: Projection::Perspective { fov_y_deg },
        shift: glam::Vec2::ZERO,
    };
    fit_depth(camera, bounds)
}

/// The up direction of a camera looking from `view` (`dir`, its
/// [`View::direction`]): +y, or for a view from straight above or below
/// (where +y is the view axis) the direction the view's azimuth turns away
/// from.
#[must_use]
pub fn up_for(dir: Vec3, view: View) -> Vec3 {
    if dir.cross(Vec3::Y).length_squared() > 1e-6 {
        Vec3::Y
    } else {
        let az = view.azimuth_deg.to_radians();
        -Vec3::new(az.sin(), 0.0, az.cos()) * dir.y.signum()
    }
}

/// `camera` with its near and far planes around `bounds` as seen from its
/// eye (the near plane halfway to the bounding sphere, a little in front of
/// the eye when the eye is inside it).
#[must_use]
pub fn fit_depth(camera: Camera, bounds: (Vec3, Vec3)) -> Camera {
    let (c, r) = sphere(bounds);
    let dist = (c - camera.eye).length().max(1e-3 * r);
    Camera { near: (dist - r).max(dist * 1e-3).max(1e-4 * r) * 0.5, far: (dist + r) * 2.0, ..camera }
}

fn sphere((lo, hi): (Vec3, Vec3)) -> (Vec3, f32) {
    ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-3))
}

/// Camera changes asked for on top of a scene's own or framed camera: a view
/// to frame the model from, then an eye, target or field of view.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CameraOverride {
    /// Frame the bounds from this view.
    pub view: Option<View>,
    /// Put the eye here.
    pub eye: Option<Vec3>,
    /// Look at this point.
    pub target: Option<Vec3>,
    /// Vertical field of view, degrees (makes the camera perspective).
    pub fov_deg: Option<f32>,
}

impl CameraOverride {
    /// Whether it changes anything.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        *self == CameraOverride::default()
    }

    /// `camera` changed as asked, for a model within `bounds` seen in an image
    /// `aspect` wide for its height; the near and far planes follow the eye.
    #[must_use]
    pub fn apply(&self, camera: Camera, bounds: (Vec3, Vec3), aspect: f32) -> Camera {
        if self.is_empty() {
            return camera;
        }
        let fov = self.fov_deg.unwrap_or(match camera.projection {
            Projection::Perspective { fov_y_deg } => fov_y_deg,
            Projection::Orthographic { .. } => FRAMING_FOV_DEG,
        });
        let mut camera = match self.view {
            Some(view) => framed_camera(bounds, aspect, view, fov),
            None => camera,
        };
        if self.fov_deg.is_some() {
            camera.projection = Projection::Perspective { fov_y_deg: fov };
        }
        camera.eye = self.eye.unwrap_or(camera.eye);
        camera.target = self.target.unwrap_or(camera.target);
        let dir = camera.eye - camera.target;
        if dir.normalize_or_zero().cross(camera.up).length_squared() <= 1e-6 {
            camera.up =
                if dir.cross(Vec3::Y).length_squared() > 1e-6 * dir.length_squared() { Vec3::Y } else { -Vec3::Z };
        }
        fit_depth(camera, bounds)
    }
}

/// The default rig for a model within `bounds` seen by `camera`: a white key
/// light up and to the right of the camera (below it when the camera looks
/// from below), carrying the ambient term and four jittered shadow maps, and a
/// cool unshadowed fill from the camera's left, so the faces the key does not
/// reach still read.
#[must_use]
pub fn light_rig(bounds: (Vec3, Vec3), camera: &Camera) -> Vec<Light> {
    let (c, r) = sphere(bounds);
    let to_eye = camera.eye - c;
    let azimuth = to_eye.x.atan2(to_eye.z).to_degrees();
    let below = to_eye.y < 0.0;
    let side = |turn: f32, up: f32| {
        View { azimuth_deg: azimuth + turn, elevation_deg: if below { -up } else { up } }.direction()
    };
    let key = key_light(c + 3.56 * r * side(27.0, 57.0), 0.05 * r);
    let fill = Light {
        kind: LightKind::Directional { direction: -side(-70.0, 15.0) },
        color: Vec3::new(0.75, 0.8, 1.0),
        intensity: 0.3,
        ambient: 0.0,
        size: 0.0,
        falloff: Falloff::None,
        shadow: ShadowSettings::NONE,
        ..Light::default()
    };
    vec![key, fill]
}

/// The rig's key light at `position` with radius `size`: white, carrying the
/// ambient term, its soft shadow from four jittered maps (soft enough for a
/// small light, quick to preview).
#[must_use]
pub fn key_light(position: Vec3, size: f32) -> Light {
    Light {
        kind: LightKind::Point { position },
        color: Vec3::ONE,
        intensity: 0.85,
        ambient: 0.12,
        size,
        falloff: Falloff::None,
        shadow: ShadowSettings { samples: 4, ..ShadowSettings::default() },
        ..Light::default()
    }
}

/// A camera and lights that show everything inside `bounds`: the camera
/// frames them from [`View::DEFAULT`], lit by [`light_rig`].
#[must_use]
pub fn framing(bounds: (Vec3, Vec3), aspect: f32) -> (Camera, Vec<Light>) {
    let camera = framed_camera(bounds, aspect, View::DEFAULT, FRAMING_FOV_DEG);
    let lights = light_rig(bounds, &camera);
    (camera, lights)
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNIT: (Vec3, Vec3) = (Vec3::splat(-1.0), Vec3::splat(1.0));

    #[test]
    fn named_views_look_from_where_they_say() {
        let from = |v: View| (framed_camera(UNIT, 1.0, v, 40.0).eye).normalize();
        assert!(from(View::FRONT).abs_diff_eq(Vec3::Z, 1e-5));
        assert!(from(View::RIGHT).abs_diff_eq(Vec3::X, 1e-5));
        assert!(from(View::TOP).abs_diff_eq(Vec3::Y, 1e-5));
        assert!(from(View::ISO).abs_diff_eq(Vec3::ONE.normalize(), 1e-5));
        let top = framed_camera(UNIT, 1.0, View::TOP, 40.0);
        assert!(top.validate().is_ok(), "a view from straight above has an up vector");
        assert!(top.up.abs_diff_eq(-Vec3::Z, 1e-6), "front at the bottom: {}", top.up);
    }

    #[test]
    fn a_framed_camera_keeps_the_bounds_in_view_and_between_its_planes() {
        for view in [View::FRONT, View::ISO, View::DEFAULT, View { azimuth_deg: 200.0, elevation_deg: -40.0 }] {
            for aspect in [0.5, 1.0, 2.0] {
                let cam = framed_camera(UNIT, aspect, view, 40.0);
                let clip = cam.view_projection(aspect);
                for i in 0..8 {
                    let corner = Vec3::new([-1.0, 1.0][i & 1], [-1.0, 1.0][i >> 1 & 1], [-1.0, 1.0][i >> 2 & 1]);
                    let p = clip * corner.extend(1.0);
                    let ndc = p.truncate() / p.w;
                    assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0, "{view:?} {aspect}: {corner} at {ndc}");
                    let d = (corner - cam.eye).length();
                    assert!(cam.near < d && d < cam.far, "{view:?}: {corner} outside the depth range");
                }
            }
        }
    }

    #[test]
    fn the_key_light_is_on_the_cameras_side_of_the_model() {
        for view in [View::DEFAULT, View::RIGHT, View { azimuth_deg: 150.0, elevation_deg: -35.0 }] {
            let cam = framed_camera(UNIT, 1.0, view, 40.0);
            let rig = light_rig(UNIT, &cam);
            let LightKind::Point { position } = rig[0].kind else { panic!("a point key") };
            assert!(position.dot(cam.eye) > 0.0, "{view:?}: the key lights the far side");
            assert_eq!(position.y < 0.0, cam.eye.y < 0.0, "{view:?}: key and camera on one side of the horizon");
            let LightKind::Directional { direction } = rig[1].kind else { panic!("a directional fill") };
            assert!(direction.dot(cam.eye) < 0.0, "{view:?}: the fill shines towards the model's seen side");
        }
    }

    #[test]
    fn overrides_move_the_eye_and_follow_it_with_the_planes() {
        let cam = framed_camera(UNIT, 1.0, View::DEFAULT, 40.0);
        let moved =
            CameraOverride { eye: Some(Vec3::new(0.0, 0.0, 30.0)), ..CameraOverride::default() }.apply(cam, UNIT, 1.0);
        assert_eq!(moved.eye, Vec3::new(0.0, 0.0, 30.0));
        assert!(moved.near < 30.0 - 3f32.sqrt() && moved.far > 30.0 + 3f32.sqrt());
        let above =
            CameraOverride { eye: Some(Vec3::new(0.0, 9.0, 0.0)), ..CameraOverride::default() }.apply(cam, UNIT, 1.0);
        assert!(above.validate().is_ok(), "looking straight down gets an up vector");
        let wide = CameraOverride { fov_deg: Some(70.0), ..CameraOverride::default() }.apply(cam, UNIT, 1.0);
        assert_eq!(wide.projection, Projection::Perspective { fov_y_deg: 70.0 });
        assert_eq!(CameraOverride::default().apply(cam, UNIT, 1.0), cam);
    }
}
