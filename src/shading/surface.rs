//! From a visibility-buffer entry back to a surface point (seed 002 §4): the pixel's
//! ray is intersected exactly with the ONE triangle whose id the pixel holds — no
//! search — giving perspective-correct barycentrics, the position, the interpolated
//! normal and texture coordinates.

use glam::{Affine3A, Mat3A, Vec2, Vec3};

use crate::scene::{Ray, Scene};
use crate::visibility::ItemId;

/// What shading needs to know about the visible point of a pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// World position.
    pub position: Vec3,
    /// Unit shading normal, turned to face the eye.
    pub normal: Vec3,
    /// Unit vector towards the eye.
    pub to_eye: Vec3,
    /// Texture coordinates (zero if the mesh has none).
    pub uv: Vec2,
    /// Index into `Scene::materials`.
    pub material: usize,
}

/// Object → world transforms for points and normals, computed once per frame.
#[derive(Debug, Clone)]
pub struct ObjectFrames {
    frames: Vec<(Affine3A, Mat3A)>,
}

impl ObjectFrames {
    /// Precomputes every object's transforms.
    #[must_use]
    pub fn new(scene: &Scene) -> Self {
        let frames = scene
            .objects
            .iter()
            .map(|o| (o.transform, o.transform.matrix3.inverse().transpose()))
            .collect();
        ObjectFrames { frames }
    }

    /// The world-space vertices of an item's triangle.
    #[must_use]
    pub fn triangle(&self, scene: &Scene, item: ItemId) -> [Vec3; 3] {
        let (m, _) = self.frames[item.object as usize];
        let mesh = &scene.objects[item.object as usize].mesh;
        mesh.triangles[item.triangle as usize]
            .map(|i| m.transform_point3(mesh.positions[i as usize]))
    }

    /// The surface seen along `ray` on `item`'s triangle.
    #[must_use]
    pub fn surface(&self, scene: &Scene, item: ItemId, ray: &Ray) -> SurfacePoint {
        let object = &scene.objects[item.object as usize];
        let mesh = &object.mesh;
        let idx = mesh.triangles[item.triangle as usize].map(|i| i as usize);
        let p = self.triangle(scene, item);
        let (t, b) = intersect_plane(ray, p);
        let position = ray.origin + ray.dir * t;
        let weights = [1.0 - b.x - b.y, b.x, b.y];
        let blend3 = |a: [Vec3; 3]| a[0] * weights[0] + a[1] * weights[1] + a[2] * weights[2];
        let (_, nm) = self.frames[item.object as usize];
        let geometric = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or(Vec3::Y);
        let normal = Vec3::from(nm * glam::Vec3A::from(blend3(idx.map(|i| mesh.normals[i]))))
            .normalize_or(geometric);
        let to_eye = -ray.dir.normalize();
        let normal = if normal.dot(to_eye) < 0.0 {
            -normal
        } else {
            normal
        };
        let uv = if mesh.uvs.is_empty() {
            Vec2::ZERO
        } else {
            let u = idx.map(|i| mesh.uvs[i]);
            u[0] * weights[0] + u[1] * weights[1] + u[2] * weights[2]
        };
        SurfacePoint {
            position,
            normal,
            to_eye,
            uv,
            material: object.material,
        }
    }
}

/// Intersects the ray with the triangle's PLANE (Möller–Trumbore without the
/// inside test: a pixel centre that the fill rule gave to this triangle may lie a
/// hair outside it). Returns the distance and barycentrics (b1, b2).
#[must_use]
pub fn intersect_plane(ray: &Ray, p: [Vec3; 3]) -> (f32, Vec2) {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let pvec = ray.dir.cross(e2);
    let det = e1.dot(pvec);
    if det.abs() < f32::MIN_POSITIVE {
        // Seen edge-on: the point nearest the centroid is as good as any.
        let c = (p[0] + p[1] + p[2]) / 3.0;
        return (
            (c - ray.origin).dot(ray.dir) / ray.dir.length_squared(),
            Vec2::splat(1.0 / 3.0),
        );
    }
    let inv = 1.0 / det;
    let tvec = ray.origin - p[0];
    let qvec = tvec.cross(e1);
    (
        e2.dot(qvec) * inv,
        Vec2::new(tvec.dot(pvec) * inv, ray.dir.dot(qvec) * inv),
    )
}
