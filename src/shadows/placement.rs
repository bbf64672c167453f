//! Where a light's shadow maps go: a spot light sees its cone through one
//! perspective map, a point light through one cone holding the casters (or,
//! among them, a cube of six 90° maps), a directional light through one
//! orthographic map fitted to the part of the scene the camera sees; and how
//! many texels each map gets. Every map-based method places its maps here
//! ([`place_maps`]).

use glam::{Vec2, Vec3};
use wide::f32x8;

use super::{DepthMap, MapPool};
use crate::camera::{Camera, Projection};
use crate::scene::{Light, LightKind, Scene, ShadowSettings};
use crate::visibility::VisibilityBuffer;

/// A light's maps as placed: one, or six round a point (+x, −x, +y, −y, +z,
/// −z).
#[derive(Debug)]
pub enum Maps<M> {
    /// One map (spot, directional, a point light outside the casters).
    One(Box<M>),
    /// Six maps round the point, each at half the configured resolution.
    Cube(Box<[M; 6]>, Vec3),
}

impl<M> Maps<M> {
    /// Every map.
    #[must_use]
    pub fn faces(&self) -> &[M] {
        match self {
            Maps::One(map) => std::slice::from_ref(map.as_ref()),
            Maps::Cube(faces, _) => faces.as_slice(),
        }
    }

    /// Every map, to change.
    pub fn faces_mut(&mut self) -> &mut [M] {
        match self {
            Maps::One(map) => std::slice::from_mut(map.as_mut()),
            Maps::Cube(faces, _) => faces.as_mut_slice(),
        }
    }

    /// The maps, given up.
    #[must_use]
    pub fn into_faces(self) -> Vec<M> {
        match self {
            Maps::One(map) => vec![*map],
            Maps::Cube(faces, _) => Vec::from(*faces),
        }
    }

    /// The map world point `p` is looked up in.
    #[must_use]
    pub fn at(&self, p: Vec3) -> &M {
        match self {
            Maps::One(map) => map,
            Maps::Cube(faces, centre) => &faces[cube_face(p - *centre)],
        }
    }

    /// The map all eight points (x, y, z lanes) are looked up in, if they
    /// share one (neighbouring pixels usually do).
    #[must_use]
    pub fn at_lanes(&self, p: [f32x8; 3]) -> Option<&M> {
        match self {
            Maps::One(map) => Some(map),
            Maps::Cube(faces, centre) => same_cube_face(p, *centre).map(|f| &faces[f]),
        }
    }
}

impl Maps<DepthMap> {
    /// Bytes the depth maps hold.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.faces().iter().map(DepthMap::memory_bytes).sum()
    }

    /// The maps given up: the buffers they were drawn in.
    #[must_use]
    pub fn into_buffers(self) -> Vec<VisibilityBuffer> {
        self.into_faces().into_iter().map(DepthMap::into_buffer).collect()
    }
}

/// Places `light`'s maps over casters within `bounds` and draws each with
/// `draw(camera, resolution, pool)`, the resolution `None` for a cube face
/// that sees no caster. `scale` widens a cone's or a parallel map's view
/// that many times (seed 000's virtual projection space; 1: none). `None`
/// when the light casts no shadows.
pub fn place_maps<M>(
    scene: &Scene,
    light: &Light,
    bounds: (Vec3, Vec3),
    pool: &mut MapPool,
    scale: f32,
    mut draw: impl FnMut(Camera, Option<u32>, &mut MapPool) -> M,
) -> Option<Maps<M>> {
    let settings = &light.shadow;
    let view = *pool.view(scene);
    let (w, h) = (scene.width, scene.height);
    let resolution = |cam: &Camera, most: u32| map_resolution(settings, most, &view, (w, h), cam, bounds);
    // A cube's six faces take half the resolution: 1.5 single maps of memory.
    let (single, face) = (settings.resolution.max(1), (settings.resolution / 2).max(16));
    match placement(light, bounds) {
        Placement::None => None,
        Placement::Cone { eye, axis, fov_y_deg } => {
            let fov_y_deg = if scale == 1.0 {
                fov_y_deg
            } else {
                2.0 * ((fov_y_deg.to_radians() * 0.5).tan() * scale).atan().to_degrees().min(85.0)
            };
            let cam = light_camera(eye, axis, Projection::Perspective { fov_y_deg }, bounds);
            let res = resolution(&cam, single);
            Some(Maps::One(Box::new(draw(cam, Some(res), pool))))
        }
        Placement::Cube { eye } => {
            let faces = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z].map(|axis| {
                let cam = light_camera(eye, axis, Projection::Perspective { fov_y_deg: 90.0 }, bounds);
                let res = face_sees(eye, axis, bounds).then(|| resolution(&cam, face));
                draw(cam, res, pool)
            });
            Some(Maps::Cube(Box::new(faces), eye))
        }
        Placement::Parallel { direction } => {
            let aspect = w as f32 / h as f32;
            let mut cam = fitted_orthographic(&view, aspect, direction, bounds);
            if let Projection::Orthographic { height } = &mut cam.projection {
                *height *= scale;
            }
            let res = resolution(&cam, single);
            Some(Maps::One(Box::new(draw(cam, Some(res), pool))))
        }
    }
}

/// Texels `light`'s maps hold at most: `per_map(resolution)` bytes for each
/// map at the configured resolution, a cube's six at half of it.
#[must_use]
pub fn placed_bytes(light: &Light, bounds: (Vec3, Vec3), per_map: impl Fn(usize) -> usize) -> usize {
    let res = light.shadow.resolution.max(1) as usize;
    match placement(light, bounds) {
        Placement::None => 0,
        Placement::Cone { .. } | Placement::Parallel { .. } => per_map(res),
        Placement::Cube { .. } => 6 * per_map((res / 2).max(16)),
    }
}

/// Widest spot cone (half-angle, degrees) one perspective map covers; wider spots
/// use a cube like point lights.
const MAX_SPOT_HALF_ANGLE_DEG: f32 = 75.0;

/// How a light's shadow maps are placed.
pub(super) enum Placement {
    /// No shadows.
    None,
    /// One perspective map from `eye` along `axis`.
    Cone { eye: Vec3, axis: Vec3, fov_y_deg: f32 },
    /// Six 90° maps around `eye`.
    Cube { eye: Vec3 },
    /// One orthographic map fitted to the view.
    Parallel { direction: Vec3 },
}

/// A spot light sees through its own cone; a point light (or a spot wider than
/// one map can hold) outside the scene's bounding sphere sees the whole scene
/// through one cone just holding that sphere (the peers' placement), and needs a
/// cube only when it is among the objects.
pub(super) fn placement(light: &Light, bounds: (Vec3, Vec3)) -> Placement {
    if !light.casts_shadows() {
        return Placement::None;
    }
    let (centre, radius) = ((bounds.0 + bounds.1) * 0.5, (bounds.1 - bounds.0).length() * 0.5);
    match light.kind {
        LightKind::Spot { position, direction, outer, .. } if outer.to_degrees() <= MAX_SPOT_HALF_ANGLE_DEG => {
            Placement::Cone { eye: position, axis: direction, fov_y_deg: (2.0 * outer.to_degrees() + 2.0).min(170.0) }
        }
        LightKind::Point { position } | LightKind::Spot { position, .. } => {
            let to_centre = centre - position;
            let half = (radius / to_centre.length().max(f32::MIN_POSITIVE)).min(1.0).asin().to_degrees();
            if half + 1.0 <= MAX_SPOT_HALF_ANGLE_DEG {
                Placement::Cone { eye: position, axis: to_centre.normalize(), fov_y_deg: 2.0 * half + 2.0 }
            } else {
                Placement::Cube { eye: position }
            }
        }
        LightKind::Directional { direction } => Placement::Parallel { direction },
    }
}

/// The cube face every one of eight points (x, y, z lanes) lies in, seen
/// from `centre`, if they share one.
fn same_cube_face(p: [f32x8; 3], centre: Vec3) -> Option<usize> {
    let (x, y, z) = (p[0].to_array(), p[1].to_array(), p[2].to_array());
    let first = cube_face(Vec3::new(x[0], y[0], z[0]) - centre);
    (1..8).all(|i| cube_face(Vec3::new(x[i], y[i], z[i]) - centre) == first).then_some(first)
}

/// The cube face (+x, −x, +y, −y, +z, −z) that direction `d` from the centre
/// looks into.
fn cube_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        usize::from(d.x < 0.0)
    } else if a.y >= a.z {
        2 + usize::from(d.y < 0.0)
    } else {
        4 + usize::from(d.z < 0.0)
    }
}

/// Fewest texels a map chosen by need has along a side: below it a map costs
/// its triangles, hardly its texels, and a small image's soft shadows would
/// show the texels.
const MIN_NEEDED_RESOLUTION: u32 = 512;

/// Texels along a side of the map `light_cam` renders for a light with
/// `settings`, in a frame of `size` pixels seen through `view`, of casters
/// within `bounds`: `most` (the configured resolution; a cube face: half of
/// it), or by need at most that — two texels across a pixel at the casters' centre,
/// where their shadows fall (with one, shadow maps and shadow rays disagree on
/// 1.3% of the lit tests of the CAD example, against under 0.5%), half of one
/// for a soft light's jittered maps (their average hides the coarser texels), more
/// for a light low over the floor (whose texels the floor stretches); the
/// nearest power of two, so a camera moving a little keeps a kept map's size.
fn map_resolution(
    settings: &ShadowSettings,
    most: u32,
    view: &Camera,
    size: (u32, u32),
    light_cam: &Camera,
    bounds: (Vec3, Vec3),
) -> u32 {
    if !settings.by_need {
        return most;
    }
    let centre = (bounds.0 + bounds.1) * 0.5;
    let pixel = pixel_size(view, size, bounds);
    let covered = match light_cam.projection {
        Projection::Perspective { fov_y_deg } => {
            let along = (centre - light_cam.eye).length().max(light_cam.near);
            2.0 * along * (fov_y_deg.to_radians() * 0.5).tan()
        }
        Projection::Orthographic { height } => height,
    };
    let per_pixel = if settings.samples > 1 { 0.5 } else { 2.0 };
    // A light low over the floor stretches each texel along the floor by
    // 1 / sin(elevation): up to four times.
    let towards = match light_cam.projection {
        Projection::Perspective { .. } => (centre - light_cam.eye).normalize_or(Vec3::NEG_Y),
        Projection::Orthographic { .. } => (light_cam.target - light_cam.eye).normalize_or(Vec3::NEG_Y),
    };
    let stretch = 1.0 / towards.y.abs().max(0.25);
    let need = per_pixel * stretch * covered / pixel.max(f32::MIN_POSITIVE);
    if !need.is_finite() {
        return most;
    }
    // The nearest power of two: a texel between 0.7 and 1.4 pixels wide.
    let octave = need.max(1.0).log2().round().min(16.0) as u32;
    (1u32 << octave).clamp(MIN_NEEDED_RESOLUTION.min(most), most)
}

/// The world width of a pixel at the centre of `bounds`, seen through `view`
/// in a frame of `size` pixels.
pub(super) fn pixel_size(view: &Camera, size: (u32, u32), bounds: (Vec3, Vec3)) -> f32 {
    let centre = (bounds.0 + bounds.1) * 0.5;
    match view.projection {
        Projection::Perspective { fov_y_deg } => {
            let along = (centre - view.eye).dot((view.target - view.eye).normalize()).max(view.near);
            2.0 * along * (fov_y_deg.to_radians() * 0.5).tan() / size.1 as f32
        }
        Projection::Orthographic { height } => height / size.1 as f32,
    }
}

/// Whether the 90° pyramid of the cube face looking along `axis` from `eye`
/// holds any part of `bounds`: false when all eight corners lie outside one
/// of its four side planes.
fn face_sees(eye: Vec3, axis: Vec3, (lo, hi): (Vec3, Vec3)) -> bool {
    let side = [Vec3::X, Vec3::Y, Vec3::Z].into_iter().filter(|a| a.dot(axis).abs() < 0.5);
    let corners: Vec<Vec3> = (0..8)
        .map(|k| Vec3::new([lo.x, hi.x][k & 1], [lo.y, hi.y][(k >> 1) & 1], [lo.z, hi.z][(k >> 2) & 1]) - eye)
        .collect();
    // Inside: (axis · d) ≥ |s · d| for both side axes s.
    side.flat_map(|s| [s, -s]).all(|s| corners.iter().any(|&d| axis.dot(d) >= s.dot(d)))
}

/// A camera at `eye` looking along `axis` whose depth range holds `bounds`.
fn light_camera(eye: Vec3, axis: Vec3, projection: Projection, bounds: (Vec3, Vec3)) -> Camera {
    let (lo, hi) = bounds;
    let r = ((hi - lo).length() * 0.5).max(1e-6);
    let far = (eye - (lo + hi) * 0.5).length() + 2.0 * r;
    Camera {
        eye,
        target: eye + axis,
        up: up_for(axis),
        near: (r * 1e-4).min(far * 1e-3),
        far,
        projection,
        shift: Vec2::ZERO,
    }
}

/// An up vector not parallel to `axis`.
fn up_for(axis: Vec3) -> Vec3 {
    if axis.normalize().y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// The orthographic light camera of a directional light travelling along `dir`:
/// across the light, the intersection of the scene's bounds with what the eye sees
/// (its view frustum cut at the far side of the scene); along it, the whole scene,
/// so casters outside the view still cast into it.
fn fitted_orthographic(eye: &Camera, aspect: f32, dir: Vec3, bounds: (Vec3, Vec3)) -> Camera {
    let dir = dir.normalize();
    let up = up_for(dir);
    let right = dir.cross(up).normalize();
    let up = right.cross(dir);
    let to_light = |p: Vec3| Vec3::new(p.dot(right), p.dot(up), p.dot(dir));
    let (lo, hi) = bounds;
    let corners: Vec<Vec3> = (0..8)
        .map(|k| Vec3::new([lo.x, hi.x][k & 1], [lo.y, hi.y][(k >> 1) & 1], [lo.z, hi.z][(k >> 2) & 1]))
        .collect();
    let (mut slo, mut shi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &c in &corners {
        let l = to_light(c);
        (slo, shi) = (slo.min(l), shi.max(l));
    }
    // The eye's frustum, from its near plane to the farthest scene corner.
    let rays = eye.pixel_rays(Vec2::new(aspect, 1.0));
    let fwd = (eye.target - eye.eye).normalize();
    let reach = corners.iter().map(|&c| (c - eye.eye).dot(fwd)).fold(eye.near, f32::max).min(eye.far);
    let (mut flo, mut fhi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for (x, y) in [(0.0, 0.0), (aspect, 0.0), (0.0, 1.0), (aspect, 1.0)] {
        let ray = rays.ray(Vec2::new(x, y));
        let along = ray.dir.dot(fwd).max(1e-6);
        for t in [eye.near, reach] {
            let l = to_light(ray.origin + ray.dir * (t / along));
            (flo, fhi) = (flo.min(l), fhi.max(l));
        }
    }
    let (xy_lo, xy_hi) = (slo.truncate().max(flo.truncate()), shi.truncate().min(fhi.truncate()));
    let (xy_lo, xy_hi) = if xy_lo.cmple(xy_hi).all() { (xy_lo, xy_hi) } else { (slo.truncate(), shi.truncate()) };
    let size = (xy_hi - xy_lo).max_element().max(1e-6) * 1.02;
    let centre = (xy_lo + xy_hi) * 0.5;
    let margin = (shi.z - slo.z).max(1e-6) * 0.01 + 1e-6;
    let eye_pos = right * centre.x + up * centre.y + dir * (slo.z - margin);
    Camera {
        eye: eye_pos,
        target: eye_pos + dir,
        up,
        near: margin * 0.5,
        far: shi.z - slo.z + 2.0 * margin,
        projection: Projection::Orthographic { height: size },
        shift: Vec2::ZERO,
    }
}
