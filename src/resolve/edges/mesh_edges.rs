//! A mesh's edges for the edge pass: each edge with the faces on either side
//! (vertices welded by position, so a smooth sphere's UV seam is no edge),
//! whether the shading breaks across it (a crease), and each face's plane;
//! kept from frame to frame while the mesh lives ([`EdgeCache`]).

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use crate::scene::{Mesh, Scene};

/// A face is flat-shaded where each vertex normal is within 2.5° of the
/// face's normal.
const FLAT_COS: f32 = 0.999;

/// No face on this side of an edge.
pub(super) const NO_FACE: u32 = u32::MAX;

/// One edge of a mesh: two vertex indices and the faces on either side.
#[derive(Debug, Clone, Copy)]
pub(super) struct MeshEdge {
    pub(super) v: [u32; 2],
    pub(super) faces: [u32; 2],
    pub(super) crease: bool,
}

/// A mesh's edges, with vertices welded by position, and its face planes.
#[derive(Debug, Clone)]
pub struct MeshEdges {
    pub(super) edges: Vec<MeshEdge>,
    /// Per face: unit normal (xyz) and plane offset (w), `n·p = w` on the face.
    pub(super) planes: Vec<Vec4>,
    /// Per vertex: the first vertex at its position (the welded id).
    weld: Vec<u32>,
    /// Per face: whether it is flat-shaded (its vertex normals all its own).
    pub(super) flat: Vec<bool>,
    /// The mesh's bounds `(min, max)`.
    pub(super) bounds: (Vec3, Vec3),
}

impl MeshEdges {
    /// Finds every edge of `mesh` and the faces that share it. Edges with more than
    /// two faces are kept once per extra face, as boundaries.
    #[must_use]
    pub fn new(mesh: &Mesh, crease_deg: f32) -> MeshEdges {
        let planes: Vec<Vec4> = mesh
            .triangles
            .par_iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                let n = (b - a).cross(c - a).normalize_or_zero();
                n.extend(n.dot(a))
            })
            .collect();
        let weld = weld_by_position(&mesh.positions);
        let mut keyed: Vec<(u64, u32, [u32; 2])> = mesh
            .triangles
            .par_iter()
            .enumerate()
            .flat_map_iter(|(f, t)| {
                let weld = &weld;
                (0..3).map(move |k| {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    let (wa, wb) = (weld[a as usize], weld[b as usize]);
                    let key = (u64::from(wa.min(wb)) << 32) | u64::from(wa.max(wb));
                    (key, f as u32, [a, b])
                })
            })
            .filter(|(key, _, _)| (key >> 32) != (key & 0xffff_ffff))
            .collect();
        keyed.par_sort_unstable_by_key(|&(key, f, _)| (key, f));
        let cos_crease = crease_deg.to_radians().cos();
        let mut edges = Vec::with_capacity(keyed.len() / 2 + 1);
        let mut i = 0;
        while i < keyed.len() {
            let (key, f0, v) = keyed[i];
            let second = keyed.get(i + 1).filter(|e| e.0 == key).map(|e| e.1);
            let faces = [f0, second.unwrap_or(NO_FACE)];
            let crease = keyed.get(i + 1).filter(|_| second.is_some()).is_some_and(|e| {
                let [a, b] = v;
                // The other face's copies of this edge's two ends, matched by position.
                let [c, d] = if weld[e.2[0] as usize] == weld[a as usize] { e.2 } else { [e.2[1], e.2[0]] };
                let n = |i: u32| mesh.normals[i as usize];
                n(a).dot(n(c)) < cos_crease || n(b).dot(n(d)) < cos_crease
            });
            edges.push(MeshEdge { v, faces, crease });
            i += if second.is_some() { 2 } else { 1 };
        }
        let flat = mesh
            .triangles
            .par_iter()
            .zip(&planes)
            .map(|(t, plane)| {
                t.iter().all(|&v| mesh.normals[v as usize].normalize_or_zero().dot(plane.truncate()).abs() > FLAT_COS)
            })
            .collect();
        MeshEdges { edges, planes, weld, flat, bounds: mesh.bounds() }
    }

    /// The welded vertices of the faces beside edge `e`: a pixel showing a triangle
    /// that touches one of them shows the edge's own surface.
    pub(super) fn neighbourhood(&self, mesh: &Mesh, e: &MeshEdge) -> [u32; 6] {
        let mut out = [u32::MAX; 6];
        for (k, &f) in e.faces.iter().enumerate().filter(|(_, &f)| f != NO_FACE) {
            for (j, &v) in mesh.triangles[f as usize].iter().enumerate() {
                out[k * 3 + j] = self.weld[v as usize];
            }
        }
        out
    }

    /// Whether triangle `t` of `mesh` has a vertex among `near`.
    pub(super) fn touches(&self, mesh: &Mesh, t: u32, near: &[u32; 6]) -> bool {
        mesh.triangles.get(t as usize).is_some_and(|tri| tri.iter().any(|&v| near.contains(&self.weld[v as usize])))
    }
}

/// The objects of `scene` that are meshes, with their edges (`edges`, per
/// object, as [`EdgeCache::edges_of`] gives them): (index, object, mesh,
/// edges), in parallel.
pub(super) fn meshes_with_edges<'a>(
    scene: &'a Scene,
    edges: &'a [Option<Arc<MeshEdges>>],
) -> impl ParallelIterator<Item = (usize, &'a crate::scene::Object, &'a Mesh, &'a MeshEdges)> {
    scene
        .objects
        .par_iter()
        .zip(edges)
        .enumerate()
        .filter_map(|(index, (object, edges))| Some((index, object, object.triangles()?.as_ref(), edges.as_deref()?)))
}

/// Per vertex, the index of the first vertex at the same position, to a millionth
/// of the mesh's size (a seam's two copies of a vertex are often computed by
/// different formulas: sin 0 and sin 2π).
fn weld_by_position(positions: &[Vec3]) -> Vec<u32> {
    let (lo, hi) = positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), &p| (a.min(p), b.max(p)));
    let quantum = ((hi - lo).max_element() * 1e-6).max(f32::MIN_POSITIVE);
    let mut first: HashMap<[i64; 3], u32> = HashMap::with_capacity(positions.len());
    positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let cell = ((*p - lo) / quantum).round().to_array().map(|c| c as i64);
            *first.entry(cell).or_insert(i as u32)
        })
        .collect()
}

/// The edges of the meshes drawn last frame, kept while their meshes live (the
/// cache holds each `Arc<Mesh>`, so a mesh cannot change under its entry).
#[derive(Debug, Default)]
pub struct EdgeCache {
    /// Keyed by the mesh's address (only compared, never followed).
    meshes: HashMap<usize, (Arc<Mesh>, Arc<MeshEdges>)>,
    crease_deg: f32,
}

impl EdgeCache {
    /// The edges of every object's mesh, as [`EdgeCache::edges_of`], with the
    /// crease angle the cache was last asked for (the edge pass's default
    /// before that): feature lines read the faces beside each edge, not its
    /// crease flag.
    pub(super) fn edges_as_kept(&mut self, scene: &Scene) -> Vec<Option<Arc<MeshEdges>>> {
        let crease_deg = if self.crease_deg > 0.0 { self.crease_deg } else { super::EdgeOptions::default().crease_deg };
        self.edges_of(scene, crease_deg)
    }

    /// The edges of every object's mesh (index = object), found for the meshes not
    /// seen last frame; entries of meshes no longer drawn are dropped.
    pub(super) fn edges_of(&mut self, scene: &Scene, crease_deg: f32) -> Vec<Option<Arc<MeshEdges>>> {
        if self.crease_deg != crease_deg {
            self.meshes.clear();
            self.crease_deg = crease_deg;
        }
        let mut kept = HashMap::with_capacity(scene.objects.len());
        let edges = scene
            .objects
            .iter()
            .map(|o| {
                let mesh = o.triangles()?;
                let key = Arc::as_ptr(mesh) as usize;
                let entry = kept.entry(key).or_insert_with(|| {
                    self.meshes
                        .remove(&key)
                        .unwrap_or_else(|| (Arc::clone(mesh), Arc::new(MeshEdges::new(mesh, crease_deg))))
                });
                Some(Arc::clone(&entry.1))
            })
            .collect();
        self.meshes = kept;
        edges
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::shapes;

    #[test]
    fn a_flat_shaded_cube_is_flat_and_a_smooth_sphere_is_not() {
        let cube = MeshEdges::new(&crate::scene::mesh::shapes::cube(), 30.0);
        assert!(cube.flat.len() == 12 && cube.flat.iter().all(|&f| f));
        let sphere = MeshEdges::new(&crate::scene::mesh::shapes::sphere(12), 30.0);
        assert!(sphere.flat.iter().all(|&f| !f), "a smooth sphere's faces turn within each face");
    }

    #[test]
    fn a_welded_sphere_has_no_boundary_and_a_cube_twelve_creases() {
        let sphere = MeshEdges::new(&shapes::sphere(16), 30.0);
        assert!(sphere.edges.iter().all(|e| e.faces[1] != NO_FACE && !e.crease), "closed and smooth");
        let cube = MeshEdges::new(&shapes::cube(), 30.0);
        assert_eq!(cube.edges.iter().filter(|e| e.crease).count(), 12);
        assert!(cube.edges.iter().all(|e| e.faces[1] != NO_FACE));
    }

    #[test]
    fn a_crease_is_where_the_shading_normals_break_not_where_the_surface_folds() {
        // Two triangles folded 90° along the edge (0,0,0)-(1,0,0).
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let triangles = vec![[0, 1, 2], [1, 0, 3]];
        let fold = |mode| crate::scene::Mesh::new(positions.clone(), Vec::new(), Vec::new(), triangles.clone(), mode);
        let creases = |mesh: &crate::scene::Mesh| MeshEdges::new(mesh, 30.0).edges.iter().filter(|e| e.crease).count();
        let (smooth, _) = fold(crate::scene::mesh::NormalMode::Smooth).unwrap();
        let (flat, _) = fold(crate::scene::mesh::NormalMode::Flat).unwrap();
        assert_eq!(creases(&smooth), 0, "shared normals: the shading is continuous across the fold");
        assert_eq!(creases(&flat), 1, "face normals: the shading breaks at the fold");
    }
}
