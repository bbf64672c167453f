//! From a visibility-buffer entry back to a surface point (seed 002 §4): the pixel's
//! ray is intersected exactly with the ONE triangle whose id the pixel holds — no
//! search — giving perspective-correct barycentrics, the position, the interpolated
//! normal and texture coordinates.
//!
//! A pixel that shows a CSG solid (seed 003) holds its primitive, depth and normal
//! instead: its point is where the pixel's ray reaches that depth, and it is shaded
//! as the plane tangent to the solid there ([`ObjectFrames::tangent`]), so every
//! shading path built for triangles shades solids unchanged.

use glam::{Affine2, Affine3A, Mat3A, Vec2, Vec3};

use crate::scene::Scene;

use crate::camera::Ray;
use crate::visibility::{ItemId, VisibilityBuffer};

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
    /// Texture-space steps to the neighbouring pixels' points (right, below), for
    /// mip-level selection; zero where unknown (secondary rays): finest level.
    pub duv: [Vec2; 2],
    /// World-space change of the position per unit of texture u and of v
    /// (∂P/∂u, ∂P/∂v): the tangent frame a normal map is painted in; zero
    /// without texture coordinates.
    pub tangents: [Vec3; 2],
    /// Index into `Scene::materials`.
    pub material: usize,
    /// Whether the eye sees the front (counter-clockwise, outward) side.
    pub front: bool,
    /// The mesh's vertex colour here (white without one): it multiplies Ka
    /// and Kd.
    pub color: Vec3,
    /// The triangle's map from its first texture coordinates to its second
    /// ([`Mesh::uvs1`](crate::scene::Mesh::uvs1); affine over a triangle,
    /// the identity without them).
    pub second: Affine2,
}

impl SurfacePoint {
    /// The texture coordinates and footprint of coordinate set `set` (0 or
    /// 1, a texture's [`Texture::set`](crate::scene::Texture::set)).
    #[must_use]
    pub fn coords(&self, set: u8) -> (Vec2, [Vec2; 2]) {
        if set == 0 {
            return (self.uv, self.duv);
        }
        let s = self.second;
        (s.transform_point2(self.uv), self.duv.map(|d| s.transform_vector2(d)))
    }
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
        let frames = scene.objects.iter().map(|o| (o.transform, o.transform.matrix3.inverse().transpose())).collect();
        ObjectFrames { frames }
    }

    /// The world-space vertices of an item's triangle.
    ///
    /// # Panics
    ///
    /// If `item` names no triangle of a mesh object of `scene`.
    #[must_use]
    pub fn triangle(&self, scene: &Scene, item: ItemId) -> [Vec3; 3] {
        let (m, _) = self.frames[item.object as usize];
        let mesh = scene.objects[item.object as usize].triangles().expect("a triangle's item names a mesh");
        mesh.triangles[item.triangle as usize].map(|i| m.transform_point3(mesh.positions[i as usize]))
    }

    /// The surface seen along `ray` on `item`'s triangle.
    #[must_use]
    pub fn surface(&self, scene: &Scene, item: ItemId, ray: &Ray) -> SurfacePoint {
        self.prepare(scene, item).surface(ray)
    }

    /// The surface that pixel (`x`, `y`) of `vb` shows, seen along `ray` (the
    /// pixel's ray, or a ray through another point of the pixel: a triangle is
    /// met again, a solid's tangent plane stands in for its surface).
    #[must_use]
    pub fn surface_at(&self, scene: &Scene, vb: &VisibilityBuffer, x: u32, y: u32, ray: &Ray) -> SurfacePoint {
        self.prepare_at(scene, vb, x, y, ray).surface(ray)
    }

    /// [`ObjectFrames::prepare`] for the item at pixel (`x`, `y`) of `vb`, whose
    /// ray is `ray`: a solid's primitive gives its tangent plane at the pixel's
    /// point.
    #[must_use]
    pub fn prepare_at(&self, scene: &Scene, vb: &VisibilityBuffer, x: u32, y: u32, ray: &Ray) -> PreparedTriangle {
        let item = vb.item(x, y);
        if item.primitive().is_none() {
            return self.prepare(scene, item);
        }
        let t = scene.camera.distance_at_depth(ray, vb.depth(x, y));
        Self::tangent(scene, item, ray.origin + ray.dir * t, vb.normal(x, y))
    }

    /// The plane tangent to a solid's primitive `item` at `point` with the
    /// solid's outward `normal` (world space), as a triangle with that normal at
    /// every vertex: shading it along a ray through `point` gives the solid's
    /// surface point.
    #[must_use]
    pub fn tangent(scene: &Scene, item: ItemId, point: Vec3, normal: Vec3) -> PreparedTriangle {
        let normal = normal.normalize_or(Vec3::Y);
        let (e1, e2) = normal.any_orthonormal_pair();
        PreparedTriangle {
            item,
            a: point,
            e1,
            e2,
            geometric: normal,
            normals: [normal; 3],
            uvs: None,
            colors: None,
            tangents: [Vec3::ZERO; 2],
            second: Affine2::IDENTITY,
            material: item.material(scene),
        }
    }

    /// Gathers everything about `item`'s triangle (a mesh's) that does not
    /// depend on the ray, so neighbouring pixels showing the same triangle share
    /// the work.
    ///
    /// # Panics
    ///
    /// If `item` names no triangle of a mesh object of `scene`.
    #[must_use]
    pub fn prepare(&self, scene: &Scene, item: ItemId) -> PreparedTriangle {
        let object = &scene.objects[item.object as usize];
        let mesh = object.triangles().expect("a triangle's item names a mesh");
        let idx = mesh.triangles[item.triangle as usize].map(|i| i as usize);
        let [a, b, c] = self.triangle(scene, item);
        let (_, nm) = self.frames[item.object as usize];
        let (e1, e2) = (b - a, c - a);
        let uvs = (!mesh.uvs.is_empty()).then(|| idx.map(|i| mesh.uvs[i]));
        PreparedTriangle {
            item,
            a,
            e1,
            e2,
            geometric: e1.cross(e2).normalize_or(Vec3::Y),
            normals: idx.map(|i| Vec3::from(nm * glam::Vec3A::from(mesh.normals[i]))),
            uvs,
            colors: (!mesh.colors.is_empty()).then(|| idx.map(|i| mesh.colors[i])),
            tangents: uvs.map_or([Vec3::ZERO; 2], |uv| position_derivatives(e1, e2, uv)),
            second: second_coordinates(mesh, idx),
            material: object.material,
        }
    }
}

/// One item's triangle in world space, ready to be hit by pixel rays.
#[derive(Debug, Clone, Copy)]
pub struct PreparedTriangle {
    /// The item it belongs to.
    pub item: ItemId,
    a: Vec3,
    e1: Vec3,
    e2: Vec3,
    geometric: Vec3,
    normals: [Vec3; 3],
    uvs: Option<[Vec2; 3]>,
    colors: Option<[Vec3; 3]>,
    tangents: [Vec3; 2],
    /// From the first texture coordinates to the second.
    second: Affine2,
    /// Index into `Scene::materials`.
    pub material: usize,
}

/// The ray-independent data of a [`PreparedTriangle`], for batched shading.
#[derive(Debug, Clone, Copy)]
pub struct TriangleGeometry {
    /// First vertex, world space.
    pub a: Vec3,
    /// Second vertex minus the first.
    pub e1: Vec3,
    /// Third vertex minus the first.
    pub e2: Vec3,
    /// Unit geometric normal (used where the vertex normals cancel).
    pub geometric: Vec3,
    /// World-space vertex normals (not normalised).
    pub normals: [Vec3; 3],
    /// Vertex texture coordinates, if the mesh has them.
    pub uvs: Option<[Vec2; 3]>,
    /// Vertex colours, if the mesh has them ([`SurfacePoint::color`]).
    pub colors: Option<[Vec3; 3]>,
    /// ∂P/∂u and ∂P/∂v over the triangle ([`SurfacePoint::tangents`]).
    pub tangents: [Vec3; 2],
    /// From the first texture coordinates to the second ([`SurfacePoint::second`]).
    pub second: Affine2,
}

impl PreparedTriangle {
    /// The triangle's world-space data.
    #[must_use]
    pub fn geometry(&self) -> TriangleGeometry {
        TriangleGeometry {
            a: self.a,
            e1: self.e1,
            e2: self.e2,
            geometric: self.geometric,
            normals: self.normals,
            uvs: self.uvs,
            colors: self.colors,
            tangents: self.tangents,
            second: self.second,
        }
    }

    /// Whether its mesh has vertex colours (then its coefficients vary over
    /// it, as a texture's do).
    #[must_use]
    pub fn coloured(&self) -> bool {
        self.colors.is_some()
    }

    /// The texture coordinates where `ray` meets the triangle's plane (zero
    /// without them): [`PreparedTriangle::surface`]'s uv alone.
    #[must_use]
    pub fn uv(&self, ray: &Ray) -> Vec2 {
        if self.uvs.is_none() {
            return Vec2::ZERO;
        }
        let (_, b) = intersect_plane(ray, self.a, self.e1, self.e2);
        self.uv_at([1.0 - b.x - b.y, b.x, b.y])
    }

    /// Where `ray` meets the triangle's plane: the distance along it and the
    /// barycentric weights there.
    #[inline]
    fn hit(&self, ray: &Ray) -> (f32, [f32; 3]) {
        let (t, b) = intersect_plane(ray, self.a, self.e1, self.e2);
        (t, [1.0 - b.x - b.y, b.x, b.y])
    }

    /// The unit shading normal at barycentric weights `w`, turned towards
    /// `to_eye`.
    #[inline]
    fn normal_at(&self, w: [f32; 3], to_eye: Vec3) -> Vec3 {
        let n = self.normals[0] * w[0] + self.normals[1] * w[1] + self.normals[2] * w[2];
        let n = n.normalize_or(self.geometric);
        if n.dot(to_eye) < 0.0 {
            -n
        } else {
            n
        }
    }

    /// [`PreparedTriangle::surface`]'s position and normal alone.
    #[must_use]
    pub fn position_normal(&self, ray: &Ray) -> (Vec3, Vec3) {
        let (t, w) = self.hit(ray);
        (ray.origin + ray.dir * t, self.normal_at(w, -ray.dir))
    }

    /// The texture coordinates at barycentric weights `w` (zero without them).
    #[must_use]
    pub fn uv_at(&self, w: [f32; 3]) -> Vec2 {
        self.uvs.map_or(Vec2::ZERO, |u| u[0] * w[0] + u[1] * w[1] + u[2] * w[2])
    }

    /// The surface point where `ray` meets the triangle's plane.
    #[must_use]
    pub fn surface(&self, ray: &Ray) -> SurfacePoint {
        let (t, w) = self.hit(ray);
        self.surface_at(ray, t, w)
    }

    /// The surface point at distance `t` along `ray` (of unit direction),
    /// where the barycentric weights are `w` (found by the caller).
    #[must_use]
    pub fn surface_at(&self, ray: &Ray, t: f32, w: [f32; 3]) -> SurfacePoint {
        let to_eye = -ray.dir;
        let normal = self.normal_at(w, to_eye);
        let uv = self.uv_at(w);
        let front = self.geometric.dot(to_eye) >= 0.0;
        SurfacePoint {
            position: ray.origin + ray.dir * t,
            normal,
            to_eye,
            uv,
            duv: [Vec2::ZERO; 2],
            tangents: self.tangents,
            material: self.material,
            front,
            color: self.colors.map_or(Vec3::ONE, |c| c[0] * w[0] + c[1] * w[1] + c[2] * w[2]),
            second: self.second,
        }
    }
}

/// The affine map taking a point's first texture coordinates to its second
/// over the triangle of vertices `idx`: the one that takes each vertex's
/// first coordinates to its second. The identity where the mesh has no
/// second set; the second set's centroid where the first set spans no area
/// (a constant: no footprint).
fn second_coordinates(mesh: &crate::scene::Mesh, idx: [usize; 3]) -> Affine2 {
    if mesh.uvs1.is_empty() {
        return Affine2::IDENTITY;
    }
    let t = idx.map(|i| mesh.uvs1[i]);
    let s = idx.map(|i| mesh.uvs.get(i).copied().unwrap_or_default());
    let from = glam::Mat2::from_cols(s[1] - s[0], s[2] - s[0]);
    let to = glam::Mat2::from_cols(t[1] - t[0], t[2] - t[0]);
    let det = from.determinant();
    if det.abs() < 1e-12 || !det.is_finite() {
        return Affine2::from_translation((t[0] + t[1] + t[2]) / 3.0) * Affine2::from_scale(Vec2::ZERO);
    }
    let linear = to * from.inverse();
    Affine2::from_mat2_translation(linear, t[0] - linear * s[0])
}

/// ∂P/∂u and ∂P/∂v of the triangle with edges `e1`, `e2` (from its first
/// vertex) and texture coordinates `uv` at its vertices: the solution of
/// e1 = Δu₁·∂P/∂u + Δv₁·∂P/∂v, e2 = Δu₂·∂P/∂u + Δv₂·∂P/∂v; zero where the
/// texture coordinates do not span the triangle.
#[must_use]
pub fn position_derivatives(e1: Vec3, e2: Vec3, uv: [Vec2; 3]) -> [Vec3; 2] {
    let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let det = d1.x * d2.y - d2.x * d1.y;
    if !det.is_normal() {
        return [Vec3::ZERO; 2];
    }
    let inv = 1.0 / det;
    [(e1 * d2.y - e2 * d1.y) * inv, (e2 * d1.x - e1 * d2.x) * inv]
}

/// Intersects the ray with the PLANE of triangle (a, a + e1, a + e2) —
/// Möller–Trumbore without the inside test: a pixel centre that the fill rule gave
/// to this triangle may lie a hair outside it. Returns the distance along the
/// (unit) direction and the barycentrics (b1, b2).
#[must_use]
pub fn intersect_plane(ray: &Ray, a: Vec3, e1: Vec3, e2: Vec3) -> (f32, Vec2) {
    let pvec = ray.dir.cross(e2);
    let det = e1.dot(pvec);
    if det.abs() < f32::MIN_POSITIVE {
        // Seen edge-on: the point nearest the centroid is as good as any.
        let c = a + (e1 + e2) / 3.0;
        return ((c - ray.origin).dot(ray.dir), Vec2::splat(1.0 / 3.0));
    }
    let inv = 1.0 / det;
    let tvec = ray.origin - a;
    let qvec = tvec.cross(e1);
    (e2.dot(qvec) * inv, Vec2::new(tvec.dot(pvec) * inv, ray.dir.dot(qvec) * inv))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Mesh;

    /// The map between a triangle's two coordinate sets takes each vertex's
    /// first coordinates to its second, and so every point's (both are
    /// linear in the barycentric weights).
    #[test]
    fn the_second_coordinates_follow_the_first_over_a_triangle() {
        let mut mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            uvs: vec![Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.3), Vec2::new(0.2, 0.8)],
            ..Mesh::default()
        };
        mesh.uvs1 = vec![Vec2::new(0.5, 0.5), Vec2::new(0.5, 0.9), Vec2::new(0.1, 0.6)];
        let map = second_coordinates(&mesh, [0, 1, 2]);
        for w in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.2, 0.3, 0.5], [0.6, 0.1, 0.3]] {
            let at = |uv: &[Vec2]| uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2];
            let got = map.transform_point2(at(&mesh.uvs));
            assert!((got - at(&mesh.uvs1)).length() < 1e-5, "{got} vs {}", at(&mesh.uvs1));
        }
        mesh.uvs1.clear();
        assert_eq!(second_coordinates(&mesh, [0, 1, 2]), Affine2::IDENTITY);
    }
}
