//! A lone model file as a scene: turned so its up axis is kage's +y, framed by
//! a camera, lit by a rig placed from that camera, standing on a ground that
//! catches its shadow.

use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Vec3};

use super::file::add_model;
use super::framing::{fit_depth, framed_camera, key_light, light_rig, CameraOverride, View, FRAMING_FOV_DEG};
use super::load;
use super::mesh::shapes;
use super::section::SectionPlane;
use super::{box_corners, Environment, Exposure, Light, Material, Object, Scene, ShadowSettings, Up};
use crate::bvh::{Aabb, Bvh};
use crate::camera::{Camera, Projection, Ray};
use crate::csg::openscad::CsgOptions;
use crate::error::{Error, Result};
use crate::limits::Limits;
use crate::triangle::ShearedRay;

/// A matte ground under `bounds` (kage's y-up world), four times their size,
/// unless the camera looks at it from below. It lies a thousandth of the
/// model's size below the model's lowest point, so it never coincides with a
/// face of the model (a card lying flat would fight it for every pixel).
fn add_ground(scene: &mut Scene, (lo, hi): (Vec3, Vec3)) {
    if scene.camera.eye.y <= lo.y {
        return;
    }
    let extent = (hi - lo).max_element().max(1e-3);
    let size = 4.0 * extent;
    let centre = Vec3::new((lo.x + hi.x) * 0.5, lo.y - GROUND_GAP * extent, (lo.z + hi.z) * 0.5);
    let placed = Affine3A::from_translation(centre) * Affine3A::from_scale(Vec3::splat(size));
    scene.materials.push(Material {
        name: "ground".into(),
        ka: Vec3::splat(0.6),
        kd: Vec3::splat(0.6),
        ks: Vec3::ZERO,
        ..Material::default()
    });
    let ground = Object::mesh("ground", Arc::new(shapes::plane()), placed, scene.materials.len() - 1);
    // It lies under the model: its shadows fall on nothing, and in the key
    // light's map it would widen the map fourfold around the model.
    scene.objects.push(Object { casts_shadows: false, ..ground });
}

/// How far below a model its ground lies, in parts of the model's size.
const GROUND_GAP: f32 = 1e-3;

/// The view that sees a flat model of `size` face-on: along the axis it is
/// flat along (thinner than a thousandth of its size), from the side its
/// faces face (`facing`, the sum of its triangles' area vectors); `None` for
/// a model that is not flat.
fn face_on(size: Vec3, facing: Vec3) -> Option<View> {
    let flat = |extent: f32| extent <= 1e-3 * size.max_element();
    let from = |toward: f32, front: View, back: View| if toward >= 0.0 { front } else { back };
    let below = View { azimuth_deg: 0.0, elevation_deg: -90.0 };
    let behind = View { azimuth_deg: 180.0, elevation_deg: 0.0 };
    let left = View { azimuth_deg: -90.0, elevation_deg: 0.0 };
    [
        (size.y, from(facing.y, View::TOP, below)),
        (size.z, from(facing.z, View::FRONT, behind)),
        (size.x, from(facing.x, View::RIGHT, left)),
    ]
    .into_iter()
    .find(|&(extent, _)| flat(extent))
    .map(|(_, view)| view)
}

/// The sum of the area vectors of `scene`'s triangles (which way its faces
/// face, on the whole).
fn facing(scene: &Scene) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for_each_triangle(scene, |[a, b, c]| sum += (b - a).cross(c - a));
    sum
}

/// Largest extent of a model along an axis that a camera frames: beyond it
/// the camera's depth range and the depth buffer's precision fail.
pub const MAX_MODEL_SIZE: f32 = super::MAX_COORDINATE;

/// How a lone model file becomes a scene ([`scene_for_model_with`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelOptions {
    /// How a `.csg` file is read.
    pub csg: CsgOptions,
    /// The model's up axis (`None`: its format's, [`load::LoadedModel::up`]).
    pub up: Option<Up>,
    /// Stand the model on a ground that catches its shadows.
    pub ground: bool,
    /// See the model through the file's own camera (a glTF camera, an
    /// OpenSCAD camera sidecar, else OpenSCAD's default view) rather than one
    /// that frames it.
    pub file_camera: bool,
    /// Changes to the camera (a view to frame the model from, an eye, a
    /// target, a field of view); the light rig follows the camera.
    pub camera: CameraOverride,
    /// What the model may ask for.
    pub limits: Limits,
    /// A section plane in the model file's own coordinates (before its up
    /// axis is turned): what lies beyond it is removed
    /// ([`Scene::section`]); the camera and lights still frame the whole
    /// model, and the ground is not cut.
    pub section: Option<SectionPlane>,
    /// A section plane across the model (as a viewer places one): its normal
    /// in the model file's coordinates, and where it crosses the model's box
    /// along that normal (0: the box's near end, 1: its far end).
    pub section_across: Option<(Vec3, f32)>,
}

impl Default for ModelOptions {
    fn default() -> Self {
        ModelOptions {
            csg: CsgOptions::default(),
            up: None,
            ground: true,
            file_camera: false,
            camera: CameraOverride::default(),
            limits: Limits::default(),
            section: None,
            section_across: None,
        }
    }
}

/// A scene showing one model file, framed automatically, on a ground.
///
/// # Errors
///
/// As [`scene_for_model_with`].
pub fn scene_for_model(path: &Path, width: u32, height: u32) -> Result<Scene> {
    scene_for_model_with(path, width, height, &ModelOptions::default())
}

/// A scene showing one model file as `options` say: turned so that its up
/// axis is kage's +y, seen by a camera that frames it (or the file's own),
/// lit by a key light and a dim fill (or the file's own lights), and standing
/// on a ground that catches its shadows (left out when the camera looks from
/// below it). A room or open box is seen through its open side instead, lit
/// from within, with no ground.
///
/// # Errors
///
/// What loading the model fails with ([`load::model_with`]), or
/// [`Error::Scene`] when it holds nothing to draw.
pub fn scene_for_model_with(path: &Path, width: u32, height: u32, options: &ModelOptions) -> Result<Scene> {
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let fs = load::FileSystem { base };
    let name = Path::new(path.file_name().unwrap_or(path.as_os_str()));
    let model = load::model_with(name, &fs, &options.csg, &options.limits)?;
    scene_for_loaded_model(&model, path, width, height, options)
}

/// [`scene_for_model_with`] for a model already loaded (from `path`, which
/// names it in messages and objects).
///
/// # Errors
///
/// [`Error::Scene`] when it holds nothing to draw or is too large to frame.
pub fn scene_for_loaded_model(
    model: &load::LoadedModel,
    path: &Path,
    width: u32,
    height: u32,
    options: &ModelOptions,
) -> Result<Scene> {
    let turn = options.up.unwrap_or(model.up).turn();
    let aspect = width as f32 / height as f32;
    let mut scene =
        Scene::new(width, height, framed_camera((Vec3::ZERO, Vec3::ONE), 1.0, View::DEFAULT, FRAMING_FOV_DEG));
    scene.limits = options.limits;
    add_model(&mut scene, model, &path.display().to_string(), turn, None);
    let bounds = scene.bounds().ok_or_else(|| Error::Scene(format!("{}: the model is empty", path.display())))?;
    let size = bounds.1 - bounds.0;
    if !(size.is_finite() && size.max_element() <= MAX_MODEL_SIZE) {
        let message = format!(
            "{}: the model spans {size:?}, too large to frame (at most {MAX_MODEL_SIZE:e} along an axis; its coordinates or transforms are out of range)",
            path.display()
        );
        return Err(Error::Scene(message));
    }
    let interior = Interior::of(&scene, bounds);
    let camera = match (model.camera.filter(|_| options.file_camera), &interior) {
        (Some(own), _) => own.transformed(&turn),
        (None, Some(inside)) => inside.camera(bounds, aspect),
        (None, None) => {
            let framed = |view| framed_camera(bounds, aspect, view, FRAMING_FOV_DEG);
            // Far from the origin a model may look flat only because its
            // coordinates lost their fractions: if a camera along the thin
            // axis is not usable there, the usual view.
            face_on(size, facing(&scene))
                .map(framed)
                .filter(|c| c.validate().is_ok())
                .unwrap_or_else(|| framed(View::DEFAULT))
        }
    };
    scene.camera = options.camera.apply(camera, bounds, aspect);
    let own_camera = model.camera.is_some() && options.file_camera;
    if let Some(note) = interior.as_ref().filter(|_| !own_camera && options.camera.is_empty()).and_then(Interior::note)
    {
        scene.warnings.push(format!("{}: {note}", path.display()));
    }
    let mut lights = light_rig(bounds, &scene.camera);
    if let Some(inside) = &interior {
        // Lit from within: by its glowing surfaces, else from under its top;
        // the rig's fill stays, from the camera's side.
        lights.splice(0..1, inside.lights(&mut scene, bounds));
    }
    if !model.solids.is_empty() {
        // Shadow maps of solids are drawn by the same scanline walk as the
        // view, texel by texel: the key light's four jittered maps at 512²,
        // fitted to the model alone (the ground casts nothing), so the model
        // spans the map (their average hides the coarser texels), and none
        // for the fill light, whose map fitted to the whole view would cost
        // more than the rest of the frame.
        lights[0].shadow.resolution = 512;
        lights.iter_mut().skip(1).for_each(|l| l.shadow = ShadowSettings::NONE);
    }
    if let Some(plane) = options.section {
        let normal = turn.transform_vector3(plane.normal);
        let world = SectionPlane::through(normal * plane.offset, normal).expect("a turn keeps a unit normal");
        scene.section(world);
    }
    if let Some((normal, at)) = options.section_across {
        let normal = turn.transform_vector3(normal);
        let ends = box_corners(bounds).map(|c| c.dot(normal.normalize_or_zero()));
        let (near, far) = ends.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &e| (a.min(e), b.max(e)));
        let point = normal.normalize_or_zero() * (near + at.clamp(0.0, 1.0) * (far - near));
        if let Some(world) = SectionPlane::through(point, normal) {
            scene.section(world);
        }
    }
    if options.ground && interior.is_none() {
        add_ground(&mut scene, bounds);
    }
    scene.lights_follow_camera = model.lights.is_empty();
    scene.lights = if model.lights.is_empty() {
        lights
    } else {
        model.lights.iter().map(|l| Light { kind: l.kind.transformed(&turn), ..l.clone() }).collect()
    };
    if scene.environment.is_none() && scene.materials.iter().any(Material::reflects_environment) {
        // Metals mirror their surroundings: without any, they would be black.
        scene.environment = Some(Environment::studio());
    }
    if !model.lights.is_empty() {
        // The file's lights are in physical units (candela, lux): expose for them.
        scene.exposure = Exposure::Auto;
    }
    scene.validate()?;
    Ok(scene)
}

/// A model that is a room: most of its surface faces inwards, and either one
/// side has no wall (a Cornell box, seen through that side, level) or it
/// encloses its own centre (a courtyard building, a town under a sky dome:
/// seen from inside, along its longer floor axis). Either needs no ground (it
/// has its floor) and is lit from inside.
struct Interior {
    /// Where the room is seen from.
    view: RoomView,
}

/// How a room is looked into.
#[derive(Debug, Clone, Copy, PartialEq)]
enum RoomView {
    /// Through the side with no wall (its outward direction).
    OpenSide(Vec3),
    /// From inside: from `eye` towards the bounds' centre.
    Enclosed { eye: Vec3 },
}

impl Interior {
    /// Share of the surface that must face the bounds' centre.
    const INWARD_SHARE: f32 = 0.6;

    /// `Some` when `scene`'s mesh objects within `bounds` make an interior.
    fn of(scene: &Scene, bounds: (Vec3, Vec3)) -> Option<Interior> {
        let (lo, hi) = bounds;
        let (centre, extent) = ((lo + hi) * 0.5, (hi - lo).max_element().max(f32::MIN_POSITIVE));
        // The four upright sides, by outward direction.
        let sides = [Vec3::Z, Vec3::X, Vec3::NEG_Z, Vec3::NEG_X];
        let (mut total, mut inward, mut walls) = (0.0, 0.0, [0.0f32; 4]);
        for_each_triangle(scene, |[a, b, c]| {
            let cross = (b - a).cross(c - a);
            let (area, n) = (cross.length() * 0.5, cross.normalize_or_zero());
            let mid = (a + b + c) / 3.0;
            total += area;
            inward += if n.dot(centre - mid) > 0.0 { area } else { 0.0 };
            for (k, out) in sides.iter().enumerate() {
                let face = if out.dot(Vec3::ONE) > 0.0 { hi.dot(*out) } else { lo.dot(*out) };
                if (mid.dot(*out) - face).abs() < 0.02 * extent && n.dot(*out).abs() > 0.9 {
                    walls[k] += area;
                }
            }
        });
        let most = walls.iter().copied().fold(0.0, f32::max);
        let (open, least) = walls.iter().copied().enumerate().min_by(|a, b| a.1.total_cmp(&b.1))?;
        if total > 0.0 && inward > Self::INWARD_SHARE * total && least < 0.1 * most {
            return Some(Interior { view: RoomView::OpenSide(sides[open]) });
        }
        let eye = Enclosure::around(scene, centre)?.eye(bounds)?;
        Some(Interior { view: RoomView::Enclosed { eye } })
    }

    /// What to say about the camera kage chose, when it is not the usual one.
    fn note(&self) -> Option<String> {
        match self.view {
            RoomView::OpenSide(_) => None,
            RoomView::Enclosed { .. } => Some(
                "the model encloses its centre (a room): framed from inside; --view or --eye to see it from outside"
                    .into(),
            ),
        }
    }

    /// A level camera outside the open side, looking at the centre, as far
    /// out as the opening needs to fill the view; or, enclosed, one inside
    /// looking level at the centre, with a wide lens.
    fn camera(&self, (lo, hi): (Vec3, Vec3), aspect: f32) -> Camera {
        let (centre, size) = ((lo + hi) * 0.5, hi - lo);
        let (eye, fov_y_deg) = match self.view {
            RoomView::OpenSide(open) => {
                let across = if open.x != 0.0 { size.z } else { size.x };
                let half = (FRAMING_FOV_DEG.to_radians() * 0.5).tan();
                let back = 1.05 * (size.y * 0.5 / half).max(across * 0.5 / (half * aspect));
                let depth = size.dot(open.abs());
                (centre + open * (depth * 0.5 + back), FRAMING_FOV_DEG)
            }
            RoomView::Enclosed { eye } => (eye, Enclosure::FOV_DEG),
        };
        let camera = Camera {
            eye,
            target: Vec3::new(centre.x, eye.y, centre.z),
            up: Vec3::Y,
            near: 1.0,
            far: 2.0,
            projection: Projection::Perspective { fov_y_deg },
            shift: glam::Vec2::ZERO,
        };
        fit_depth(camera, (lo, hi))
    }

    /// The lights inside: one soft light at each glowing surface (a material
    /// with emission), just off it, in its colour — those surfaces then cast
    /// no shadow of their own —; without any, one under the top's centre.
    fn lights(&self, scene: &mut Scene, (lo, hi): (Vec3, Vec3)) -> Vec<Light> {
        let extent = (hi - lo).max_element();
        let mut lights = Vec::new();
        for o in 0..scene.objects.len() {
            let ke = scene.materials[scene.objects[o].material].ke;
            if ke.max_element() <= 0.0 {
                continue;
            }
            let (mut area, mut centre, mut normal) = (0.0, Vec3::ZERO, Vec3::ZERO);
            for_each_triangle_of(&scene.objects[o], |[a, b, c]| {
                let cross = (b - a).cross(c - a);
                area += cross.length() * 0.5;
                centre += (a + b + c) / 3.0 * cross.length() * 0.5;
                normal += cross;
            });
            if area <= 0.0 {
                continue;
            }
            scene.objects[o].casts_shadows = false;
            // A sphere as wide as the surface, just clear of it: every point
            // of the light lies inside the room, so the shadow rays the
            // reference casts at it and the maps the raster renders from it
            // see the same light.
            let (normal, radius) = (normal.normalize_or(Vec3::NEG_Y), (area / std::f32::consts::PI).sqrt());
            lights.push(Light {
                color: ke / ke.max_element(),
                ..Self::key(centre / area + normal * (radius + 1e-3 * extent), radius)
            });
        }
        if lights.is_empty() {
            let top = Vec3::new((lo.x + hi.x) * 0.5, lo.y + 0.9 * (hi.y - lo.y), (lo.z + hi.z) * 0.5);
            lights.push(Self::key(top, 0.05 * extent));
        }
        let share = 1.0 / lights.len() as f32;
        lights.iter_mut().for_each(|l| (l.intensity, l.ambient) = (l.intensity * share, l.ambient * share));
        lights
    }

    /// A key light inside: the rig's, a little brighter (walls hold in what
    /// the fill from outside would add).
    fn key(position: Vec3, size: f32) -> Light {
        Light { intensity: 0.9, ..key_light(position, size) }
    }
}

/// The model's triangles behind a BVH, asked whether they surround a point.
struct Enclosure {
    triangles: Vec<[Vec3; 3]>,
    bvh: Bvh,
    centre: Vec3,
}

impl Enclosure {
    /// Azimuths of the directions round the centre that are tried, evenly
    /// spaced.
    const AZIMUTHS: u32 = 16;
    /// Their elevations: level, and 25° below and above.
    const ELEVATIONS_DEG: [f32; 3] = [-25.0, 0.0, 25.0];
    /// Share of those directions that must meet the model from its inside
    /// (a face turned towards the centre): a courtyard's arcades let a few
    /// through between columns.
    const ENCLOSED_SHARE: f32 = 0.9;
    /// The lens inside a room: wide, as a visitor sees it.
    const FOV_DEG: f32 = 60.0;

    /// `Some` when `scene`'s mesh objects surround `centre`: the usual
    /// camera's line to it meets a face turned towards it (a wall seen from
    /// inside — not the outside of a solid part round it, nor nothing, as
    /// for anything the usual camera sees into), and so does nearly every
    /// direction round it.
    fn around(scene: &Scene, centre: Vec3) -> Option<Enclosure> {
        let mut triangles = Vec::new();
        for_each_triangle(scene, |t| triangles.push(t));
        // One ray first, against every triangle: most models stop here.
        let towards_camera = Ray { origin: centre, dir: View::DEFAULT.direction() };
        let sheared = ShearedRay::new(&towards_camera);
        let first = triangles
            .iter()
            .filter_map(|t| Some((sheared.intersect(t, 0.0, f32::INFINITY)?.0, t)))
            .min_by(|a, b| a.0.total_cmp(&b.0))?;
        if !faces(first.1, towards_camera.dir) {
            return None;
        }
        let boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::around(t)).collect();
        let enclosure = Enclosure { bvh: Bvh::build(&boxes), triangles, centre };
        let directions = Self::ELEVATIONS_DEG.iter().flat_map(|&up| {
            (0..Self::AZIMUTHS)
                .map(move |k| View { azimuth_deg: k as f32 * 360.0 / Self::AZIMUTHS as f32, elevation_deg: up })
        });
        let (mut inward, mut all) = (0u32, 0u32);
        for view in directions {
            all += 1;
            inward += u32::from(enclosure.inward_hit(view.direction()).is_some());
        }
        (inward as f32 >= Self::ENCLOSED_SHARE * all as f32).then_some(enclosure)
    }

    /// Distance from the centre along unit `dir` to the first face, if that
    /// face is turned towards the centre.
    fn inward_hit(&self, dir: Vec3) -> Option<f32> {
        let ray = Ray { origin: self.centre, dir };
        let sheared = ShearedRay::new(&ray);
        let (i, t) = self.bvh.intersect(&ray, f32::INFINITY, |i, t_max| {
            sheared.intersect(&self.triangles[i as usize], 0.0, t_max).map(|h| h.0)
        })?;
        faces(&self.triangles[i as usize], dir).then_some(t)
    }

    /// An eye inside: back from the centre along the longer floor axis, most
    /// of the way to the wall there, at the centre's height.
    fn eye(&self, (lo, hi): (Vec3, Vec3)) -> Option<Vec3> {
        let size = hi - lo;
        let back = if size.x >= size.z { Vec3::NEG_X } else { Vec3::NEG_Z };
        let wall = self.inward_hit(back)?;
        Some(self.centre + back * 0.75 * wall)
    }
}

/// Whether triangle `[a, b, c]` turns its front (counter-clockwise) side
/// towards a ray along `dir`.
fn faces([a, b, c]: &[Vec3; 3], dir: Vec3) -> bool {
    (*b - *a).cross(*c - *a).dot(dir) < 0.0
}

/// Calls `f` with every triangle of `scene`'s mesh objects, in world space.
fn for_each_triangle(scene: &Scene, mut f: impl FnMut([Vec3; 3])) {
    scene.objects.iter().for_each(|o| for_each_triangle_of(o, &mut f));
}

/// Calls `f` with every triangle of mesh object `o`, in world space.
fn for_each_triangle_of(o: &Object, mut f: impl FnMut([Vec3; 3])) {
    let Some(mesh) = o.triangles() else { return };
    for t in &mesh.triangles {
        f(t.map(|i| o.transform.transform_point3(mesh.positions[i as usize])));
    }
}
