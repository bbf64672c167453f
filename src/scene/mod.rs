//! The scene: what is drawn (objects with meshes and materials), how it is lit and
//! from where it is seen. Scene files are parsed to plain records first
//! ([`mod@file`]), then meshes and textures are loaded ([`load`]) into this form.

pub mod camera_path;
pub mod demo;
pub mod environment;
pub mod file;
pub mod framing;
pub mod light;
pub mod load;
pub mod material;
pub mod mesh;
pub mod model;
pub mod section;
pub mod settings;
pub mod texture;

use std::sync::Arc;

use glam::{Affine3A, Vec3};

pub use environment::Environment;
pub use framing::framing;
pub use light::{
    Falloff, HardShadows, Light, LightKind, PenumbraFalloff, PenumbraPoints, ShadowMethod, ShadowSettings,
};
pub use material::{phong_exponent, ComponentMaps, Material, NormalMap};
pub use mesh::Mesh;
pub use settings::{
    AmbientOcclusion, Antialias, EdgeFilter, EdgeMode, EdgeSelection, Exposure, FeatureLines, Fog, FogMode,
    TranslucencyOrder, Up,
};
pub use texture::{SharedFootprint, Texture};

use crate::camera::Camera;
use crate::csg::CsgSolid;
use crate::error::{Error, Result};
use crate::image::ToneCurve;
use crate::limits::Limits;

/// Largest world coordinate (in magnitude) an object may reach: squared
/// distances of points this far still fit in an f32.
pub const MAX_COORDINATE: f32 = 1e15;

/// Largest image side kage accepts, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// Largest image kage accepts, in pixels (a 16k × 8k frame).
pub const MAX_IMAGE_PIXELS: u64 = 16_384 * 8_192;

/// What an object is made of.
#[derive(Debug, Clone)]
pub enum Body {
    /// A triangle mesh, drawn by the polygon pass.
    Mesh(Arc<Mesh>),
    /// A CSG solid (seed 003), drawn by the scanline walk of
    /// [`crate::visibility::solids`]; its pixels' item ids name the primitive.
    Solid {
        /// The solid, in object space.
        solid: Arc<CsgSolid>,
        /// Per primitive: index into [`Scene::materials`].
        materials: Arc<[usize]>,
    },
}

impl Body {
    /// Whether both are the same shared geometry (the same `Arc`; a solid's
    /// materials too).
    #[must_use]
    pub fn same(&self, other: &Body) -> bool {
        match (self, other) {
            (Body::Mesh(a), Body::Mesh(b)) => Arc::ptr_eq(a, b),
            (Body::Solid { solid: a, materials: m }, Body::Solid { solid: b, materials: n }) => {
                Arc::ptr_eq(a, b) && Arc::ptr_eq(m, n)
            }
            _ => false,
        }
    }
}

/// An axis-aligned box: its lowest and highest corners.
type Bounds = (Vec3, Vec3);

/// What a scene's geometry was when a cache was filled: every object's body
/// (a clone of its `Arc`: while held, no one can change that geometry in
/// place, so pointer equality is a sound test), transform and whether it
/// casts shadows. Caches of the BVH and of shadow maps keep one and rebuild
/// when the scene no longer [`GeometryKey::matches`] it.
#[derive(Debug, Clone, Default)]
pub struct GeometryKey(Vec<(Body, Affine3A, bool)>);

impl GeometryKey {
    /// The key of `scene`'s geometry.
    #[must_use]
    pub fn of(scene: &Scene) -> GeometryKey {
        GeometryKey(scene.objects.iter().map(|o| (o.body.clone(), o.transform, o.casts_shadows)).collect())
    }

    /// Whether `scene` has the same geometry.
    #[must_use]
    pub fn matches(&self, scene: &Scene) -> bool {
        self.0.len() == scene.objects.len()
            && self
                .0
                .iter()
                .zip(&scene.objects)
                .all(|((b, t, c), o)| b.same(&o.body) && *t == o.transform && *c == o.casts_shadows)
    }
}

/// A mesh or a CSG solid placed in the world with a material.
#[derive(Debug, Clone)]
pub struct Object {
    /// Name, for messages and statistics.
    pub name: String,
    /// Shared geometry in object space.
    pub body: Body,
    /// Object → world transform.
    pub transform: Affine3A,
    /// Index into [`Scene::materials`] (a solid's primitives name their own).
    pub material: usize,
    /// Whether it is drawn into shadow maps. A floor under everything casts
    /// no shadow onto anything; leaving it out lets a light's map fit the
    /// objects that do ([`Scene::caster_bounds`]) rather than the floor.
    pub casts_shadows: bool,
    /// An OpenSCAD `#` (highlighted) or `%` (background) part, drawn
    /// see-through over the model as OpenSCAD's preview draws it; a viewer
    /// may hide such parts.
    pub ghost: bool,
}

impl Object {
    /// A mesh object.
    #[must_use]
    pub fn mesh(name: impl Into<String>, mesh: Arc<Mesh>, transform: Affine3A, material: usize) -> Object {
        Object { name: name.into(), body: Body::Mesh(mesh), transform, material, casts_shadows: true, ghost: false }
    }

    /// The triangles, if the object is a mesh.
    #[must_use]
    pub fn triangles(&self) -> Option<&Arc<Mesh>> {
        match &self.body {
            Body::Mesh(m) => Some(m),
            Body::Solid { .. } => None,
        }
    }

    /// The solid, if the object is one.
    #[must_use]
    pub fn solid(&self) -> Option<&Arc<CsgSolid>> {
        match &self.body {
            Body::Solid { solid, .. } => Some(solid),
            Body::Mesh(_) => None,
        }
    }

    /// Bounds `(min, max)` in world space: the object-space box's eight corners
    /// transformed (`None` for an empty body).
    #[must_use]
    pub fn world_bounds(&self) -> Option<(Vec3, Vec3)> {
        Some(self.world_box(self.local_bounds()?))
    }

    /// The world-space bounds of the object-space box `(lo, hi)`: its eight
    /// corners transformed.
    #[must_use]
    pub fn world_box(&self, bounds: (Vec3, Vec3)) -> (Vec3, Vec3) {
        let corners = box_corners(bounds).map(|c| self.transform.transform_point3(c));
        corners.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &c| (lo.min(c), hi.max(c)))
    }

    /// Bounds `(min, max)` in object space (`None` for an empty body).
    #[must_use]
    pub fn local_bounds(&self) -> Option<(Vec3, Vec3)> {
        match &self.body {
            Body::Mesh(m) => Some(m.bounds()),
            Body::Solid { solid, .. } => solid.bounds(),
        }
    }
}

/// The eight corners of the box `(lo, hi)`.
#[must_use]
pub fn box_corners((lo, hi): (Vec3, Vec3)) -> [Vec3; 8] {
    std::array::from_fn(|k| {
        let pick = |bit: usize, a: f32, b: f32| if k >> bit & 1 == 0 { a } else { b };
        Vec3::new(pick(0, lo.x, hi.x), pick(1, lo.y, hi.y), pick(2, lo.z, hi.z))
    })
}

/// The opacity of every material in an x-ray view ([`Scene::xray`]).
pub const XRAY_OPACITY: f32 = 0.3;

/// The diffuse share of a surface's white in a technical drawing
/// ([`Scene::drawing`]); the rest is its own flat light.
pub const DRAWING_DIFFUSE: f32 = 0.2;

/// A complete scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
    /// Linear RGB colour of pixels that see no object.
    pub background: Vec3,
    /// Brightness of 8-bit output.
    pub exposure: Exposure,
    /// How 8-bit output rolls off light above white.
    pub tone: ToneCurve,
    /// How edges are antialiased.
    pub antialias: Antialias,
    /// Fog (seed 002 §3.5), if any.
    pub fog: Option<Fog>,
    /// Ambient occlusion, if any: the ambient term darkened where nearby
    /// surfaces hide the sky.
    pub ambient_occlusion: Option<AmbientOcclusion>,
    /// Feature lines drawn over the image, if any.
    pub lines: Option<FeatureLines>,
    /// The environment map (reflection map of eq. 4 and optional background).
    pub environment: Option<Environment>,
    /// How translucent surfaces are ordered (seed 002 §3.4).
    pub translucency: TranslucencyOrder,
    /// The eye.
    pub camera: Camera,
    /// The camera's path over the frames of an animation, if the scene
    /// file gives one (`[path]`): [`camera_path::CameraPath::camera_at`].
    pub camera_path: Option<camera_path::CameraPath>,
    /// Lights.
    pub lights: Vec<Light>,
    /// Whether the lights are a rig placed from the camera (a lone model's,
    /// [`model`]), which turns with it round a turntable
    /// ([`camera_path::turntable_lights`]); a scene file's lights stay put.
    pub lights_follow_camera: bool,
    /// Materials, referenced by index from objects.
    pub materials: Vec<Material>,
    /// Objects.
    pub objects: Vec<Object>,
    /// Things the loaders repaired or ignored, for the user to see.
    pub warnings: Vec<String>,
    /// What rendering the scene may ask for: its triangles, shadow maps and
    /// memory are checked against these before a frame starts.
    pub limits: Limits,
}

/// Checks an image size before anything is allocated for it.
///
/// # Errors
///
/// [`Error::ImageSize`] for a side of 0 or over [`MAX_IMAGE_SIDE`], or more
/// than [`MAX_IMAGE_PIXELS`] pixels.
pub fn check_image_size(width: u64, height: u64) -> Result<()> {
    let err = |reason| Err(Error::ImageSize { width, height, reason });
    if width == 0 || height == 0 {
        return err("width and height must be at least 1");
    }
    if width > MAX_IMAGE_SIDE as u64 || height > MAX_IMAGE_SIDE as u64 {
        return err("each side must be at most 16384 pixels");
    }
    if width * height > MAX_IMAGE_PIXELS {
        return err("the image must have at most 134,217,728 pixels (16384 x 8192)");
    }
    Ok(())
}

impl Scene {
    /// An empty `width` × `height` scene seen by `camera`: no objects, lights
    /// or materials yet, a dark background, every setting at its default.
    #[must_use]
    pub fn new(width: u32, height: u32, camera: Camera) -> Scene {
        Scene {
            width,
            height,
            background: Vec3::new(0.1, 0.1, 0.15),
            exposure: Exposure::default(),
            tone: ToneCurve::default(),
            antialias: Antialias::default(),
            fog: None,
            ambient_occlusion: None,
            lines: None,
            environment: None,
            translucency: TranslucencyOrder::default(),
            camera,
            camera_path: None,
            lights: Vec::new(),
            lights_follow_camera: false,
            materials: Vec::new(),
            objects: Vec::new(),
            warnings: Vec::new(),
            limits: Limits::default(),
        }
    }

    /// Checks everything a render relies on: image size, camera, materials referenced.
    ///
    /// # Errors
    ///
    /// [`Error::ImageSize`] as [`check_image_size`]; [`Error::Scene`] for an
    /// unusable camera, an object without a material or with a non-finite
    /// transform.
    pub fn validate(&self) -> Result<()> {
        check_image_size(self.width as u64, self.height as u64)?;
        self.camera.validate().map_err(Error::Scene)?;
        if let Some(o) = self.objects.iter().find(|o| o.material >= self.materials.len()) {
            return Err(Error::Scene(format!("object '{}' has no material", o.name)));
        }
        if let Some(o) = self.objects.iter().find(|o| !o.transform.is_finite()) {
            return Err(Error::Scene(format!("object '{}' has a non-finite transform", o.name)));
        }
        Ok(())
    }

    /// Makes the scene an x-ray view: every object but a floor under them
    /// all (which stays as it is, the ground the parts stand on) drawn in a
    /// see-through copy of its material, with `opacity` and two-sided (back
    /// faces drawn too), blended in depth order
    /// ([`TranslucencyOrder::Sorted`]: each pixel's fragments sorted, so the
    /// image does not depend on the order of the objects); no shadows (a
    /// see-through part would darken what lies behind it), no mirrors or
    /// glass traced.
    pub fn xray(&mut self, opacity: f32) {
        let floors = self.grounds();
        let mut see_through: std::collections::HashMap<usize, usize> = std::collections::HashMap::new();
        let materials = &mut self.materials;
        let mut copy = |m: usize| {
            *see_through.entry(m).or_insert_with(|| {
                let base = &materials[m];
                let (kr, kt) = (Vec3::ZERO, Vec3::ZERO);
                materials.push(Material { opacity, two_sided: true, kr, kt, ..base.clone() });
                materials.len() - 1
            })
        };
        let parts = self.objects.iter_mut().enumerate().filter(|(i, _)| !floors.contains(i));
        for (_, object) in parts {
            object.material = copy(object.material);
            if let Body::Solid { materials: own, .. } = &mut object.body {
                *own = own.iter().map(|&m| copy(m)).collect();
            }
        }
        self.translucency = TranslucencyOrder::Sorted;
        self.lights.iter_mut().for_each(|l| l.shadow = ShadowSettings::NONE);
    }

    /// Makes the scene a technical drawing: every surface white, lit mostly
    /// by its own flat light (a fifth of it diffuse, so faces at different
    /// angles stay apart), nothing glossy, mirrored or textured (alpha kept);
    /// a white background, no ground (the objects [`Scene::xray`] keeps
    /// opaque), no shadows, no fog, colours clipped at white rather than
    /// rolled off; dark feature lines with the hidden ones dashed.
    pub fn drawing(&mut self) {
        for m in &mut self.materials {
            let maps = ComponentMaps { alpha: m.maps.alpha.take(), filter: m.maps.filter, ..ComponentMaps::default() };
            let (ka, ks, kr, kt, km) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
            let (kd, ke) = (Vec3::splat(DRAWING_DIFFUSE), Vec3::splat(1.0 - DRAWING_DIFFUSE));
            *m = Material { ka, kd, ks, ke, kr, kt, km, maps, ..m.clone() };
        }
        let grounds = self.grounds();
        let mut index = 0;
        self.objects.retain(|_| {
            index += 1;
            !grounds.contains(&(index - 1))
        });
        self.background = Vec3::ONE;
        // White stays white: no roll-off towards it.
        (self.exposure, self.tone) = (Exposure::default(), ToneCurve::Clip);
        self.fog = None;
        self.lights.iter_mut().for_each(|l| l.shadow = ShadowSettings::NONE);
        self.lines = Some(FeatureLines { hidden: true, ..self.lines.unwrap_or_default() });
    }

    /// The objects that are a ground: flat and horizontal, under every other
    /// object (a model's ground, a scene's floor), whether they cast shadows
    /// or not.
    fn grounds(&self) -> Vec<usize> {
        let boxes: Vec<(usize, Bounds)> =
            self.objects.iter().enumerate().filter_map(|(i, o)| Some((i, o.world_bounds()?))).collect();
        flat_under(&boxes, |_| true)
    }

    /// The ambient-occlusion radius: the scene's own, or
    /// [`AmbientOcclusion::RADIUS_OF_SIZE`] of the diagonal of the shadow
    /// casters' box (the model, not its floor; all objects' without casters).
    /// `None` without ambient occlusion.
    #[must_use]
    pub fn occlusion_radius(&self) -> Option<f32> {
        let ao = self.ambient_occlusion?;
        let size = || {
            let (lo, hi) = self.caster_bounds().or_else(|| self.bounds()).unwrap_or((Vec3::ZERO, Vec3::ONE));
            AmbientOcclusion::RADIUS_OF_SIZE * (hi - lo).length()
        };
        Some(ao.radius.unwrap_or_else(size))
    }

    /// World-space bounds `(min, max)` of all objects (`None` if there are none).
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        Self::union_of(self.objects.iter())
    }

    /// What the lights' shadow methods cannot draw as the materials ask:
    /// the silhouette-line buffer outlines whole triangles, so an
    /// alpha-tested cut-out shadows its whole shape there.
    #[must_use]
    pub fn shadow_warnings(&self) -> Vec<String> {
        let cut = self.objects.iter().any(|o| self.materials[o.material].cuts_out());
        let slb = self.lights.iter().any(|l| l.shadow.method == ShadowMethod::Slb);
        if cut && slb {
            vec!["alpha-tested cut-outs (glTF MASK, OBJ map_d) cast the shadow of their whole triangles under the \
                  silhouette-line buffer (SLB); a shadow map cuts them"
                .into()]
        } else {
            Vec::new()
        }
    }

    /// World-space bounds of the objects that cast shadows: what a light's
    /// shadow map must hold (a receiver outside it is lit, as nothing between
    /// it and the light is outside it either). A floor is left out: a flat
    /// object lying under every other caster, with every light above it, casts
    /// onto nothing (what it hides from a light lies below it).
    #[must_use]
    pub fn caster_bounds(&self) -> Option<(Vec3, Vec3)> {
        self.shadow_casters().1
    }

    /// Per object, whether shadow maps draw it: it casts shadows and is not a
    /// floor ([`Scene::caster_bounds`]'s: what a floor hides from a light lies
    /// below it, so leaving it out changes no shadow, and spares a map the
    /// texels it would fill — most of a spot light's map, in the demo).
    #[must_use]
    pub fn map_casters(&self) -> Vec<bool> {
        self.shadow_casters().0
    }

    /// [`Scene::map_casters`] and [`Scene::caster_bounds`] at once: each
    /// walks every object's vertices (a scanned mesh's tenth of a
    /// millisecond or more, on one worker), which a frame does once for both.
    #[must_use]
    pub fn shadow_casters(&self) -> (Vec<bool>, Option<(Vec3, Vec3)>) {
        let (casters, floors) = self.casters_and_floors();
        let drawn = self.objects.iter().enumerate().map(|(i, o)| o.casts_shadows && !floors.contains(&i)).collect();
        let union = |boxes: &mut dyn Iterator<Item = (Vec3, Vec3)>| boxes.reduce(|(a, b), (c, d)| (a.min(c), b.max(d)));
        let all = union(&mut casters.iter().map(|&(_, b)| b));
        let mut rest = casters.iter().filter(|(i, _)| !floors.contains(i)).map(|&(_, b)| b);
        (drawn, union(&mut rest).or(all))
    }

    /// The shadow casters (object index and world bounds), and which of them
    /// are floors: flat, lying under every other caster, every light above.
    fn casters_and_floors(&self) -> (Vec<(usize, Bounds)>, Vec<usize>) {
        let casters: Vec<(usize, Bounds)> = self
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.casts_shadows)
            .filter_map(|(i, o)| Some((i, o.world_bounds()?)))
            .collect();
        let lit_from_above = |top: f32, eps: f32| {
            self.lights.iter().all(|l| match l.kind {
                LightKind::Point { position } | LightKind::Spot { position, .. } => position.y > top + eps,
                LightKind::Directional { direction } => direction.y < 0.0,
            })
        };
        let floors = flat_under(&casters, |(top, eps)| lit_from_above(top, eps));
        (casters, floors)
    }

    fn union_of<'a>(objects: impl Iterator<Item = &'a Object>) -> Option<(Vec3, Vec3)> {
        objects.filter_map(Object::world_bounds).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// What a ray leaving the scene along `dir` sees: the environment if it is
    /// visible, else the background colour.
    #[must_use]
    pub fn background_along(&self, dir: Vec3) -> Vec3 {
        match &self.environment {
            Some(env) if env.visible => env.radiance(dir),
            _ => self.background,
        }
    }

    /// Number of triangles over all mesh objects.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().filter_map(Object::triangles).map(|m| m.triangles.len()).sum()
    }
}

/// Of the `boxes` (object index, world bounds), the flat, horizontal ones lying
/// under every other (within a hair of their union's size) whose top and
/// hair `also(top, hair)` accepts.
fn flat_under(boxes: &[(usize, Bounds)], also: impl Fn((f32, f32)) -> bool) -> Vec<usize> {
    let Some((lo, hi)) = boxes.iter().map(|&(_, b)| b).reduce(|(a, b), (c, d)| (a.min(c), b.max(d))) else {
        return Vec::new();
    };
    let eps = 1e-4 * (hi - lo).max_element().max(f32::MIN_POSITIVE);
    let under = |i: usize, top: f32| boxes.iter().all(|&(j, c)| j == i || c.0.y >= top - eps);
    let flat = |&&(i, b): &&(usize, Bounds)| b.1.y - b.0.y <= eps && under(i, b.1.y) && also((b.1.y, eps));
    boxes.iter().filter(flat).map(|&(i, _)| i).collect()
}
