//! The TOML scene format (documented key by key in `docs/scene-format.md`).
//!
//! Parsing happens in two steps, as in pbrt-v4: the text becomes plain records that
//! remember where each value came from ([`SceneFile`]), then [`SceneFile::build`]
//! loads meshes and textures and produces a [`Scene`]. Both steps report errors at
//! the file, line and column of the value at fault.

use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, EulerRot, Quat, Vec3};
use serde::Deserialize;
use toml::Spanned;

use super::load::{self, AssetSource, LoadedModel};
use super::mesh::shapes;
use super::{
    box_corners, framing, Body, Environment, Falloff, HardShadows, Light, LightKind, Material, Object, PenumbraFalloff,
    PenumbraPoints, Scene, ShadowMethod, ShadowSettings, Texture, Up,
};
use crate::camera::{Camera, Projection};
use crate::csg::openscad::{CsgOptions, Geometry};
use crate::error::{Error, Result, SourceLocation};
use crate::image::ToneCurve;
use crate::limits::{Limit, LimitSetting, Limits};
use crate::scene::camera_path::{CameraPath, Interpolation, Key};
use crate::scene::material::Filter;
use crate::scene::settings::{
    AmbientOcclusion, Antialias, EdgeFilter, EdgeMode, EdgeSelection, Exposure, FeatureLines, Fog, FogMode,
    TranslucencyOrder, MAX_JITTER_SAMPLES,
};
use crate::scene::texture::Wrap;

mod values;

type V3 = [f32; 3];

/// A parsed scene file: plain records with source spans.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(default)]
    image: ImageRec,
    camera: Option<Spanned<CameraRec>>,
    path: Option<Spanned<PathRec>>,
    #[serde(default, rename = "light")]
    lights: Vec<Spanned<LightRec>>,
    #[serde(default, rename = "material")]
    materials: Vec<Spanned<MaterialRec>>,
    #[serde(default, rename = "object")]
    objects: Vec<Spanned<ObjectRec>>,
    fog: Option<Spanned<FogRec>>,
    ambient_occlusion: Option<Spanned<OcclusionRec>>,
    lines: Option<Spanned<LinesRec>>,
    section: Option<Spanned<SectionRec>>,
    environment: Option<Spanned<EnvironmentRec>>,
    /// `[limits]`: limit name → value.
    #[serde(default)]
    limits: BTreeMap<Spanned<String>, Spanned<i64>>,
    #[serde(skip)]
    origin: Option<Origin>,
}

#[derive(Debug, Clone)]
struct Origin {
    path: PathBuf,
    text: Arc<str>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ImageRec {
    #[serde(default = "default_width")]
    width: Spanned<i64>,
    #[serde(default = "default_height")]
    height: Spanned<i64>,
    #[serde(default = "default_background")]
    background: Spanned<V3>,
    #[serde(default = "default_exposure")]
    exposure: Spanned<ExposureRec>,
    antialias: Option<Spanned<AntialiasRec>>,
    #[serde(default)]
    translucency: TranslucencyRec,
    #[serde(default)]
    tonemap: ToneRec,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum ToneRec {
    None,
    #[default]
    Neutral,
    Agx,
    Aces,
}

impl From<ToneRec> for ToneCurve {
    fn from(r: ToneRec) -> Self {
        match r {
            ToneRec::None => ToneCurve::Clip,
            ToneRec::Neutral => ToneCurve::Neutral,
            ToneRec::Agx => ToneCurve::Agx,
            ToneRec::Aces => ToneCurve::Aces,
        }
    }
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum TranslucencyRec {
    #[default]
    Sorted,
    Unsorted,
}

impl From<TranslucencyRec> for TranslucencyOrder {
    fn from(r: TranslucencyRec) -> Self {
        match r {
            TranslucencyRec::Sorted => TranslucencyOrder::Sorted,
            TranslucencyRec::Unsorted => TranslucencyOrder::Unsorted,
        }
    }
}

/// `[fog]`: `mode` linear (`start`, `end`), exp or exp2 (`density`), `color`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FogRec {
    mode: FogModeRec,
    #[serde(default = "fog_color")]
    color: V3,
    start: Option<f32>,
    end: Option<f32>,
    density: Option<f32>,
}

/// `[ambient_occlusion]`: `radius` (world units; default from the model's
/// size), `rays` a point (default 16), `screen_space` (default false).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct OcclusionRec {
    radius: Option<f32>,
    rays: Option<i64>,
    screen_space: Option<bool>,
}

/// `[lines]`: feature lines' `width` (pixels, default 1.5), `color`
/// (linear RGB, default near-black), `hidden` (dashed hidden lines, default
/// false) and `crease` (degrees between two faces' normals that make a
/// crease, default 30).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LinesRec {
    width: Option<f32>,
    color: Option<V3>,
    hidden: Option<bool>,
    crease: Option<f32>,
}

/// `[section]`: the plane through `point` with `normal` (pointing into the
/// half removed).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SectionRec {
    point: V3,
    normal: V3,
}

fn fog_color() -> V3 {
    [0.7, 0.72, 0.75]
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
enum FogModeRec {
    Linear,
    Exp,
    Exp2,
}

/// `antialias = { method = "jitter", samples = 8 }`, `{ method = "edge" }` (with
/// `edges = "outline"` or `"all"`, `filter = "coverage"` or `"paper"`) or
/// `{ method = "none" }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AntialiasRec {
    method: Spanned<String>,
    samples: Option<Spanned<i64>>,
    edges: Option<Spanned<String>>,
    filter: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq)]
#[serde(untagged)]
enum ExposureRec {
    Stops(f32),
    Word(AutoWord),
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
enum AutoWord {
    Auto,
}

impl Default for ExposureRec {
    fn default() -> Self {
        ExposureRec::Stops(0.0)
    }
}

impl From<ExposureRec> for Exposure {
    fn from(e: ExposureRec) -> Exposure {
        match e {
            ExposureRec::Stops(ev) => Exposure::Stops(ev),
            ExposureRec::Word(AutoWord::Auto) => Exposure::Auto,
        }
    }
}

fn default_width() -> Spanned<i64> {
    Spanned::new(0..0, 960)
}
fn default_height() -> Spanned<i64> {
    Spanned::new(0..0, 540)
}
fn default_background() -> Spanned<V3> {
    Spanned::new(0..0, [0.1, 0.1, 0.15])
}

fn default_exposure() -> Spanned<ExposureRec> {
    Spanned::new(0..0, ExposureRec::default())
}

impl Default for ImageRec {
    fn default() -> Self {
        ImageRec {
            width: default_width(),
            height: default_height(),
            background: default_background(),
            exposure: default_exposure(),
            antialias: None,
            translucency: TranslucencyRec::default(),
            tonemap: ToneRec::default(),
        }
    }
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum ProjectionRec {
    #[default]
    Perspective,
    Orthographic,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraRec {
    eye: V3,
    target: V3,
    #[serde(default = "up")]
    up: V3,
    #[serde(default = "fov")]
    fov: f32,
    #[serde(default = "near")]
    near: f32,
    #[serde(default = "far")]
    far: f32,
    #[serde(default)]
    projection: ProjectionRec,
    height: Option<f32>,
}

/// `[path]`: the camera over an animation's frames.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PathRec {
    frames: Spanned<i64>,
    #[serde(default)]
    interpolation: InterpolationRec,
    #[serde(rename = "key")]
    keys: Vec<Spanned<KeyRec>>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum InterpolationRec {
    Linear,
    #[default]
    CatmullRom,
}

/// `[[path.key]]`: what a key leaves out it keeps from the key before (the
/// first: from `[camera]`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyRec {
    frame: i64,
    eye: Option<V3>,
    target: Option<V3>,
    fov: Option<f32>,
}

fn up() -> V3 {
    [0.0, 1.0, 0.0]
}
fn fov() -> f32 {
    45.0
}
fn near() -> f32 {
    0.1
}
fn far() -> f32 {
    1000.0
}
fn one() -> f32 {
    1.0
}
fn white() -> V3 {
    [1.0; 3]
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
enum LightType {
    Point,
    Spot,
    Directional,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum FalloffRec {
    #[default]
    None,
    InverseSquare,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LightRec {
    #[serde(rename = "type")]
    kind: LightType,
    position: Option<V3>,
    direction: Option<V3>,
    target: Option<V3>,
    #[serde(default = "white")]
    color: V3,
    #[serde(default = "one")]
    intensity: f32,
    #[serde(default)]
    ambient: f32,
    #[serde(default)]
    size: f32,
    #[serde(default = "inner")]
    inner_angle: f32,
    #[serde(default = "outer")]
    outer_angle: f32,
    #[serde(default)]
    falloff: FalloffRec,
    shadow: Option<Spanned<ShadowRec>>,
    only: Option<Vec<Spanned<String>>>,
}

/// `shadow = { method = "map", resolution = 2048, bias = 1.0, slope = 1.5, pcf = 1 }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ShadowRec {
    method: Option<Spanned<String>>,
    resolution: Option<Spanned<i64>>,
    bias: Option<f32>,
    slope: Option<f32>,
    pcf: Option<Spanned<i64>>,
    samples: Option<Spanned<i64>>,
    bits: Option<Spanned<i64>>,
    scale: Option<Spanned<f32>>,
    antialias: Option<bool>,
    focus: Option<V3>,
    search: Option<Spanned<i64>>,
    falloff: Option<PenumbraRec>,
    depth_aware: Option<bool>,
    half: Option<bool>,
    hard: Option<HardRec>,
    points: Option<PointsRec>,
    blockers: Option<Spanned<i64>>,
    filter: Option<Spanned<i64>>,
}

/// `falloff = "linear" | "smooth"` of a two-map penumbra.
#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
enum PenumbraRec {
    Linear,
    Smooth,
}

/// `points = "paper" | "matched" | "ring"`: where a two-map soft shadow's points lie.
#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
enum PointsRec {
    Paper,
    Matched,
    Ring,
}

/// `hard = "map" | "slb"`: the hard shadows of a two-map soft shadow.
#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
enum HardRec {
    Map,
    Slb,
}

fn inner() -> f32 {
    25.0
}
fn outer() -> f32 {
    30.0
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialRec {
    name: Spanned<String>,
    ka: Option<V3>,
    #[serde(default = "grey")]
    kd: V3,
    #[serde(default = "ks")]
    ks: V3,
    #[serde(default = "shininess")]
    shininess: f32,
    #[serde(default)]
    ke: V3,
    ka_map: Option<MapsRec>,
    kd_map: Option<MapsRec>,
    ks_map: Option<MapsRec>,
    ke_map: Option<MapsRec>,
    #[serde(default)]
    two_sided: bool,
    #[serde(default)]
    kr: V3,
    #[serde(default)]
    kt: V3,
    ior: Option<Spanned<f32>>,
    #[serde(default)]
    km: V3,
    opacity: Option<Spanned<f32>>,
    #[serde(default)]
    filter: FilterRec,
    #[serde(default)]
    wrap: WrapRec,
}

/// One texture path, or a list of them (one added pass each).
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum MapsRec {
    One(String),
    Many(Vec<String>),
}

impl MapsRec {
    fn paths(&self) -> &[String] {
        match self {
            MapsRec::One(p) => std::slice::from_ref(p),
            MapsRec::Many(v) => v,
        }
    }
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum FilterRec {
    #[default]
    Trilinear,
    Bilinear,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum WrapRec {
    #[default]
    Repeat,
    Clamp,
    Mirror,
}

/// `[environment]`: an equirectangular image around the scene.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentRec {
    map: Spanned<String>,
    #[serde(default = "one")]
    intensity: f32,
    #[serde(default)]
    rotate: f32,
    #[serde(default = "yes")]
    background: bool,
}

fn yes() -> bool {
    true
}

fn grey() -> V3 {
    [0.8; 3]
}
fn ks() -> V3 {
    [0.2; 3]
}
/// Every component of `c` is a finite number ≥ 0.
fn finite_non_negative(c: glam::Vec3) -> bool {
    c.is_finite() && c.min_element() >= 0.0
}

fn shininess() -> f32 {
    32.0
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Hash)]
#[serde(rename_all = "kebab-case")]
enum ShapeRec {
    Plane,
    Cube,
    Sphere,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum GeometryRec {
    #[default]
    Exact,
    Faceted,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
enum UpRec {
    Y,
    Z,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum ScaleRec {
    Uniform(f32),
    Axes(V3),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectRec {
    name: Option<String>,
    mesh: Option<Spanned<String>>,
    shape: Option<ShapeRec>,
    material: Option<Spanned<String>>,
    #[serde(default)]
    translate: V3,
    #[serde(default)]
    rotate: V3,
    scale: Option<ScaleRec>,
    fit: Option<Spanned<f32>>,
    /// The model's up axis, when not its format's ([`LoadedModel::up`]).
    up: Option<UpRec>,
    /// A `.csg` model's spheres and cylinders.
    #[serde(default)]
    geometry: GeometryRec,
    /// A `.csg` model: skip nodes kage cannot render, with a warning.
    #[serde(default)]
    skip_unsupported: bool,
    /// Whether it is drawn into shadow maps ([`Object::casts_shadows`]).
    #[serde(default = "yes")]
    casts_shadows: bool,
}

impl SceneFile {
    /// Parses scene text. `path` is used for messages and to resolve relative files.
    ///
    /// # Errors
    ///
    /// [`Error::SceneSyntax`] for text that is not TOML or does not match the
    /// scene format, located at the offending characters.
    pub fn parse(text: &str, path: &Path) -> Result<SceneFile> {
        let shared: Arc<str> = Arc::from(text);
        let mut file: SceneFile = toml::from_str(text).map_err(|e| Error::SceneSyntax {
            location: Box::new(SourceLocation::new(path, shared.clone(), e.span().unwrap_or(0..0))),
            message: e.message().trim().to_string(),
        })?;
        file.origin = Some(Origin { path: path.to_path_buf(), text: shared });
        Ok(file)
    }

    fn invalid(&self, span: Range<usize>, message: impl Into<String>) -> Error {
        let origin = self.origin.clone().unwrap_or(Origin { path: "<scene>".into(), text: Arc::from("") });
        Error::SceneInvalid {
            location: Box::new(SourceLocation::new(origin.path, origin.text, span)),
            message: message.into(),
        }
    }

    /// Loads every mesh and texture and builds the scene, within the file's
    /// `[limits]`.
    ///
    /// # Errors
    ///
    /// As [`SceneFile::build_with`].
    pub fn build(&self, assets: &dyn AssetSource) -> Result<Scene> {
        self.build_with(assets, &[])
    }

    /// The limits this file sets in `[limits]`, over the defaults.
    ///
    /// # Errors
    ///
    /// [`Error::SceneInvalid`] at an unknown limit or a value below 0.
    pub fn limits(&self) -> Result<Limits> {
        let mut limits = Limits::default();
        for (name, value) in &self.limits {
            let limit = Limit::named(name.get_ref()).map_err(|e| self.invalid(name.span(), e))?;
            let v = u64::try_from(*value.get_ref())
                .map_err(|_| self.invalid(value.span(), "a limit is a whole number ≥ 0"))?;
            limits.set(limit, v);
        }
        Ok(limits)
    }

    /// Loads every mesh and texture and builds the scene, within the file's
    /// `[limits]` with `overrides` (the command line's) applied over them.
    ///
    /// # Errors
    ///
    /// [`Error::SceneInvalid`] for impossible values (located in the file), and
    /// whatever loading a named mesh, model or texture fails with (a request
    /// past a limit among them).
    pub fn build_with(&self, assets: &dyn AssetSource, overrides: &[LimitSetting]) -> Result<Scene> {
        let from = Sources::new(assets, self.limits()?.with_settings(overrides));
        let (w, h) = (&self.image.width, &self.image.height);
        for side in [w, h] {
            if *side.get_ref() < 1 || *side.get_ref() > super::MAX_IMAGE_SIDE as i64 {
                return Err(self.invalid(side.span(), "image sides must be between 1 and 16384 pixels"));
            }
        }
        let mut materials = Vec::new();
        let mut by_name = HashMap::new();
        for m in &self.materials {
            let mat = self.material(m.get_ref(), &from)?;
            if !(mat.shininess.is_finite() && mat.shininess >= 0.0) {
                return Err(self.invalid(m.span(), format!("shininess must be finite and ≥ 0, not {}", mat.shininess)));
            }
            let colours =
                [("kd", mat.kd), ("ka", mat.ka), ("ks", mat.ks), ("ke", mat.ke), ("kr", mat.kr), ("kt", mat.kt)];
            if let Some((name, c)) = colours.into_iter().chain([("km", mat.km)]).find(|(_, c)| !finite_non_negative(*c))
            {
                let msg = format!("material '{}': `{name}` must be finite and ≥ 0, not {c}", mat.name);
                return Err(self.invalid(m.span(), msg));
            }
            if by_name.insert(mat.name.clone(), materials.len()).is_some() {
                return Err(self.invalid(m.get_ref().name.span(), format!("material '{}' is defined twice", mat.name)));
            }
            materials.push(mat);
        }
        let mut scene = Scene {
            width: *w.get_ref() as u32,
            height: *h.get_ref() as u32,
            background: self.background()?,
            camera: framing((Vec3::ZERO, Vec3::ONE), 1.0).0,
            lights: self.lights.iter().map(|l| self.light(l)).collect::<Result<_>>()?,
            lights_follow_camera: false,
            materials,
            objects: Vec::new(),
            warnings: Vec::new(),
            exposure: self.exposure()?,
            tone: self.image.tonemap.into(),
            antialias: self.antialias()?,
            fog: self.fog()?,
            ambient_occlusion: self.ambient_occlusion()?,
            lines: self.lines()?,
            environment: self.environment(&from)?,
            translucency: self.image.translucency.into(),
            limits: from.limits,
            camera_path: None,
        };
        for (rec, light) in self.lights.iter().zip(&scene.lights) {
            if let Some(shadow) = &rec.get_ref().shadow {
                scene.warnings.extend(self.shadow_key_warnings(shadow, &light.shadow));
            }
        }
        let mut models = Vec::new();
        let mut produced = Vec::new();
        let mut triangles = 0;
        for o in &self.objects {
            let first = scene.objects.len();
            models.push(self.object(o, &by_name, &from, &mut scene)?);
            let added = scene.objects[first..].iter().filter_map(Object::triangles);
            triangles += added.map(|m| m.triangles.len() as u64).sum::<u64>();
            let what = || format!("the objects up to this one ({})", scene.objects.len());
            from.limits.check(Limit::Triangles, triangles, what).map_err(|e| self.invalid(o.span(), e.to_string()))?;
            produced.push((o.get_ref().name.clone(), first..scene.objects.len()));
        }
        self.resolve_only(&mut scene, &produced)?;
        if scene.objects.is_empty() {
            return Err(self.invalid(0..0, "the scene has no [[object]]: there is nothing to draw"));
        }
        if let Some(rec) = &self.section {
            let r = rec.get_ref();
            let plane = super::section::SectionPlane::through(Vec3::from(r.point), Vec3::from(r.normal));
            let plane = plane
                .ok_or_else(|| self.invalid(rec.span(), "section `point` must be finite and `normal` not zero"))?;
            scene.section(plane);
        }
        self.place_camera_and_lights(&mut scene, &models)?;
        scene.camera_path = self.camera_path(&scene.camera)?;
        scene.validate()?;
        Ok(scene)
    }

    /// `[path]`, its keys checked (frames rising, inside the path, every
    /// camera usable) and completed from the keys before them and `camera`.
    fn camera_path(&self, camera: &Camera) -> Result<Option<CameraPath>> {
        let Some(rec) = &self.path else { return Ok(None) };
        let frames = *rec.get_ref().frames.get_ref();
        if !(1..=1_000_000).contains(&frames) {
            return Err(self.invalid(rec.get_ref().frames.span(), "a path has 1 to 1000000 frames"));
        }
        if rec.get_ref().keys.is_empty() {
            return Err(self.invalid(rec.span(), "a path needs at least one [[path.key]]"));
        }
        let fov = match camera.projection {
            Projection::Perspective { fov_y_deg } => fov_y_deg,
            Projection::Orthographic { .. } => 0.0,
        };
        let mut last = Key { frame: 0, eye: camera.eye, target: camera.target, fov_deg: fov };
        let mut keys: Vec<Key> = Vec::new();
        for k in &rec.get_ref().keys {
            let r = k.get_ref();
            let after = keys.last().map_or(0, |l| i64::from(l.frame) + 1);
            if r.frame < after || r.frame >= frames {
                let msg = format!("key frames must rise, each from {after} to {} (the path's last frame)", frames - 1);
                return Err(self.invalid(k.span(), msg));
            }
            let key = Key {
                frame: r.frame as u32,
                eye: r.eye.map_or(last.eye, Vec3::from),
                target: r.target.map_or(last.target, Vec3::from),
                fov_deg: r.fov.unwrap_or(last.fov_deg),
            };
            let cam = Camera {
                eye: key.eye,
                target: key.target,
                projection: match camera.projection {
                    Projection::Perspective { .. } => Projection::Perspective { fov_y_deg: key.fov_deg },
                    p => p,
                },
                ..*camera
            };
            cam.validate().map_err(|m| self.invalid(k.span(), m))?;
            keys.push(key);
            last = key;
        }
        let interpolation = match rec.get_ref().interpolation {
            InterpolationRec::Linear => Interpolation::Linear,
            InterpolationRec::CatmullRom => Interpolation::CatmullRom,
        };
        Ok(Some(CameraPath { frames: frames as u32, keys, interpolation }))
    }

    fn place_camera_and_lights(&self, scene: &mut Scene, models: &[LoadedModel]) -> Result<()> {
        let aspect = scene.width as f32 / scene.height as f32;
        let Some(bounds) = scene.bounds() else {
            let span = self.objects.first().map_or(0..0, |o| o.span());
            return Err(self.invalid(
                span,
                "every object of the scene is empty (no volume, no triangles): there is nothing to draw",
            ));
        };
        let (auto_cam, auto_lights) = framing(bounds, aspect);
        let model_cam = models.iter().find_map(|m| m.camera);
        scene.camera = match &self.camera {
            Some(c) => self.camera(c)?,
            None => model_cam.unwrap_or(auto_cam),
        };
        if self.lights.is_empty() {
            let model_lights: Vec<Light> = models.iter().flat_map(|m| m.lights.iter().cloned()).collect();
            scene.lights = if model_lights.is_empty() { auto_lights } else { model_lights };
        }
        Ok(())
    }

    fn object(
        &self,
        o: &Spanned<ObjectRec>,
        by_name: &HashMap<String, usize>,
        from: &Sources,
        scene: &mut Scene,
    ) -> Result<LoadedModel> {
        let r = o.get_ref();
        let model = match (&r.mesh, r.shape) {
            (Some(path), None) => {
                let geometry = match r.geometry {
                    GeometryRec::Exact => Geometry::Exact,
                    GeometryRec::Faceted => Geometry::Faceted,
                };
                let csg = CsgOptions { geometry, skip_unsupported: r.skip_unsupported };
                load::model_with(Path::new(path.get_ref()), from.assets, &csg, &from.limits)?
            }
            (None, Some(shape)) => from.shape(shape),
            _ => return Err(self.invalid(o.span(), "an object needs exactly one of `mesh` (a file) or `shape`")),
        };
        let material = match &r.material {
            Some(name) => Some(*by_name.get(name.get_ref()).ok_or_else(|| {
                let known: Vec<&str> = self.materials.iter().map(|m| m.get_ref().name.get_ref().as_str()).collect();
                let known = if known.is_empty() {
                    "no [[material]] is defined".to_string()
                } else {
                    format!("defined: {}", known.join(", "))
                };
                self.invalid(name.span(), format!("no material named '{}' ({known})", name.get_ref()))
            })?),
            None => None,
        };
        let transform = self.transform(r, &model)?;
        if !transform.is_finite() {
            return Err(self.invalid(o.span(), "the object's translate, rotate, scale and fit must be finite"));
        }
        let label = r
            .name
            .clone()
            .or_else(|| r.mesh.as_ref().map(|m| m.get_ref().clone()))
            .unwrap_or_else(|| format!("{:?}", r.shape).to_lowercase());
        let first = scene.objects.len();
        add_model(scene, &model, &label, transform, material);
        scene.objects[first..].iter_mut().for_each(|o| o.casts_shadows = r.casts_shadows);
        let limit = super::MAX_COORDINATE;
        let out_of_range = scene.objects[first..]
            .iter()
            .filter_map(Object::world_bounds)
            .find(|(lo, hi)| !(lo.abs().max_element() <= limit && hi.abs().max_element() <= limit));
        if let Some((lo, hi)) = out_of_range {
            let msg = format!("the object reaches from {lo} to {hi}: every coordinate must lie within ±{limit:e}");
            return Err(self.invalid(o.span(), msg));
        }
        Ok(model)
    }

    fn transform(&self, r: &ObjectRec, model: &LoadedModel) -> Result<Affine3A> {
        let scale = match r.scale {
            None => Vec3::ONE,
            Some(ScaleRec::Uniform(s)) => Vec3::splat(s),
            Some(ScaleRec::Axes(a)) => a.into(),
        };
        let [rx, ry, rz] = r.rotate.map(f32::to_radians);
        let up = match r.up {
            Some(UpRec::Y) => Up::Y,
            Some(UpRec::Z) => Up::Z,
            None => model.up,
        };
        let turn = up.turn();
        let placed = Affine3A::from_scale_rotation_translation(
            scale,
            Quat::from_euler(EulerRot::ZYX, rz, ry, rx),
            r.translate.into(),
        );
        let Some(fit) = &r.fit else { return Ok(placed * turn) };
        let (lo, hi) = turned_bounds(model, &turn);
        let extent = (hi - lo).max_element();
        if fit.get_ref().is_nan() || *fit.get_ref() <= 0.0 || extent <= 0.0 {
            return Err(self.invalid(fit.span(), "`fit` must be > 0 and the mesh must have a non-zero extent"));
        }
        let s = fit.get_ref() / extent;
        let base = Vec3::new((lo.x + hi.x) * 0.5, lo.y, (lo.z + hi.z) * 0.5);
        Ok(placed * Affine3A::from_scale(Vec3::splat(s)) * Affine3A::from_translation(-base) * turn)
    }
}

/// Where a scene's files come from and what they may ask for; the textures
/// and shapes made so far, which every material or object naming them shares.
struct Sources<'a> {
    assets: &'a dyn AssetSource,
    limits: Limits,
    textures: RefCell<HashMap<(String, bool, Wrap), Arc<Texture>>>,
    shapes: RefCell<HashMap<ShapeRec, LoadedModel>>,
}

impl<'a> Sources<'a> {
    fn new(assets: &'a dyn AssetSource, limits: Limits) -> Sources<'a> {
        Sources { assets, limits, textures: RefCell::default(), shapes: RefCell::default() }
    }

    /// The texture at `path` (a colour map if `srgb`), wrapping as `wrap` says.
    fn texture(&self, path: &str, srgb: bool, wrap: Wrap) -> Result<Arc<Texture>> {
        let key = (path.to_string(), srgb, wrap);
        if let Some(done) = self.textures.borrow().get(&key) {
            return Ok(Arc::clone(done));
        }
        let mut t = load::texture(Path::new(path), srgb, self.assets, &self.limits)?;
        Arc::make_mut(&mut t).wrap = wrap;
        self.textures.borrow_mut().insert(key, Arc::clone(&t));
        Ok(t)
    }

    /// The built-in shape's model (one mesh, shared by every object of it).
    fn shape(&self, shape: ShapeRec) -> LoadedModel {
        let make = || {
            LoadedModel::single(match shape {
                ShapeRec::Plane => shapes::plane(),
                ShapeRec::Cube => shapes::cube(),
                ShapeRec::Sphere => shapes::sphere(48),
            })
        };
        self.shapes.borrow_mut().entry(shape).or_insert_with(make).clone()
    }
}

/// The bounds of `model` turned by `turn` (the box around its turned box).
fn turned_bounds(model: &LoadedModel, turn: &Affine3A) -> (Vec3, Vec3) {
    let corners = box_corners(model.bounds()).map(|c| turn.transform_point3(c));
    corners.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &c| (lo.min(c), hi.max(c)))
}

/// Adds every part of a loaded model to the scene as objects, with `material`
/// overriding the model's own materials when given.
pub fn add_model(scene: &mut Scene, model: &LoadedModel, label: &str, transform: Affine3A, material: Option<usize>) {
    scene.warnings.extend(model.warnings.iter().cloned());
    for part in &model.parts {
        let material = material.unwrap_or_else(|| {
            scene.materials.push(part.material.clone().unwrap_or_default());
            scene.materials.len() - 1
        });
        let name = if model.parts.len() > 1 { format!("{label}/{}", part.name) } else { label.to_string() };
        let object = Object::mesh(name, part.mesh.clone(), transform * part.transform, material);
        scene.objects.push(Object { casts_shadows: !part.ghost, ghost: part.ghost, ..object });
    }
    for part in &model.solids {
        let materials: Arc<[usize]> = match material {
            Some(m) => vec![m; part.materials.len()].into(),
            None => {
                let base = scene.materials.len();
                scene.materials.extend(part.palette.iter().cloned());
                part.materials.iter().map(|m| base + m).collect()
            }
        };
        // Objects need a material of their own even when no primitive shows one.
        let own = material.or(materials.first().copied()).unwrap_or_else(|| {
            scene.materials.push(Material::default());
            scene.materials.len() - 1
        });
        let name = if model.parts.len() + model.solids.len() > 1 {
            format!("{label}/{}", part.name)
        } else {
            label.to_string()
        };
        let body = Body::Solid { solid: Arc::clone(&part.solid), materials };
        scene.objects.push(Object { name, body, transform, material: own, casts_shadows: true, ghost: false });
    }
}

/// Reads and builds a scene file from disk.
///
/// # Errors
///
/// As [`load_scene_with`].
pub fn load_scene(path: &Path) -> Result<Scene> {
    load_scene_with(path, &[])
}

/// Reads and builds a scene file from disk, with `overrides` applied over
/// its `[limits]`.
///
/// # Errors
///
/// [`Error::Read`] when the file cannot be read, [`Error::Limit`] when it is
/// larger than [`Limit::FileMb`], [`Error::SceneSyntax`] when it is not UTF-8
/// text; then as [`SceneFile::parse`] and [`SceneFile::build_with`].
pub fn load_scene_with(path: &Path, overrides: &[LimitSetting]) -> Result<Scene> {
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let files = load::FileSystem { base };
    let name = Path::new(path.file_name().unwrap_or(path.as_os_str()));
    let bytes = load::read(name, &files, &Limits::default().with_settings(overrides))?;
    let text = String::from_utf8(bytes).map_err(|e| Error::SceneSyntax {
        location: Box::new(SourceLocation::new(path, Arc::from(""), 0..0)),
        message: format!("the file is not UTF-8 text (at byte {})", e.utf8_error().valid_up_to()),
    })?;
    SceneFile::parse(&text, path)?.build_with(&files, overrides)
}
