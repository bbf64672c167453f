//! OpenSCAD's 3-D primitives — `cube`, `sphere`, `cylinder`, `polyhedron` —
//! as exact quadrics or as the convex polyhedra of OpenSCAD's own facets.

use std::f32::consts::PI;

use glam::{Affine3A, Vec3, Vec4};

use glam::DVec3;

use super::hull::{bounds_size, convex_from_faces};
use super::syntax::CsgNode;
use super::{Builder, Geometry};
use crate::csg::{ClosedMesh, ConvexPolyhedron, Primitive, Shape};
use crate::error::Result;
use crate::limits::Limit;
use crate::polygon::face_triangles;

/// What a primitive node makes.
pub(super) enum Made {
    /// A convex primitive.
    Convex(Primitive),
    /// A closed mesh (unplaced: its faces as written).
    Mesh(ClosedMesh),
}

/// A `polyhedron()`, convex or not.
pub(super) enum Polyhedron {
    Convex(ConvexPolyhedron),
    Mesh(ClosedMesh),
}

/// Faces (polygons of corner indices into `points`) cut into triangles,
/// wound as each face is (a face may be concave: see [`crate::polygon`]).
#[must_use]
pub(super) fn triangulated(points: &[Vec3], faces: &[Vec<usize>]) -> Vec<[u32; 3]> {
    let points: Vec<DVec3> = points.iter().map(|p| p.as_dvec3()).collect();
    let mut out = Vec::with_capacity(faces.len() * 2);
    for f in faces {
        let face: Vec<u32> = f.iter().map(|&i| i as u32).collect();
        face_triangles(&points, &face, &mut out);
    }
    out
}

/// `$fn` at or below which spheres and cylinders stay faceted in exact mode.
const ALWAYS_FACETED_FN: f64 = 8.0;

impl Builder<'_> {
    /// Whether a sphere or cylinder is made of facets.
    pub(super) fn faceted(&self, node: &CsgNode) -> Result<bool> {
        let fine = self.number_or(node, "$fn", 0.0)?;
        Ok(self.options.geometry == Geometry::Faceted || (fine > 0.0 && fine <= ALWAYS_FACETED_FN))
    }

    /// A primitive node as a convex primitive or a closed mesh (a
    /// polyhedron that is not convex), or `None` if it has no volume.
    pub(super) fn primitive(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Option<Made>> {
        let made = match node.name.as_str() {
            "cube" => self.cube(node)?,
            "sphere" => self.sphere(node)?,
            "cylinder" => self.cylinder(node)?,
            _ => match self.polyhedron(node)? {
                None => None,
                Some(Polyhedron::Convex(p)) => Some((Shape::Polyhedron(p), Affine3A::IDENTITY)),
                Some(Polyhedron::Mesh(mesh)) => return Ok(Some(Made::Mesh(mesh))),
            },
        };
        Ok(made.map(|(shape, local)| {
            Made::Convex(Primitive { shape, transform: m * local, color, source: node.span.clone() })
        }))
    }

    pub(super) fn cube(&self, node: &CsgNode) -> Result<Option<(Shape, Affine3A)>> {
        let size = Vec3::from_slice(&self.floats(node, Some("size"), 3)?);
        if !(size.min_element() > 0.0 && size.is_finite()) {
            return Ok(None);
        }
        let offset = if self.flag(node, "center")? { -size * 0.5 } else { Vec3::ZERO };
        Ok(Some((
            Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
            Affine3A::from_scale_rotation_translation(size, glam::Quat::IDENTITY, offset),
        )))
    }

    pub(super) fn sphere(&self, node: &CsgNode) -> Result<Option<(Shape, Affine3A)>> {
        let r = self.number(node, "r")? as f32;
        if !(r > 0.0 && r.is_finite()) {
            return Ok(None);
        }
        let n = self.fragments(node, r)?;
        if !self.faceted(node)? {
            return Ok(Some((Shape::Sphere, Affine3A::from_scale(Vec3::splat(r)))));
        }
        // OpenSCAD's sphere: (n + 1) / 2 rings of n vertices, flat caps, no poles.
        let rings = n.div_ceil(2);
        let facets = (n * (rings - 1) + 2) as u64;
        if let Err(e) = self.limits.check(Limit::Facets, facets, || "this faceted sphere".into()) {
            return Err(self.invalid(&node.span, e.to_string()));
        }
        let points: Vec<Vec3> = (0..rings)
            .flat_map(|k| {
                let phi = PI * (k as f32 + 0.5) / rings as f32;
                circle(n, r * phi.sin(), r * phi.cos())
            })
            .collect();
        let mut faces: Vec<Vec<usize>> = vec![(0..n).collect(), ((rings - 1) * n..rings * n).collect()];
        for k in 0..rings - 1 {
            faces.extend(
                (0..n).map(|i| vec![k * n + i, k * n + (i + 1) % n, (k + 1) * n + (i + 1) % n, (k + 1) * n + i]),
            );
        }
        Ok(Some((Shape::Polyhedron(convex_from_faces(points, &faces)), Affine3A::IDENTITY)))
    }

    pub(super) fn cylinder(&self, node: &CsgNode) -> Result<Option<(Shape, Affine3A)>> {
        let h = self.number(node, "h")? as f32;
        let (r1, r2) = (self.number(node, "r1")? as f32, self.number(node, "r2")? as f32);
        let big = r1.max(r2);
        if !(h > 0.0 && h.is_finite() && big > 0.0 && big.is_finite() && r1 >= 0.0 && r2 >= 0.0) {
            return Ok(None);
        }
        let z0 = if self.flag(node, "center")? { -h * 0.5 } else { 0.0 };
        if !self.faceted(node)? {
            let to_solid = Affine3A::from_scale_rotation_translation(
                Vec3::new(big, big, h),
                glam::Quat::IDENTITY,
                Vec3::new(0.0, 0.0, z0),
            );
            return Ok(Some((Shape::Frustum { bottom: r1 / big, top: r2 / big }, to_solid)));
        }
        // OpenSCAD's cylinder: two n-gons (a point where a radius is 0) joined by
        // quads or triangles.
        let n = self.fragments(node, big)?;
        let ring = |r: f32, z: f32| if r > 0.0 { circle(n, r, z) } else { vec![Vec3::new(0.0, 0.0, z)] };
        let (bottom, top) = (ring(r1, z0), ring(r2, z0 + h));
        let (nb, nt) = (bottom.len(), top.len());
        let mut faces = Vec::new();
        for i in 0..n {
            let mut f = vec![i % nb, (i + 1) % nb, nb + (i + 1) % nt, nb + i % nt];
            f.dedup();
            if f.first() == f.last() && f.len() > 1 {
                f.pop();
            }
            faces.push(f);
        }
        faces.extend([(0..nb).collect::<Vec<_>>(), (nb..nb + nt).collect()].into_iter().filter(|f| f.len() >= 3));
        let points = bottom.into_iter().chain(top).collect();
        Ok(Some((Shape::Polyhedron(convex_from_faces(points, &faces)), Affine3A::IDENTITY)))
    }

    /// `polyhedron()`: convex (its planes), or a closed mesh of its faces,
    /// each face cut into triangles.
    pub(super) fn polyhedron(&self, node: &CsgNode) -> Result<Option<Polyhedron>> {
        let points = self.list(node, "points")?;
        self.check(node, Limit::Points, points.len() as u64, || "this polyhedron's points".into())?;
        let points: Vec<Vec3> = points.iter().map(|p| self.vec3(node, "points", p)).collect::<Result<_>>()?;
        let faces = self.index_lists(node, "faces", points.len())?;
        if points.len() < 4 || faces.len() < 4 {
            return Ok(None);
        }
        let poly = convex_from_faces(points, &faces);
        let size = bounds_size(&poly.vertices);
        let eps = 1e-4 * size.max(f32::MIN_POSITIVE);
        if poly.vertices.iter().all(|v| poly.contains(*v, eps)) {
            return Ok(Some(Polyhedron::Convex(poly)));
        }
        let triangles = triangulated(&poly.vertices, &faces);
        Ok(ClosedMesh::new(poly.vertices, triangles).map(Polyhedron::Mesh))
    }
}

/// `n` points on the circle of radius `r` at height `z`, the first on +x.
fn circle(n: usize, r: f32, z: f32) -> Vec<Vec3> {
    (0..n)
        .map(|i| {
            let a = 2.0 * PI * i as f32 / n as f32;
            Vec3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect()
}
