//! The TOML scene format (documented key by key in `docs/scene-format.md`).
//!
//! Parsing happens in two steps, as in pbrt-v4: the text becomes plain records that
//! remember where each value came from ([`SceneFile`]), then [`SceneFile::build`]
//! loads meshes and textures and produces a [`Scene`]. Both steps report errors at
//! the file, line and column of the value at fault.

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, EulerRot, Quat, Vec3};
use serde::Deserialize;
use toml::Spanned;

use super::load::{self, AssetSource, LoadedModel};
use super::mesh::shapes;
use super::{
    box_corners, framing, Body, Environment, Falloff, Light, LightKind, Material, Object, Scene, ShadowMethod,
    ShadowSettings, Texture, Up,
};
use crate::camera::{Camera, Projection};
use crate::csg::openscad::{CsgOptions, Geometry};
use crate::error::{Error, Result, SourceLocation};
use crate::image::ToneCurve;
use crate::scene::material::Filter;
use crate::scene::settings::{
    Antialias, EdgeFilter, EdgeMode, EdgeSelection, Exposure, Fog, FogMode, TranslucencyOrder, MAX_JITTER_SAMPLES,
};
use crate::scene::texture::Wrap;

type V3 = [f32; 3];

/// A parsed scene file: plain records with source spans.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(default)]
    image: ImageRec,
    camera: Option<Spanned<CameraRec>>,
    #[serde(default, rename = "light")]
    lights: Vec<Spanned<LightRec>>,
    #[serde(default, rename = "material")]
    materials: Vec<Spanned<MaterialRec>>,
    #[serde(default, rename = "object")]
    objects: Vec<Spanned<ObjectRec>>,
    fog: Option<Spanned<FogRec>>,
    environment: Option<Spanned<EnvironmentRec>>,
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
    #[serde(default)]
    method: ShadowMethodRec,
    resolution: Option<Spanned<i64>>,
    bias: Option<f32>,
    slope: Option<f32>,
    pcf: Option<Spanned<i64>>,
    samples: Option<Spanned<i64>>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum ShadowMethodRec {
    None,
    #[default]
    Map,
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
fn shininess() -> f32 {
    32.0
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
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

    fn environment(&self, assets: &dyn AssetSource) -> Result<Option<Environment>> {
        let Some(rec) = &self.environment else { return Ok(None) };
        let r = rec.get_ref();
        if !(r.intensity.is_finite() && r.intensity >= 0.0 && r.rotate.is_finite()) {
            return Err(self.invalid(rec.span(), "environment intensity must be finite and ≥ 0, rotate finite"));
        }
        // PNG and JPEG hold sRGB-encoded colours; EXR linear radiance (the loader knows).
        let map = load::texture(Path::new(r.map.get_ref()), true, assets)?;
        Ok(Some(Environment::new(map, r.intensity, r.rotate.to_radians(), r.background)))
    }

    fn fog(&self) -> Result<Option<Fog>> {
        let Some(rec) = &self.fog else { return Ok(None) };
        let r = rec.get_ref();
        let bad = |msg: &str| Err(self.invalid(rec.span(), msg.to_string()));
        let finite = |v: Option<f32>| v.is_none_or(|v| v.is_finite() && v >= 0.0);
        if !(finite(r.start)
            && finite(r.end)
            && finite(r.density)
            && r.color.iter().all(|c| c.is_finite() && *c >= 0.0))
        {
            return bad("fog distances, density and colour must be finite and ≥ 0");
        }
        let mode = match (r.mode, r.start, r.end, r.density) {
            (FogModeRec::Linear, start, Some(end), None) if end > start.unwrap_or(0.0) => {
                FogMode::Linear { start: start.unwrap_or(0.0), end }
            }
            (FogModeRec::Linear, ..) => return bad("linear fog needs `end` (> `start`, default 0) and no `density`"),
            (FogModeRec::Exp, None, None, Some(density)) => FogMode::Exp { density },
            (FogModeRec::Exp2, None, None, Some(density)) => FogMode::Exp2 { density },
            _ => return bad("exp and exp2 fog need `density` and no `start`/`end`"),
        };
        Ok(Some(Fog { mode, color: r.color.into() }))
    }

    fn antialias(&self) -> Result<Antialias> {
        let Some(rec) = &self.image.antialias else { return Ok(Antialias::default()) };
        let rec = rec.get_ref();
        let method = rec.method.get_ref().as_str();
        if method != "edge" {
            if let Some(key) = [&rec.edges, &rec.filter].into_iter().flatten().next() {
                return Err(self.invalid(key.span(), "`edges` and `filter` belong to method \"edge\""));
            }
        }
        let mut mode = EdgeMode::default();
        if let Some(e) = &rec.edges {
            mode.selection = match e.get_ref().as_str() {
                "outline" => EdgeSelection::Outline,
                "all" => EdgeSelection::All,
                other => {
                    return Err(
                        self.invalid(e.span(), format!("unknown edges '{other}' (expected \"outline\" or \"all\")"))
                    )
                }
            };
        }
        if let Some(f) = &rec.filter {
            mode.filter = match f.get_ref().as_str() {
                "coverage" => EdgeFilter::Coverage,
                "paper" => EdgeFilter::Paper,
                other => {
                    return Err(self
                        .invalid(f.span(), format!("unknown filter '{other}' (expected \"coverage\" or \"paper\")")))
                }
            };
        }
        match (method, &rec.samples) {
            ("none", None) => Ok(Antialias::None),
            ("none", Some(n)) => Err(self.invalid(n.span(), "method \"none\" takes no samples")),
            ("edge", None) => Ok(Antialias::Edge(mode)),
            ("edge", Some(n)) => Err(self.invalid(n.span(), "method \"edge\" takes no samples")),
            ("jitter", None) => Err(self.invalid(rec.method.span(), "method \"jitter\" needs `samples = n`")),
            ("jitter", Some(n)) => match u32::try_from(*n.get_ref()) {
                Ok(k @ 1..=MAX_JITTER_SAMPLES) => Ok(Antialias::Jitter(k)),
                _ => Err(self.invalid(n.span(), format!("samples must be between 1 and {MAX_JITTER_SAMPLES}"))),
            },
            (other, _) => Err(self.invalid(
                rec.method.span(),
                format!("unknown antialiasing method '{other}' (expected \"none\", \"edge\" or \"jitter\")"),
            )),
        }
    }

    /// Loads every mesh and texture and builds the scene.
    ///
    /// # Errors
    ///
    /// [`Error::SceneInvalid`] for impossible values (located in the file), and
    /// whatever loading a named mesh, model or texture fails with.
    pub fn build(&self, assets: &dyn AssetSource) -> Result<Scene> {
        let (w, h) = (&self.image.width, &self.image.height);
        for side in [w, h] {
            if *side.get_ref() < 1 || *side.get_ref() > super::MAX_IMAGE_SIDE as i64 {
                return Err(self.invalid(side.span(), "image sides must be between 1 and 16384 pixels"));
            }
        }
        let mut materials = Vec::new();
        let mut by_name = HashMap::new();
        for m in &self.materials {
            let mat = self.material(m.get_ref(), assets)?;
            if !(mat.shininess.is_finite() && mat.shininess >= 0.0) {
                return Err(self.invalid(m.span(), format!("shininess must be finite and ≥ 0, not {}", mat.shininess)));
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
            materials,
            objects: Vec::new(),
            warnings: Vec::new(),
            exposure: self.exposure()?,
            tone: self.image.tonemap.into(),
            antialias: self.antialias()?,
            fog: self.fog()?,
            environment: self.environment(assets)?,
            translucency: self.image.translucency.into(),
        };
        let mut models = Vec::new();
        let mut produced = Vec::new();
        for o in &self.objects {
            let first = scene.objects.len();
            models.push(self.object(o, &by_name, assets, &mut scene)?);
            produced.push((o.get_ref().name.clone(), first..scene.objects.len()));
        }
        self.resolve_only(&mut scene, &produced)?;
        if scene.objects.is_empty() {
            return Err(self.invalid(0..0, "the scene has no [[object]]: there is nothing to draw"));
        }
        self.place_camera_and_lights(&mut scene, &models)?;
        scene.validate()?;
        Ok(scene)
    }

    fn place_camera_and_lights(&self, scene: &mut Scene, models: &[LoadedModel]) -> Result<()> {
        let aspect = scene.width as f32 / scene.height as f32;
        let bounds = scene.bounds().expect("objects exist");
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

    fn camera(&self, c: &Spanned<CameraRec>) -> Result<Camera> {
        let r = c.get_ref();
        let projection = match r.projection {
            ProjectionRec::Perspective => Projection::Perspective { fov_y_deg: r.fov },
            ProjectionRec::Orthographic => {
                let height = r.height.ok_or_else(|| {
                    self.invalid(c.span(), "an orthographic camera needs `height` (world units shown top to bottom)")
                })?;
                Projection::Orthographic { height }
            }
        };
        let cam = Camera {
            eye: r.eye.into(),
            target: r.target.into(),
            up: r.up.into(),
            near: r.near,
            far: r.far,
            projection,
            shift: glam::Vec2::ZERO,
        };
        cam.validate().map_err(|m| self.invalid(c.span(), m))?;
        Ok(cam)
    }

    /// The background colour: finite and ≥ 0.
    fn background(&self) -> Result<Vec3> {
        let b = &self.image.background;
        let ok = b.get_ref().iter().all(|c| c.is_finite() && *c >= 0.0);
        ok.then(|| Vec3::from(*b.get_ref())).ok_or_else(|| self.invalid(b.span(), "background must be finite and ≥ 0"))
    }

    /// The exposure: a finite number of stops, or `auto`.
    fn exposure(&self) -> Result<Exposure> {
        let e = &self.image.exposure;
        match e.get_ref() {
            ExposureRec::Stops(ev) if !ev.is_finite() => {
                Err(self.invalid(e.span(), "exposure must be a finite number of stops or \"auto\""))
            }
            rec => Ok((*rec).into()),
        }
    }

    fn light(&self, l: &Spanned<LightRec>) -> Result<Light> {
        let r = l.get_ref();
        let need = |v: Option<V3>, key: &str| {
            v.map(Vec3::from)
                .ok_or_else(|| self.invalid(l.span(), format!("a {:?} light needs `{key}`", r.kind).to_lowercase()))
        };
        let aim = |from: Option<V3>| -> Result<Vec3> {
            let d = match (r.direction, r.target, from) {
                (Some(d), _, _) => Vec3::from(d),
                (None, Some(t), Some(p)) => Vec3::from(t) - Vec3::from(p),
                _ => return Err(self.invalid(l.span(), "this light needs `direction` (or `position` and `target`)")),
            };
            d.try_normalize().ok_or_else(|| self.invalid(l.span(), "the light direction has zero length"))
        };
        let kind = match r.kind {
            LightType::Point => LightKind::Point { position: need(r.position, "position")? },
            LightType::Directional => LightKind::Directional { direction: aim(r.position)? },
            LightType::Spot => LightKind::Spot {
                position: need(r.position, "position")?,
                direction: aim(r.position)?,
                inner: r.inner_angle.to_radians(),
                outer: r.outer_angle.to_radians(),
            },
        };
        let places = match kind {
            LightKind::Point { position } => [position, Vec3::ZERO],
            LightKind::Spot { position, direction, .. } => [position, direction],
            LightKind::Directional { direction } => [direction, Vec3::ZERO],
        };
        if !places.iter().all(|p| p.is_finite()) {
            return Err(self.invalid(l.span(), "light position, direction and target must be finite"));
        }
        if r.kind == LightType::Spot
            && !(0.0 <= r.inner_angle && r.inner_angle <= r.outer_angle && r.outer_angle <= 180.0)
        {
            return Err(self.invalid(l.span(), "spot angles must satisfy 0 ≤ inner_angle ≤ outer_angle ≤ 180"));
        }
        let values = [r.intensity, r.ambient, r.size, r.color[0], r.color[1], r.color[2]];
        if values.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return Err(self.invalid(l.span(), "light colour, intensity, ambient and size must be finite and ≥ 0"));
        }
        let falloff = match r.falloff {
            FalloffRec::None => Falloff::None,
            FalloffRec::InverseSquare => Falloff::InverseSquare,
        };
        Ok(Light {
            kind,
            color: r.color.into(),
            intensity: r.intensity,
            ambient: r.ambient,
            size: r.size,
            falloff,
            shadow: self.shadow(r.shadow.as_ref())?,
            only: None, // resolved once the objects exist
        })
    }

    fn shadow(&self, rec: Option<&Spanned<ShadowRec>>) -> Result<ShadowSettings> {
        let mut s = ShadowSettings::default();
        let Some(rec) = rec else { return Ok(s) };
        let r = rec.get_ref();
        s.method = match r.method {
            ShadowMethodRec::None => ShadowMethod::None,
            ShadowMethodRec::Map => ShadowMethod::Map,
        };
        let count = |v: &Option<Spanned<i64>>, lo: i64, hi: i64, what: &str| -> Result<Option<u32>> {
            match v {
                Some(n) if !(lo..=hi).contains(n.get_ref()) => {
                    Err(self.invalid(n.span(), format!("{what} must be between {lo} and {hi}")))
                }
                Some(n) => Ok(Some(*n.get_ref() as u32)),
                None => Ok(None),
            }
        };
        if let Some(n) = count(&r.resolution, 16, 16384, "shadow resolution")? {
            (s.resolution, s.by_need) = (n, false);
        }
        s.pcf = count(&r.pcf, 1, 15, "pcf")?.unwrap_or(s.pcf);
        s.samples = count(&r.samples, 1, 256, "shadow samples")?.unwrap_or(s.samples);
        for (v, slot) in [(r.bias, &mut s.bias), (r.slope, &mut s.slope)] {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(self.invalid(rec.span(), "shadow bias and slope must be finite and ≥ 0"));
                }
                *slot = v;
            }
        }
        Ok(s)
    }

    /// Turns each light's `only = [names]` into object indices: a name means every
    /// object its [[object]] record produced.
    fn resolve_only(&self, scene: &mut Scene, produced: &[(Option<String>, Range<usize>)]) -> Result<()> {
        for (light, rec) in scene.lights.iter_mut().zip(&self.lights) {
            let Some(names) = &rec.get_ref().only else { continue };
            let mut objects = Vec::new();
            for name in names {
                let hits: Vec<_> =
                    produced.iter().filter(|(n, _)| n.as_deref() == Some(name.get_ref().as_str())).collect();
                if hits.is_empty() {
                    let msg = format!("no [[object]] named '{}' for this light to light", name.get_ref());
                    return Err(self.invalid(name.span(), msg));
                }
                objects.extend(hits.into_iter().flat_map(|(_, r)| r.clone()));
            }
            light.only = Some(objects);
        }
        Ok(())
    }

    fn material(&self, r: &MaterialRec, assets: &dyn AssetSource) -> Result<Material> {
        let wrap = match r.wrap {
            WrapRec::Repeat => Wrap::Repeat,
            WrapRec::Clamp => Wrap::Clamp,
            WrapRec::Mirror => Wrap::Mirror,
        };
        let texture = |maps: &Option<MapsRec>, srgb: bool| -> Result<Vec<Arc<Texture>>> {
            let load = |p: &String| {
                let mut t = load::texture(Path::new(p), srgb, assets)?;
                Arc::make_mut(&mut t).wrap = wrap;
                Ok(t)
            };
            maps.as_ref().map_or(&[][..], MapsRec::paths).iter().map(load).collect()
        };
        Ok(Material {
            name: r.name.get_ref().clone(),
            ka: r.ka.unwrap_or(r.kd).into(),
            kd: r.kd.into(),
            ks: r.ks.into(),
            shininess: r.shininess,
            ke: r.ke.into(),
            maps: super::ComponentMaps {
                ambient: texture(&r.ka_map, true)?,
                diffuse: texture(&r.kd_map, true)?,
                specular: texture(&r.ks_map, true)?,
                emission: texture(&r.ke_map, true)?,
                normal: None,
                filter: match r.filter {
                    FilterRec::Trilinear => Filter::Trilinear,
                    FilterRec::Bilinear => Filter::Bilinear,
                },
            },
            two_sided: r.two_sided,
            kr: r.kr.into(),
            kt: r.kt.into(),
            km: r.km.into(),
            opacity: match &r.opacity {
                Some(a) if !(0.0..=1.0).contains(a.get_ref()) => {
                    return Err(self.invalid(a.span(), "opacity must be between 0 and 1"))
                }
                Some(a) => *a.get_ref(),
                None => 1.0,
            },
            ior: match &r.ior {
                Some(ior) if !(ior.get_ref().is_finite() && *ior.get_ref() >= 1.0) => {
                    return Err(self.invalid(ior.span(), "the index of refraction must be a finite number ≥ 1"))
                }
                Some(ior) => *ior.get_ref(),
                None => 1.5,
            },
        })
    }

    fn object(
        &self,
        o: &Spanned<ObjectRec>,
        by_name: &HashMap<String, usize>,
        assets: &dyn AssetSource,
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
                load::model_with(Path::new(path.get_ref()), assets, &csg)?
            }
            (None, Some(shape)) => LoadedModel::single(match shape {
                ShapeRec::Plane => shapes::plane(),
                ShapeRec::Cube => shapes::cube(),
                ShapeRec::Sphere => shapes::sphere(48),
            }),
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
        scene.objects.push(Object::mesh(name, part.mesh.clone(), transform * part.transform, material));
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
        scene.objects.push(Object { name, body, transform, material: own, casts_shadows: true });
    }
}

/// Reads and builds a scene file from disk.
///
/// # Errors
///
/// [`Error::Read`] when the file cannot be read; then as [`SceneFile::parse`]
/// and [`SceneFile::build`].
pub fn load_scene(path: &Path) -> Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Read { path: path.to_path_buf(), source })?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    SceneFile::parse(&text, path)?.build(&load::FileSystem { base })
}
