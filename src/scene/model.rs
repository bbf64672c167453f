//! A lone model file as a scene: turned so its up axis is kage's +y, framed by
//! a camera, lit by a rig placed from that camera, standing on a ground that
//! catches its shadow.

use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Vec3};

use super::file::add_model;
use super::framing::{framed_camera, light_rig, CameraOverride, View, FRAMING_FOV_DEG};
use super::load;
use super::mesh::shapes;
use super::{Environment, Exposure, Light, Material, Object, Scene, ShadowSettings, Up};
use crate::csg::openscad::CsgOptions;
use crate::error::{Error, Result};

/// A matte ground under `bounds` (kage's y-up world), four times their size,
/// unless the camera looks at it from below.
fn add_ground(scene: &mut Scene, (lo, hi): (Vec3, Vec3)) {
    if scene.camera.eye.y <= lo.y {
        return;
    }
    let size = 4.0 * (hi - lo).max_element().max(1e-3);
    let centre = Vec3::new((lo.x + hi.x) * 0.5, lo.y, (lo.z + hi.z) * 0.5);
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
}

impl Default for ModelOptions {
    fn default() -> Self {
        ModelOptions {
            csg: CsgOptions::default(),
            up: None,
            ground: true,
            file_camera: false,
            camera: CameraOverride::default(),
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
/// below it).
///
/// # Errors
///
/// What loading the model fails with ([`load::model_with`]), or
/// [`Error::Scene`] when it holds nothing to draw.
pub fn scene_for_model_with(path: &Path, width: u32, height: u32, options: &ModelOptions) -> Result<Scene> {
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let fs = load::FileSystem { base };
    let name = Path::new(path.file_name().unwrap_or(path.as_os_str()));
    let model = load::model_with(name, &fs, &options.csg)?;
    let turn = options.up.unwrap_or(model.up).turn();
    let aspect = width as f32 / height as f32;
    let mut scene =
        Scene::new(width, height, framed_camera((Vec3::ZERO, Vec3::ONE), 1.0, View::DEFAULT, FRAMING_FOV_DEG));
    add_model(&mut scene, &model, &path.display().to_string(), turn, None);
    let bounds = scene.bounds().ok_or_else(|| Error::Scene(format!("{}: the model is empty", path.display())))?;
    let camera = match model.camera.filter(|_| options.file_camera) {
        Some(own) => own.transformed(&turn),
        None => framed_camera(bounds, aspect, View::DEFAULT, FRAMING_FOV_DEG),
    };
    scene.camera = options.camera.apply(camera, bounds, aspect);
    let mut lights = light_rig(bounds, &scene.camera);
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
    if options.ground {
        add_ground(&mut scene, bounds);
    }
    scene.lights = if model.lights.is_empty() {
        lights
    } else {
        model.lights.iter().map(|l| Light { kind: l.kind.transformed(&turn), ..l.clone() }).collect()
    };
    if scene.environment.is_none() && scene.materials.iter().any(|m| m.km.max_element() > 0.0) {
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
