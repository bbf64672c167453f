//! Antialiased edges after an aliased fill: seed 004 (Kato & Kameyama, "A fast and
//! simple antialiased polygon rendering", §3 (2)).
//!
//! Pass 1 (the visibility pass and shading) leaves every pixel entirely one surface:
//! the one whose triangle covers the pixel centre. Pass 2 walks the edges with a DDA
//! along each edge's major axis. At column i (an x-major edge; y-major edges are the
//! same with the axes swapped, through one walker) the edge's true height is `Y_i`;
//! the pixels `P_i` above and `Q_i` below have their centres on either side of it, at
//! distances `D_P` and `D_Q = 1 − D_P`. The paper blends the edge's colour into both,
//! with alphas `Filter(D_Q)` and `Filter(D_P)`, z-tested and never z-written, so a
//! partly covered pixel never hides anything.
//!
//! What kage makes of the paper's open points (measured in `docs/benchmarks.md`):
//!
//! - Alpha. Of the two pixels only the one whose square the edge crosses is wrong
//!   after the aliased fill: the other lies wholly on its centre's side. The wrong
//!   one, `C` (the nearer, at distance `d = min(D_P, D_Q) < ½`), shows its centre's
//!   side but has `½ − d` of its area on the far side of the edge. So `C` takes the
//!   colour of the pixel across the edge, `O`, with alpha `Filter(d) = ½ − d`:
//!   `C ← C + (½ − d)·(O − C)`. When `C` lies outside the polygon this is the
//!   paper's blend of the edge colour (the colour of the surface next to the edge);
//!   when `C` lies inside, it brings back the background the fill covered, which
//!   blending the edge colour alone cannot — without it a straight edge is drawn half
//!   a pixel too fat on every other column. For a straight edge the result is the
//!   pixel's exact covered area along the major axis.
//! - Gamma. The frame is linear light, so blending there is the gamma-corrected
//!   filter the paper asks for; the sRGB curve is applied at output.
//! - Which edges. By default the outline: silhouette edges (one adjacent face towards
//!   the eye, one away), mesh boundaries and creases (adjacent face normals more than
//!   [`EdgeOptions::crease_deg`] apart), with vertices welded by position so the UV
//!   seam of a smooth sphere is not an edge. [`EdgeSelection::All`] walks every
//!   triangle edge, as the paper does.
//! - Depth test. Each pixel is classed against the edge's depth at that point: the
//!   edge's own surface (same object, depth within 5%), an occluder (nearer) or what
//!   lies behind. Nothing is blended where either pixel is an occluder, so a hidden
//!   edge never bleeds through; the blend happens when at least one pixel is the
//!   edge's own surface. The pixel across the edge is always read from the frame as
//!   pass 1 left it.
//! - Order. Every edge's blends are computed from the unchanged pass-1 frame and
//!   applied in scene order (object, then edge), so the result does not depend on
//!   threads.
//! - The same blends are applied to every component image (`--aov`): each is linear
//!   in the image, so the components still sum to the frame.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DVec4, Mat4, Vec3, Vec4};
use rayon::prelude::*;

use super::LinearImage;
use crate::scene::{Camera, Mesh, Projection, Scene};
use crate::visibility::VisibilityBuffer;

/// Which edges the edge pass walks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EdgeSelection {
    /// Silhouettes, mesh boundaries and creases.
    #[default]
    Outline,
    /// Every triangle edge with a face towards the eye (the paper).
    All,
}

/// How the edge pass runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeOptions {
    /// Which edges.
    pub selection: EdgeSelection,
    /// Adjacent faces whose normals differ by more than this (degrees) meet at a
    /// crease, which is drawn like a silhouette.
    pub crease_deg: f32,
}

impl Default for EdgeOptions {
    fn default() -> Self {
        EdgeOptions { selection: EdgeSelection::Outline, crease_deg: 30.0 }
    }
}

/// No face on this side of an edge.
const NO_FACE: u32 = u32::MAX;

/// One edge of a mesh: two vertex indices and the faces on either side.
#[derive(Debug, Clone, Copy)]
struct MeshEdge {
    v: [u32; 2],
    faces: [u32; 2],
    crease: bool,
}

/// A mesh's edges, with vertices welded by position, and its face planes.
#[derive(Debug, Clone)]
pub struct MeshEdges {
    edges: Vec<MeshEdge>,
    /// Per face: unit normal (xyz) and plane offset (w), `n·p = w` on the face.
    planes: Vec<Vec4>,
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
            let crease = second
                .is_some_and(|f1| planes[f0 as usize].truncate().dot(planes[f1 as usize].truncate()) < cos_crease);
            edges.push(MeshEdge { v, faces, crease });
            i += if second.is_some() { 2 } else { 1 };
        }
        MeshEdges { edges, planes }
    }

    /// Number of edges.
    #[must_use]
    pub fn len(&self) -> usize {
        self.edges.len()
    }

    /// Whether the mesh has no edges.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }
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
    /// The edges of every object's mesh (index = object), found for the meshes not
    /// seen last frame; entries of meshes no longer drawn are dropped.
    fn edges_of(&mut self, scene: &Scene, crease_deg: f32) -> Vec<Arc<MeshEdges>> {
        if self.crease_deg != crease_deg {
            self.meshes.clear();
            self.crease_deg = crease_deg;
        }
        let mut kept = HashMap::with_capacity(scene.objects.len());
        let edges = scene
            .objects
            .iter()
            .map(|o| {
                let key = Arc::as_ptr(&o.mesh) as usize;
                let entry = kept.entry(key).or_insert_with(|| {
                    self.meshes
                        .remove(&key)
                        .unwrap_or_else(|| (Arc::clone(&o.mesh), Arc::new(MeshEdges::new(&o.mesh, crease_deg))))
                });
                Arc::clone(&entry.1)
            })
            .collect();
        self.meshes = kept;
        edges
    }
}

/// One blend of the edge pass: pixel `c` moves towards pixel `o` by `alpha`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeBlend {
    /// The pixel the edge crosses (row-major index).
    pub c: u32,
    /// The pixel across the edge.
    pub o: u32,
    /// The share of `c`'s area on `o`'s side of the edge (≤ ½).
    pub alpha: f32,
}

/// What the edge pass did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EdgeStats {
    /// Edges walked (after selection and clipping).
    pub edges: usize,
    /// Pixel blends applied.
    pub blends: usize,
}

/// Runs seed 004's edge pass over the frame: finds the blends from `vb` and the
/// frame `images[0]` as pass 1 left it, then applies them to every image in
/// `images` (the frame and its component images, same size as `vb`).
pub fn antialias_edges(
    scene: &Scene,
    vb: &VisibilityBuffer,
    images: &mut [&mut LinearImage],
    options: &EdgeOptions,
    cache: &mut EdgeCache,
) -> EdgeStats {
    let edges = cache.edges_of(scene, options.crease_deg);
    let (blends, walked) = find_blends(scene, vb, &edges, options.selection);
    for image in images.iter_mut() {
        apply(image, &blends);
    }
    EdgeStats { edges: walked, blends: blends.len() }
}

/// Every blend, in scene order (object, then edge), and the number of edges walked.
fn find_blends(
    scene: &Scene,
    vb: &VisibilityBuffer,
    edges: &[Arc<MeshEdges>],
    selection: EdgeSelection,
) -> (Vec<EdgeBlend>, usize) {
    let camera = &scene.camera;
    let (w, h) = (vb.width(), vb.height());
    let view_proj = camera.view_projection(w as f32 / h as f32);
    let depth = DepthScale::of(camera);
    let mut blends = Vec::new();
    let mut walked = 0;
    for (object, (o, mesh_edges)) in scene.objects.iter().zip(edges).enumerate() {
        let material = &scene.materials[o.material];
        if material.translucent() {
            continue; // blended over the opaque frame later; its edges are not walked
        }
        let facing = Facing::new(camera, o.transform.inverse());
        let to_clip = (view_proj * Mat4::from(o.transform)).as_dmat4();
        let screen = Screen { width: w as f64, height: h as f64, far: f64::from(camera.far_plane_factor()) };
        let per_edge: Vec<Vec<EdgeBlend>> = mesh_edges
            .edges
            .par_iter()
            .filter(|e| selected(e, mesh_edges, &facing, material.two_sided, selection))
            .filter_map(|e| {
                let [a, b] = e.v.map(|i| to_clip * o.mesh.positions[i as usize].as_dvec3().extend(1.0));
                let (a, b) = screen.clip_and_project(a, b)?;
                let mut out = Vec::new();
                let visit = |c, other, alpha, z| {
                    if let Some(blend) = depth_tested(vb, object as u32, c, other, alpha, z, &depth) {
                        out.push(blend);
                    }
                };
                walk(a, b, visit, (w, h));
                Some(out)
            })
            .collect();
        walked += per_edge.len();
        blends.extend(per_edge.into_iter().flatten());
    }
    (blends, walked)
}

/// `c ← c + alpha·(o − c)` for every blend, reading `o` and `c` as they were
/// before any blend.
fn apply(image: &mut LinearImage, blends: &[EdgeBlend]) {
    let deltas: Vec<Vec3> = {
        let px = image.pixels();
        blends.iter().map(|b| (px[b.o as usize] - px[b.c as usize]) * b.alpha).collect()
    };
    let px = image.pixels_mut();
    for (b, d) in blends.iter().zip(deltas) {
        px[b.c as usize] += d;
    }
}

/// Which faces look at the eye, tested in the object's own space (the sign of a
/// point's side of a plane survives any affine map).
struct Facing {
    /// Perspective: the eye in object space; orthographic: the direction towards
    /// the eye in object space, with w = 0.
    eye: Vec4,
}

impl Facing {
    fn new(camera: &Camera, world_to_object: glam::Affine3A) -> Facing {
        let eye = match camera.projection {
            Projection::Perspective { .. } => world_to_object.transform_point3(camera.eye).extend(1.0),
            Projection::Orthographic { .. } => {
                world_to_object.transform_vector3(camera.eye - camera.target).extend(0.0)
            }
        };
        Facing { eye }
    }

    /// Whether face `plane` (n, n·p) has the eye on its front side.
    fn front(&self, plane: Vec4) -> bool {
        plane.truncate().dot(self.eye.truncate()) - plane.w * self.eye.w > 0.0
    }
}

fn selected(e: &MeshEdge, mesh: &MeshEdges, facing: &Facing, two_sided: bool, selection: EdgeSelection) -> bool {
    let front = |f: u32| f != NO_FACE && (two_sided || facing.front(mesh.planes[f as usize]));
    let (f0, f1) = (front(e.faces[0]), front(e.faces[1]));
    if !(f0 || f1) {
        return false; // both faces culled: nothing of it is drawn
    }
    match selection {
        EdgeSelection::All => true,
        EdgeSelection::Outline => {
            let boundary = e.faces[1] == NO_FACE;
            let silhouette = !boundary
                && (facing.front(mesh.planes[e.faces[0] as usize]) != facing.front(mesh.planes[e.faces[1] as usize]));
            boundary || silhouette || e.crease
        }
    }
}

/// Clip space to the pixel grid, as the polygon pass maps it.
struct Screen {
    width: f64,
    height: f64,
    /// The far plane `z = far·w` (reversed depth).
    far: f64,
}

impl Screen {
    /// The part of segment `a`–`b` (clip space) between the near (`z ≤ w`) and far
    /// (`z ≥ far·w`) planes, as screen points (x, y in pixels, z = depth).
    fn clip_and_project(&self, mut a: DVec4, mut b: DVec4) -> Option<(glam::DVec3, glam::DVec3)> {
        for plane in [DVec4::new(0.0, 0.0, -1.0, 1.0), DVec4::new(0.0, 0.0, 1.0, -self.far)] {
            let (da, db) = (plane.dot(a), plane.dot(b));
            if da < 0.0 && db < 0.0 {
                return None;
            }
            if da < 0.0 {
                a = b + (a - b) * (db / (db - da));
            } else if db < 0.0 {
                b = a + (b - a) * (da / (da - db));
            }
        }
        let project = |c: DVec4| {
            let inv_w = 1.0 / c.w;
            glam::DVec3::new(
                (c.x * inv_w * 0.5 + 0.5) * self.width,
                (0.5 - c.y * inv_w * 0.5) * self.height,
                c.z * inv_w,
            )
        };
        (a.w > 0.0 && b.w > 0.0).then(|| (project(a), project(b)))
    }
}

/// The DDA of pass 2, one walker for both axes: steps along the major axis through
/// every pixel centre the segment spans, finds the true edge position on the minor
/// axis and calls `visit(c, o, alpha, z)` for the pixel `c` whose square the edge
/// crosses, the pixel `o` across the edge, the share of `c` on `o`'s side and the
/// edge's depth there. Pixels are (x, y); pairs reaching outside the image are
/// skipped.
fn walk(a: glam::DVec3, b: glam::DVec3, mut visit: impl FnMut((u32, u32), (u32, u32), f32, f32), size: (u32, u32)) {
    let swap = (b.y - a.y).abs() > (b.x - a.x).abs();
    // (major, minor, depth) of each end, ordered along the major axis.
    let axes = |p: glam::DVec3| if swap { (p.y, p.x, p.z) } else { (p.x, p.y, p.z) };
    let (mut s, mut e) = (axes(a), axes(b));
    if s.0 > e.0 {
        std::mem::swap(&mut s, &mut e);
    }
    let length = e.0 - s.0;
    let (major_size, minor_size) = if swap { (size.1, size.0) } else { (size.0, size.1) };
    if length < 1e-9 {
        return;
    }
    // Centres i + ½ in [start, end): two edges meeting at a vertex share no column.
    let first = (s.0 - 0.5).ceil().max(0.0);
    let last = ((e.0 - 0.5).ceil() - 1.0).min(f64::from(major_size) - 1.0);
    let to_xy = |major: u32, minor: u32| if swap { (minor, major) } else { (major, minor) };
    let mut i = first;
    while i <= last {
        let t = (i + 0.5 - s.0) / length;
        let minor = s.1 + t * (e.1 - s.1) - 0.5; // in pixel-centre units
        let above = minor.floor();
        let d = minor - above; // distance from the centre before the edge
        let (c, o, dist) = if d < 0.5 { (above, above + 1.0, d) } else { (above + 1.0, above, 1.0 - d) };
        let inside = |k: f64| k >= 0.0 && k < f64::from(minor_size);
        if inside(c) && inside(o) && dist < 0.5 {
            let z = s.2 + t * (e.2 - s.2);
            visit(to_xy(i as u32, c as u32), to_xy(i as u32, o as u32), (0.5 - dist) as f32, z as f32);
        }
        i += 1.0;
    }
}

/// View distance from stored depth, to compare depths relatively.
struct DepthScale {
    projection: Projection,
    near: f32,
    far: f32,
}

impl DepthScale {
    fn of(camera: &Camera) -> DepthScale {
        DepthScale { projection: camera.projection, near: camera.near, far: camera.far }
    }

    fn distance(&self, z: f32) -> f32 {
        match self.projection {
            Projection::Perspective { .. } => self.near / z.max(f32::MIN_POSITIVE),
            Projection::Orthographic { .. } => self.far - z * (self.far - self.near),
        }
    }

    /// Whether depths `a` and `b` are within 5% of each other's distance.
    fn close(&self, a: f32, b: f32) -> bool {
        let (da, db) = (self.distance(a), self.distance(b));
        (da - db).abs() <= 0.05 * db
    }
}

/// How a pixel relates to the edge at the edge's depth `z`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    /// The edge's own surface (same object, about the same depth).
    Own,
    /// Something nearer than the edge: the edge is hidden there.
    Occluder,
    /// Something behind the edge (or the background).
    Behind,
}

/// The blend of `c` towards `o` if the depth test lets the edge show: neither pixel
/// hides it, and one of them is its own surface.
fn depth_tested(
    vb: &VisibilityBuffer,
    object: u32,
    c: (u32, u32),
    o: (u32, u32),
    alpha: f32,
    z: f32,
    scale: &DepthScale,
) -> Option<EdgeBlend> {
    let w = vb.width();
    let index = |(x, y): (u32, u32)| y * w + x;
    let side = |p: (u32, u32)| {
        let i = index(p) as usize;
        let (zp, item) = (vb.depths()[i], vb.items()[i]);
        if !item.is_none() && item.object == object && scale.close(zp, z) {
            Side::Own
        } else if zp > z {
            Side::Occluder
        } else {
            Side::Behind
        }
    };
    let (sc, so) = (side(c), side(o));
    let shows = sc != Side::Occluder && so != Side::Occluder && (sc == Side::Own || so == Side::Own);
    shows.then(|| EdgeBlend { c: index(c), o: index(o), alpha })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::shapes;

    #[test]
    fn a_welded_sphere_has_no_boundary_and_a_cube_twelve_creases() {
        let sphere = MeshEdges::new(&shapes::sphere(16), 30.0);
        assert!(sphere.edges.iter().all(|e| e.faces[1] != NO_FACE && !e.crease), "closed and smooth");
        let cube = MeshEdges::new(&shapes::cube(), 30.0);
        assert_eq!(cube.edges.iter().filter(|e| e.crease).count(), 12);
        assert!(cube.edges.iter().all(|e| e.faces[1] != NO_FACE));
    }

    #[test]
    fn the_walker_visits_each_major_column_once_with_the_exact_alpha() {
        // y = 0.3·x + 2.2 from x = 0 to 10: x-major; at column i the edge is at
        // y = 0.3·(i + ½) + 2.2.
        let mut seen = Vec::new();
        let a = glam::DVec3::new(0.0, 2.2, 0.5);
        let b = glam::DVec3::new(10.0, 5.2, 0.5);
        walk(a, b, |c, o, alpha, _| seen.push((c, o, alpha)), (20, 20));
        let swapped = {
            let mut v = Vec::new();
            let t = |p: glam::DVec3| glam::DVec3::new(p.y, p.x, p.z);
            walk(t(b), t(a), |c, o, alpha, _| v.push(((c.1, c.0), (o.1, o.0), alpha)), (20, 20));
            v
        };
        assert_eq!(seen, swapped, "y-major is x-major with the axes swapped");
        let columns: Vec<u32> = seen.iter().map(|s| s.0 .0).collect();
        assert_eq!(columns.len(), columns.iter().collect::<std::collections::HashSet<_>>().len());
        for ((cx, cy), (ox, oy), alpha) in seen {
            let y = 0.3 * (cx as f32 + 0.5) + 2.2;
            assert_eq!(cx, ox);
            assert!(cy as f32 <= y && y <= cy as f32 + 1.0, "the edge crosses pixel {cy} at {y}");
            // Share of the pixel on the other pixel's side of the edge.
            let other_side = if oy > cy { cy as f32 + 1.0 - y } else { y - cy as f32 };
            assert!((alpha - other_side).abs() < 1e-5, "alpha {alpha} vs {other_side}");
        }
    }
}
