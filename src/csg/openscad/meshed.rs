//! Where a node needs the surface of a subtree rather than its primitives —
//! the corners a `hull()` wraps, the box a `resize()` fits, the outline a
//! `projection()` draws — the subtree is built with OpenSCAD's facets and,
//! when it is not a plain union of convex parts, evaluated as a mesh by
//! Manifold's booleans (the engine OpenSCAD itself moved to).
//!
//! A union of convex parts needs no booleans: its corners and its box are its
//! parts' own.

use glam::{Affine3A, DVec2, Vec3};
use manifold_rust::linalg::Vec3 as MVec3;
use manifold_rust::manifold::Manifold;
use manifold_rust::types::OpType;

use super::flat::Region;
use super::syntax::CsgNode;
use super::{Builder, CsgOptions, Geometry};
use crate::csg::{ClosedMesh, CsgSolid, CsgTree};
use crate::error::Result;

impl Builder<'_> {
    /// `kids` placed by `m`, built as a solid of their own with OpenSCAD's
    /// facets (what `hull()`, `minkowski()` and `projection()` see).
    pub(super) fn faceted_solid(&mut self, kids: &[CsgNode], m: Affine3A) -> Result<CsgSolid> {
        let options = CsgOptions { geometry: Geometry::Faceted, ..self.options };
        let mut sub = Builder::new(&self.path, std::sync::Arc::clone(&self.text), options, self.limits, self.imports);
        sub.cutting = self.cutting;
        sub.ghostly = false;
        let tree = sub.union(kids, m, None)?.into_tree();
        self.warnings.append(&mut sub.warnings);
        Ok(CsgSolid { primitives: sub.solid.primitives, tree })
    }
}

/// Whether `tree` is a union of primitives (no part cut or intersected).
#[must_use]
pub(super) fn union_only(tree: &CsgTree) -> bool {
    match tree {
        CsgTree::Leaf(_) => true,
        CsgTree::Union(kids) => kids.iter().all(union_only),
        CsgTree::Intersection(_) | CsgTree::Difference(..) => false,
    }
}

/// A primitive as a Manifold mesh: a convex one the hull of its corners
/// (faceted: spheres and cylinders by their facets), a closed mesh's layer
/// (the first; the others add nothing to the union of layers) its triangles.
fn leaf(p: &crate::csg::Primitive) -> Manifold {
    let point = |c: Vec3| MVec3::new(c.x.into(), c.y.into(), c.z.into());
    match &p.shape {
        crate::csg::Shape::Mesh { mesh, layer } => {
            if *layer > 0 {
                return Manifold::empty();
            }
            let gl = manifold_rust::types::MeshGL {
                num_prop: 3,
                vert_properties: mesh
                    .positions()
                    .iter()
                    .flat_map(|v| p.transform.transform_point3(*v).to_array())
                    .collect(),
                tri_verts: mesh.triangles().iter().flatten().copied().collect(),
                ..Default::default()
            };
            Manifold::from_mesh_gl(&gl)
        }
        _ => Manifold::hull(&p.corners().into_iter().map(point).collect::<Vec<_>>()),
    }
}

/// The solid as a Manifold mesh: each primitive as [`leaf`] makes it,
/// combined along the tree.
#[must_use]
pub(super) fn to_manifold(solid: &CsgSolid) -> Manifold {
    fn of(solid: &CsgSolid, tree: &CsgTree) -> Manifold {
        let batch =
            |kids: &[CsgTree], op| Manifold::batch_boolean(&kids.iter().map(|k| of(solid, k)).collect::<Vec<_>>(), op);
        match tree {
            CsgTree::Leaf(i) => leaf(&solid.primitives[*i]),
            CsgTree::Union(kids) => batch(kids, OpType::Add),
            CsgTree::Intersection(kids) => batch(kids, OpType::Intersect),
            CsgTree::Difference(first, cutters) => {
                let cut = batch(cutters, OpType::Add);
                of(solid, first).difference(&cut)
            }
        }
    }
    solid.tree.as_ref().map_or_else(Manifold::empty, |t| of(solid, t))
}

/// A primitive's corners: a convex one's, a closed mesh's vertices (its
/// first layer's; the others repeat them).
fn corners(p: &crate::csg::Primitive) -> Vec<Vec3> {
    match &p.shape {
        crate::csg::Shape::Mesh { mesh, layer: 0 } => {
            mesh.positions().iter().map(|v| p.transform.transform_point3(*v)).collect()
        }
        crate::csg::Shape::Mesh { .. } => Vec::new(),
        _ => p.corners(),
    }
}

/// The corners of the solid's surface: its primitives' corners for a union
/// of convex parts, the mesh's vertices otherwise.
#[must_use]
pub(super) fn surface_points(solid: &CsgSolid) -> Vec<Vec3> {
    let Some(tree) = &solid.tree else { return Vec::new() };
    if union_only(tree) {
        return solid.primitives.iter().flat_map(corners).collect();
    }
    let mesh = to_manifold(solid).get_mesh_gl64(0);
    let stride = (mesh.num_prop as usize).max(3);
    mesh.vert_properties.chunks_exact(stride).map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect()
}

/// The solid's axis-aligned bounds `(min, max)`, `None` if it is empty.
#[must_use]
pub(super) fn surface_bounds(solid: &CsgSolid) -> Option<(Vec3, Vec3)> {
    let points = surface_points(solid);
    if points.is_empty() {
        return None;
    }
    Some(points.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p))))
}

/// `projection()`: the solid's shadow on the xy-plane, or with `cut` its
/// section by the plane z = 0.
#[must_use]
pub(super) fn projection(solid: &CsgSolid, cut: bool) -> Region {
    let mesh = to_manifold(solid);
    let section = if cut { mesh.slice(0.0) } else { mesh.project() };
    let contours: Vec<Vec<DVec2>> =
        section.to_polygons().into_iter().map(|c| c.into_iter().map(|p| DVec2::new(p.x, p.y)).collect()).collect();
    Region::non_zero(&contours)
}

/// The Minkowski sum of `solids` (each evaluated as a mesh), by Manifold,
/// as a closed mesh; `None` when it is empty.
#[must_use]
pub(super) fn minkowski_of_meshes(solids: &[CsgSolid]) -> Option<ClosedMesh> {
    let mut parts = solids.iter().map(to_manifold);
    let first = parts.next()?;
    let sum = parts.fold(first, |acc, part| acc.minkowski_sum(&part));
    closed_mesh(&sum)
}

/// A Manifold mesh as a closed mesh primitive.
#[must_use]
pub(super) fn closed_mesh(m: &Manifold) -> Option<ClosedMesh> {
    let mesh = m.get_mesh_gl64(0);
    let stride = (mesh.num_prop as usize).max(3);
    let positions: Vec<Vec3> =
        mesh.vert_properties.chunks_exact(stride).map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect();
    let triangles: Vec<[u32; 3]> =
        mesh.tri_verts.chunks_exact(3).map(|t| [t[0] as u32, t[1] as u32, t[2] as u32]).collect();
    ClosedMesh::new(positions, triangles)
}

/// The solid's surface as a triangle mesh (Manifold's booleans of its
/// faceted primitives): vertices and triangles wound outwards.
#[must_use]
pub fn surface_mesh(solid: &CsgSolid) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mesh = to_manifold(solid).get_mesh_gl64(0);
    let stride = (mesh.num_prop as usize).max(3);
    let positions =
        mesh.vert_properties.chunks_exact(stride).map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect();
    let triangles = mesh.tri_verts.chunks_exact(3).map(|t| [t[0] as u32, t[1] as u32, t[2] as u32]).collect();
    (positions, triangles)
}
