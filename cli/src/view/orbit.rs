//! The viewer's camera: an eye orbiting a target point, moved by the mouse
//! (orbit, pan, zoom), framed on the scene (F), put at the standard views (1
//! front, 3 right, 7 top, 9 isometric) and switched between perspective and
//! orthographic (5) as Blender and f3d put them on the number keys.

use glam::{Vec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::scene::framing::{self, fit_depth, framed_camera, View};

/// Degrees the view turns per pixel the mouse is dragged.
pub const DEGREES_PER_PIXEL: f32 = 0.4;
/// How much nearer one wheel step brings the eye (a share of its distance).
pub const ZOOM_STEP: f32 = 0.1;

/// An eye at `distance` from `target`, seen from `view`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// The point the eye looks at and turns about.
    pub target: Vec3,
    /// Distance from the target to the eye.
    pub distance: f32,
    /// Where the eye is, about the target.
    pub view: View,
    /// Vertical field of view in degrees, for the perspective lens.
    pub fov_y_deg: f32,
    /// Orthographic (the view's height at the target kept) instead of
    /// perspective.
    pub orthographic: bool,
}

impl Orbit {
    /// The orbit that gives `camera` (its up taken as +y).
    #[must_use]
    pub fn from_camera(camera: &Camera) -> Orbit {
        let offset = camera.eye - camera.target;
        let distance = offset.length().max(1e-6);
        let dir = offset / distance;
        let view = View {
            azimuth_deg: dir.x.atan2(dir.z).to_degrees(),
            elevation_deg: dir.y.clamp(-1.0, 1.0).asin().to_degrees(),
        };
        let (fov_y_deg, orthographic) = match camera.projection {
            Projection::Perspective { fov_y_deg } => (fov_y_deg, false),
            Projection::Orthographic { height } => ((0.5 * height / distance).atan().to_degrees() * 2.0, true),
        };
        Orbit { target: camera.target, distance, view, fov_y_deg, orthographic }
    }

    /// The camera of this orbit, its near and far planes fitted to `bounds`.
    #[must_use]
    pub fn camera(&self, bounds: (Vec3, Vec3)) -> Camera {
        let dir = self.view.direction();
        let projection = if self.orthographic {
            Projection::Orthographic { height: 2.0 * self.distance * (self.fov_y_deg.to_radians() * 0.5).tan() }
        } else {
            Projection::Perspective { fov_y_deg: self.fov_y_deg }
        };
        let camera = Camera {
            eye: self.target + dir * self.distance,
            target: self.target,
            up: up_for(self.view),
            near: 1.0,
            far: 2.0,
            projection,
            shift: Vec2::ZERO,
        };
        // An orthographic eye is pulled back (the image does not change) so
        // nothing in the bounds lies behind it.
        let (c, r) = ((bounds.0 + bounds.1) * 0.5, (bounds.1 - bounds.0).length() * 0.5);
        let camera = if self.orthographic {
            let back = ((c - self.target).length() + r + self.distance).max(self.distance);
            Camera { eye: self.target + dir * back, ..camera }
        } else {
            camera
        };
        fit_depth(camera, bounds)
    }

    /// Turns the eye about the target by a mouse drag of `dx`, `dy` pixels
    /// (right turns the scene to the right; up looks from higher), the
    /// elevation kept within ±89.9°.
    pub fn rotate(&mut self, dx: f32, dy: f32) {
        self.view.azimuth_deg = wrap_degrees(self.view.azimuth_deg - dx * DEGREES_PER_PIXEL);
        self.view.elevation_deg = (self.view.elevation_deg + dy * DEGREES_PER_PIXEL).clamp(-89.9, 89.9);
    }

    /// Moves the target (and the eye with it) across the view by a drag of
    /// `dx`, `dy` pixels in an image `height` pixels high: the point under
    /// the mouse at the target's depth stays under it.
    pub fn pan(&mut self, dx: f32, dy: f32, height: u32) {
        let world_per_pixel = 2.0 * self.distance * (self.fov_y_deg.to_radians() * 0.5).tan() / height.max(1) as f32;
        let forward = -self.view.direction();
        let right = forward.cross(up_for(self.view)).normalize_or(Vec3::X);
        let up = right.cross(forward);
        self.target += (-dx * right + dy * up) * world_per_pixel;
    }

    /// Brings the eye nearer by `steps` wheel steps (negative: farther).
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * (1.0 - ZOOM_STEP).powf(steps)).clamp(1e-4, 1e7);
    }

    /// Frames `bounds` from the current view in an image `aspect` wide for
    /// its height.
    pub fn frame(&mut self, bounds: (Vec3, Vec3), aspect: f32) {
        let framed = framed_camera(bounds, aspect, self.view, self.fov_y_deg);
        self.target = framed.target;
        self.distance = (framed.eye - framed.target).length();
    }

    /// Puts the eye at `view`, framing `bounds`.
    pub fn look_from(&mut self, view: View, bounds: (Vec3, Vec3), aspect: f32) {
        self.view = view;
        self.frame(bounds, aspect);
    }

    /// Switches between the perspective and the orthographic lens (the same
    /// height seen at the target).
    pub fn toggle_projection(&mut self) {
        self.orthographic = !self.orthographic;
    }
}

/// Degrees in (−180, 180].
fn wrap_degrees(d: f32) -> f32 {
    let w = d.rem_euclid(360.0);
    if w > 180.0 {
        w - 360.0
    } else {
        w
    }
}

/// The up direction of a camera looking from `view`.
fn up_for(view: View) -> Vec3 {
    framing::up_for(view.direction(), view)
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNIT: (Vec3, Vec3) = (Vec3::splat(-1.0), Vec3::ONE);

    fn orbit() -> Orbit {
        Orbit { target: Vec3::ZERO, distance: 10.0, view: View::FRONT, fov_y_deg: 40.0, orthographic: false }
    }

    /// A camera comes back from its orbit: eye, target and lens.
    #[test]
    fn an_orbit_gives_back_the_camera_it_was_taken_from() {
        for view in
            [View::FRONT, View::RIGHT, View::ISO, View::DEFAULT, View { azimuth_deg: -120.0, elevation_deg: -30.0 }]
        {
            let camera = framed_camera(UNIT, 1.5, view, 35.0);
            let again = Orbit::from_camera(&camera).camera(UNIT);
            assert!((again.eye - camera.eye).length() < 1e-4, "{view:?}: {} against {}", again.eye, camera.eye);
            assert!((again.target - camera.target).length() < 1e-5);
            assert_eq!(again.projection, camera.projection);
        }
    }

    /// Dragging right turns the eye to the left of the scene (the scene
    /// turns right); dragging up raises it; 900 pixels up stops short of the
    /// pole; a full turn comes back.
    #[test]
    fn dragging_turns_the_eye_about_the_target() {
        let mut o = orbit();
        o.rotate(100.0, 0.0);
        assert!(o.camera(UNIT).eye.x < 0.0, "{}", o.camera(UNIT).eye);
        assert!((o.camera(UNIT).eye.length() - 10.0).abs() < 1e-4, "the distance is kept");
        o.rotate(0.0, 50.0);
        assert!(o.camera(UNIT).eye.y > 0.0);
        o.rotate(0.0, 900.0);
        assert!(o.view.elevation_deg < 90.0 && o.camera(UNIT).eye.y < 10.0);
        let mut turn = orbit();
        turn.rotate(360.0 / DEGREES_PER_PIXEL, 0.0);
        assert!((turn.camera(UNIT).eye - orbit().camera(UNIT).eye).length() < 1e-3);
    }

    /// Panning keeps the point under the mouse under it: the target moves
    /// one pixel's world size per pixel dragged, across the view.
    #[test]
    fn panning_moves_the_target_across_the_view() {
        let mut o = orbit();
        o.pan(100.0, 0.0, 500);
        let per_pixel = 2.0 * 10.0 * 20f32.to_radians().tan() / 500.0;
        assert!((o.target - Vec3::new(-100.0 * per_pixel, 0.0, 0.0)).length() < 1e-4, "{}", o.target);
        o.pan(0.0, 100.0, 500);
        assert!((o.target.y - 100.0 * per_pixel).abs() < 1e-4);
        assert_eq!(o.distance, 10.0);
    }

    /// A wheel step in and one out come back; the eye never reaches the target.
    #[test]
    fn zooming_scales_the_distance() {
        let mut o = orbit();
        o.zoom(3.0);
        assert!((o.distance - 10.0 * 0.9f32.powi(3)).abs() < 1e-4);
        o.zoom(-3.0);
        assert!((o.distance - 10.0).abs() < 1e-4);
        o.zoom(10_000.0);
        assert!(o.distance > 0.0);
    }

    /// The standard views look from where their names say, framing the
    /// bounds; the orthographic lens shows the same height at the target.
    #[test]
    fn standard_views_and_the_orthographic_lens() {
        let mut o = orbit();
        for (view, from) in [(View::FRONT, Vec3::Z), (View::RIGHT, Vec3::X), (View::TOP, Vec3::Y)] {
            o.look_from(view, UNIT, 1.0);
            let c = o.camera(UNIT);
            assert!((c.eye - c.target).normalize().dot(from) > 0.9999, "{view:?}");
            assert!(c.near < (c.eye - c.target).length() - 3f32.sqrt());
        }
        o.look_from(View::ISO, UNIT, 1.0);
        let iso = (o.camera(UNIT).eye - o.target).normalize();
        assert!((iso.x - iso.y).abs() < 1e-4 && (iso.y - iso.z).abs() < 1e-4, "{iso}");
        o.toggle_projection();
        let c = o.camera(UNIT);
        let Projection::Orthographic { height } = c.projection else { panic!("orthographic") };
        assert!((height - 2.0 * o.distance * 20f32.to_radians().tan()).abs() < 1e-4);
        assert!(c.near > 0.0 && (c.eye - c.target).length() - c.near > 3f32.sqrt(), "nothing behind the eye");
        o.toggle_projection();
        assert!(matches!(o.camera(UNIT).projection, Projection::Perspective { .. }));
    }
}
