//! Scenes and CSG trees made from fuzzer bytes (`Arbitrary`), every value
//! drawn from a range a real scene could hold: the structure-aware targets
//! explore what is drawn, not what is refused.

use std::f32::consts::TAU;
use std::sync::Arc;

use glam::{Affine3A, Mat3, Vec3};
use libfuzzer_sys::arbitrary::{self, Arbitrary};

use kage::camera::{Camera, Projection};
use kage::csg::{ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Shape};
use kage::scene::mesh::shapes;
use kage::scene::{Body, Falloff, Light, LightKind, Material, Object, Scene, ShadowMethod, ShadowSettings};

/// A number in `lo..=hi` from a byte.
fn unit(b: u8, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * f32::from(b) / 255.0
}

/// A camera looking at the origin from a distance.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub struct CameraSpec {
    azimuth: u8,
    elevation: u8,
    distance: u8,
    fov: u8,
    orthographic: bool,
}

impl CameraSpec {
    /// The camera.
    #[must_use]
    pub fn camera(&self) -> Camera {
        let (az, el) = (unit(self.azimuth, 0.0, TAU), unit(self.elevation, -1.4, 1.4));
        let dir = Vec3::new(az.cos() * el.cos(), el.sin(), az.sin() * el.cos());
        let distance = unit(self.distance, 4.0, 12.0);
        let projection = if self.orthographic {
            Projection::Orthographic { height: distance }
        } else {
            Projection::Perspective { fov_y_deg: unit(self.fov, 20.0, 90.0) }
        };
        Camera {
            eye: dir * distance,
            target: Vec3::ZERO,
            up: Vec3::Y,
            near: 0.05,
            far: 100.0,
            projection,
            shift: glam::Vec2::ZERO,
        }
    }
}

/// A placement: scale 0.3–1.5 per axis, a small shear, any rotation, an
/// offset within ±2.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub struct PlaceSpec {
    scale: [u8; 3],
    shear: [u8; 3],
    axis: [u8; 3],
    angle: u8,
    offset: [u8; 3],
}

impl PlaceSpec {
    /// The transform; `k` (the primitive's index) moves it off the byte grid,
    /// so two primitives' faces are not flush by accident of the encoding.
    #[must_use]
    pub fn transform(&self, k: usize) -> Affine3A {
        let v = |b: [u8; 3], lo: f32, hi: f32| Vec3::new(unit(b[0], lo, hi), unit(b[1], lo, hi), unit(b[2], lo, hi));
        let axis = v(self.axis, -1.0, 1.0).normalize_or(Vec3::Z);
        let rotation = Mat3::from_axis_angle(axis, unit(self.angle, 0.0, TAU));
        let s = v(self.scale, 0.3, 1.5);
        let h = v(self.shear, -0.3, 0.3);
        let shear = Mat3::from_cols(Vec3::X, Vec3::new(h.x, 1.0, 0.0), Vec3::new(h.y, h.z, 1.0));
        let nudge = Vec3::new(0.0137, 0.0071, 0.0113) * (k as f32 + 1.0);
        Affine3A::from_mat3_translation(rotation * shear * Mat3::from_diagonal(s), v(self.offset, -2.0, 2.0) + nudge)
    }
}

/// A convex primitive.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum PrimitiveSpec {
    /// The unit sphere.
    Sphere(PlaceSpec),
    /// A frustum with these radii (0 a point).
    Frustum(u8, u8, PlaceSpec),
    /// The unit cube.
    Cube(PlaceSpec),
    /// A tetrahedron on the origin and the unit axes.
    Tetrahedron(PlaceSpec),
}

impl PrimitiveSpec {
    fn primitive(&self, k: usize) -> Primitive {
        let (shape, place) = match *self {
            PrimitiveSpec::Sphere(p) => (Shape::Sphere, p),
            PrimitiveSpec::Frustum(a, b, p) => {
                // The larger radius is 1, as the OpenSCAD reader makes it (a
                // frustum of two zero radii, a line, has no volume to draw).
                let (a, b) = (unit(a, 0.0, 1.0), unit(b, 0.0, 1.0));
                let (bottom, top) = if a.max(b) > 0.0 { (a / a.max(b), b / a.max(b)) } else { (1.0, 0.0) };
                (Shape::Frustum { bottom, top }, p)
            }
            PrimitiveSpec::Cube(p) => (Shape::Polyhedron(ConvexPolyhedron::unit_cube()), p),
            PrimitiveSpec::Tetrahedron(p) => {
                let n = Vec3::ONE.normalize();
                let planes =
                    vec![(-Vec3::X).extend(0.0), (-Vec3::Y).extend(0.0), (-Vec3::Z).extend(0.0), n.extend(n.x)];
                let vertices = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
                (Shape::Polyhedron(ConvexPolyhedron { planes, vertices }), p)
            }
        };
        Primitive { shape, transform: place.transform(k), color: None, source: 0..0 }
    }
}

/// A CSG tree of primitives.
#[derive(Arbitrary, Debug, Clone)]
pub enum TreeSpec {
    /// One primitive.
    Leaf(PrimitiveSpec),
    /// Their union.
    Union(Vec<TreeSpec>),
    /// Their intersection.
    Intersection(Vec<TreeSpec>),
    /// The first less the others.
    Difference(Vec<TreeSpec>),
}

/// Most primitives a fuzzed tree is given (the rest of its leaves dropped).
const MAX_LEAVES: usize = 24;
/// Deepest a fuzzed tree is read.
const MAX_DEPTH: usize = 8;

impl TreeSpec {
    /// The solid, `None` when the tree has no leaf.
    #[must_use]
    pub fn solid(&self) -> Option<CsgSolid> {
        let mut primitives = Vec::new();
        let tree = self.tree(&mut primitives, 0)?;
        Some(CsgSolid { primitives, tree: Some(tree) })
    }

    fn tree(&self, prims: &mut Vec<Primitive>, depth: usize) -> Option<CsgTree> {
        let kids = |v: &[TreeSpec], prims: &mut Vec<Primitive>| -> Vec<CsgTree> {
            if depth >= MAX_DEPTH {
                return Vec::new();
            }
            v.iter().filter_map(|t| t.tree(prims, depth + 1)).collect()
        };
        match self {
            TreeSpec::Leaf(p) if prims.len() < MAX_LEAVES => {
                prims.push(p.primitive(prims.len()));
                Some(CsgTree::Leaf(prims.len() - 1))
            }
            TreeSpec::Leaf(_) => None,
            TreeSpec::Union(v) => one_or(kids(v, prims), CsgTree::Union),
            TreeSpec::Intersection(v) => one_or(kids(v, prims), CsgTree::Intersection),
            TreeSpec::Difference(v) => one_or(kids(v, prims), |mut kids| {
                let first = kids.remove(0);
                CsgTree::Difference(Box::new(first), kids)
            }),
        }
    }
}

fn one_or(mut kids: Vec<CsgTree>, make: fn(Vec<CsgTree>) -> CsgTree) -> Option<CsgTree> {
    match kids.len() {
        0 => None,
        1 => kids.pop(),
        _ => Some(make(kids)),
    }
}

/// A surface.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub struct MaterialSpec {
    kd: [u8; 3],
    ks: u8,
    shininess: u8,
    kr: u8,
    kt: u8,
    opacity: u8,
    two_sided: bool,
}

impl MaterialSpec {
    fn material(&self, k: usize) -> Material {
        let kd = Vec3::from(self.kd.map(|c| unit(c, 0.0, 1.0)));
        Material {
            name: format!("m{k}"),
            ka: kd,
            kd,
            ks: Vec3::splat(unit(self.ks, 0.0, 1.0)),
            shininess: unit(self.shininess, 0.0, 200.0),
            kr: Vec3::splat(unit(self.kr, 0.0, 1.0)),
            kt: Vec3::splat(unit(self.kt, 0.0, 1.0)),
            opacity: unit(self.opacity, 0.0, 1.0).max(0.05),
            two_sided: self.two_sided,
            ..Material::default()
        }
    }
}

/// An object of the scene.
#[derive(Arbitrary, Debug, Clone)]
pub enum ObjectSpec {
    /// A unit plane, cube or sphere.
    Shape(u8, PlaceSpec, MaterialSpec),
    /// A CSG solid.
    Solid(TreeSpec, MaterialSpec),
}

/// A light.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub struct LightSpec {
    kind: u8,
    at: [u8; 3],
    size: u8,
    samples: u8,
    resolution: u8,
    pcf: u8,
    inner: u8,
    outer: u8,
}

impl LightSpec {
    fn light(&self) -> Light {
        let at = Vec3::from(self.at.map(|c| unit(c, -6.0, 6.0))) + Vec3::Y * 3.0;
        let direction = (-at).normalize_or(Vec3::NEG_Y);
        let (inner, outer) = (unit(self.inner.min(self.outer), 0.0, 1.5), unit(self.inner.max(self.outer), 0.0, 1.5));
        let kind = match self.kind % 3 {
            0 => LightKind::Point { position: at },
            1 => LightKind::Directional { direction },
            _ => LightKind::Spot { position: at, direction, inner, outer },
        };
        let shadow = ShadowSettings {
            method: if self.kind & 4 == 0 { ShadowMethod::Map } else { ShadowMethod::None },
            resolution: 16 + u32::from(self.resolution) * 2,
            by_need: self.kind & 8 != 0,
            pcf: 1 + u32::from(self.pcf % 5) * 2,
            samples: 1 + u32::from(self.samples % 8),
            ..ShadowSettings::MAP
        };
        Light {
            kind,
            color: Vec3::ONE,
            intensity: 1.0,
            ambient: 0.1,
            size: unit(self.size, 0.0, 1.0),
            falloff: if self.kind & 16 == 0 { Falloff::None } else { Falloff::InverseSquare },
            shadow,
            only: None,
        }
    }
}

/// A scene.
#[derive(Arbitrary, Debug, Clone)]
pub struct SceneSpec {
    camera: CameraSpec,
    objects: Vec<ObjectSpec>,
    lights: Vec<LightSpec>,
}

/// Most objects and lights a fuzzed scene is given.
const MAX_OBJECTS: usize = 8;
const MAX_LIGHTS: usize = 3;

impl SceneSpec {
    /// The scene at `size`, `None` when it has no object.
    #[must_use]
    pub fn scene(&self, (width, height): (u32, u32)) -> Option<Scene> {
        let mut scene = Scene::new(width, height, self.camera.camera());
        for (k, o) in self.objects.iter().take(MAX_OBJECTS).enumerate() {
            let (body, transform, material) = match o {
                ObjectSpec::Shape(kind, place, m) => {
                    let mesh = match kind % 3 {
                        0 => shapes::plane(),
                        1 => shapes::cube(),
                        _ => shapes::sphere(6 + u32::from(kind / 3) % 24),
                    };
                    (Body::Mesh(Arc::new(mesh)), place.transform(k), m)
                }
                ObjectSpec::Solid(tree, m) => {
                    let Some(solid) = tree.solid() else { continue };
                    let materials = vec![scene.materials.len(); solid.primitives.len()].into();
                    (Body::Solid { solid: Arc::new(solid), materials }, Affine3A::IDENTITY, m)
                }
            };
            scene.materials.push(material.material(k));
            let material = scene.materials.len() - 1;
            scene.objects.push(Object { name: format!("o{k}"), body, transform, material, casts_shadows: true, ghost: false });
        }
        scene.lights = self.lights.iter().take(MAX_LIGHTS).map(LightSpec::light).collect();
        (!scene.objects.is_empty()).then_some(scene)
    }
}
