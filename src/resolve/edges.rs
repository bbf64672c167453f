//! Antialiased edges after an aliased fill: seed 004 (Kato & Kameyama, "A fast and
//! simple antialiased polygon rendering", §3 (2)).
//!
//! Pass 1 (the visibility pass and shading) leaves every pixel entirely one surface:
//! the one whose triangle covers the pixel centre. Pass 2 walks the edges with a DDA
//! along each edge's major axis. At column i (an x-major edge; y-major edges are the
//! same with the axes swapped, through one walker: `super::dda`) the edge's true height is `Y_i`;
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
//!   a pixel too fat on every other column. Where the edge's line crosses two rows
//!   of a column, both crossed pixels are blended, each by its own share, so for a
//!   straight edge every pixel ends at its exact covered area. The paper's weights
//!   are kept as [`EdgeFilter::Paper`], to measure against.
//! - The parts' colours. The paper's colours come from pass 1's pixel centres;
//!   but a part of a pixel beyond a silhouette can lie in a shadow that begins
//!   right behind the silhouette, and a grazing surface's shading changes fast
//!   within one pixel. So the blends are found from the visibility buffer alone
//!   ([`plan`], while the first pass shades the pixels:
//!   [`crate::shading::shade_lit_while`]), and a part's colour is its pixel's
//!   moved by how the shading changes from the pixel's centre to the part's
//!   centroid: shaded there by the passes themselves
//!   (parts beyond edges, and own parts on curved surfaces), or stepped along the
//!   colours of the pixel's neighbours (own parts on flat faces): `super::parts`.
//!   Measured: this takes the bunny from 57% to 65% of the aliased edge error
//!   removed, spotlights from 51% to 61%.
//! - Intersections. Where two objects pass through each other (a box standing
//!   in a floor) the outline is no mesh edge: `super::intersections` finds it from
//!   the two pixels' depth planes, and it is blended like an edge.
//! - Gamma. The frame is linear light, so blending there is the gamma-corrected
//!   filter the paper asks for; the sRGB curve is applied at output.
//! - Which edges. By default the outline: silhouette edges (one adjacent face towards
//!   the eye, one away), mesh boundaries and creases, with vertices welded by
//!   position so the UV seam of a smooth sphere is not an edge. A crease is where
//!   the shading breaks: the two faces' vertex normals at an end of the edge differ
//!   by more than [`EdgeOptions::crease_deg`] (a flat-shaded mesh breaks at every
//!   fold; a smooth-shaded one, however sharply folded, has no crease to smooth —
//!   blending across its folds only blurred a scanned model's detail). [`EdgeSelection::All`] walks every
//!   triangle edge, as the paper does.
//! - Depth test. Each pixel is classed against the edge: the edge's own surface (it
//!   shows a triangle that touches a face beside the edge), else by depth against
//!   the edge's depth at that point: an occluder (nearer) or what lies behind. (A
//!   depth tolerance alone cannot tell a visible silhouette, whose inside pixels lie
//!   a few per cent nearer at grazing angles, from the hidden silhouette of the same
//!   object's far side a few per cent farther.)
//!   An occluder is judged at the edge's point, not at its pixel's centre: the
//!   pixel's surface plane carried to the point must lie nearer than the edge
//!   (beyond rounding) (a floor pixel just below a box standing on it lies nearer than
//!   the box's bottom edge, but the floor meets that edge). Nothing is blended
//!   where either pixel is an occluder, so a hidden
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

use glam::{DVec3, DVec4, Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::dda::{walk, PartBeyond};
pub use super::parts::{EdgePlan, RESHADED_SHARE};
use super::{intersections, PixelSet};
use crate::camera::{Camera, Projection};
use crate::scene::{EdgeFilter, EdgeMode, EdgeSelection, Mesh, Scene};
use crate::visibility::{ItemId, VisibilityBuffer};

/// How the edge pass runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeOptions {
    /// Which edges and how they blend.
    pub mode: EdgeMode,
    /// Adjacent faces whose vertex normals at a shared end differ by more than
    /// this (degrees) meet at a crease, which is drawn like a silhouette.
    pub crease_deg: f32,
}

impl Default for EdgeOptions {
    fn default() -> Self {
        EdgeOptions { mode: EdgeMode::default(), crease_deg: 30.0 }
    }
}

/// A face is flat-shaded where each vertex normal is within 2.5° of the
/// face's normal.
const FLAT_COS: f32 = 0.999;

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
    /// Per vertex: the first vertex at its position (the welded id).
    weld: Vec<u32>,
    /// Per face: whether it is flat-shaded (its vertex normals all its own).
    flat: Vec<bool>,
    /// The mesh's bounds `(min, max)`.
    bounds: (Vec3, Vec3),
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
    fn neighbourhood(&self, mesh: &Mesh, e: &MeshEdge) -> [u32; 6] {
        let mut out = [u32::MAX; 6];
        for (k, &f) in e.faces.iter().enumerate().filter(|(_, &f)| f != NO_FACE) {
            for (j, &v) in mesh.triangles[f as usize].iter().enumerate() {
                out[k * 3 + j] = self.weld[v as usize];
            }
        }
        out
    }

    /// Whether triangle `t` of `mesh` has a vertex among `near`.
    fn touches(&self, mesh: &Mesh, t: u32, near: &[u32; 6]) -> bool {
        mesh.triangles.get(t as usize).is_some_and(|tri| tri.iter().any(|&v| near.contains(&self.weld[v as usize])))
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
    fn edges_of(&mut self, scene: &Scene, crease_deg: f32) -> Vec<Option<Arc<MeshEdges>>> {
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

/// One blend of the edge pass: pixel `c` moves towards pixel `o` by `alpha`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeBlend {
    /// The pixel the edge crosses (row-major index).
    pub c: u32,
    /// The pixel across the edge.
    pub o: u32,
    /// How far `c` moves: under the coverage filter the share of `c`'s area on
    /// `o`'s side of the edge (≤ ½); under the paper's, its Wu weight (≤ 1).
    pub alpha: f32,
    /// Whether `c` shows the edge's own surface (else what lies behind the edge).
    pub inside: bool,
    /// The edge: object index (high 32 bits) and edge index within its mesh.
    pub source: u64,
    /// Where in `c` the part on `o`'s side of the edge has its centroid, from
    /// `c`'s centre (pixels, y down).
    pub far: Vec2,
}

/// Plans seed 004's edge pass over the frame whose visibility buffer is `vb`.
#[must_use]
pub fn plan(scene: &Scene, vb: &VisibilityBuffer, options: &EdgeOptions, cache: &mut EdgeCache) -> EdgePlan {
    let edges = cache.edges_of(scene, options.crease_deg);
    let clips = ClipMap::of_objects(scene, vb.width(), vb.height());
    let mut blends = find_blends(scene, vb, (&edges, &clips), options.mode);
    if options.mode.filter == EdgeFilter::Coverage {
        // Where an edge runs between two pixels it bounds what they show; an
        // intersection is only looked for where none does.
        let walked = intersections::WalkedPairs::of(&blends, vb.width(), vb.height());
        let opaque = |o: &crate::scene::Object| !scene.materials[o.material].translucent();
        let objects = scene.objects.iter().zip(&edges);
        let boxes: Vec<(Vec3, Vec3)> =
            objects.filter(|(o, _)| opaque(o)).filter_map(|(o, e)| Some(o.world_box(e.as_ref()?.bounds))).collect();
        blends.extend(intersections::find_intersection_blends(scene, vb, &clips, &walked, &boxes));
    }
    // One straight edge moves a pixel by at most ½ under the coverage filter; the
    // paper's Wu weights reach 1.
    let cap = match options.mode.filter {
        EdgeFilter::Coverage => 0.5,
        EdgeFilter::Paper => 1.0,
    };
    let blends = merge(blends, cap, vb.width());
    let flat = |item: ItemId| {
        let edges = edges.get(item.object as usize).and_then(Option::as_ref);
        item.primitive().is_none() && edges.is_some_and(|e| e.flat.get(item.triangle as usize) == Some(&true))
    };
    EdgePlan::new(blends, options.mode.filter == EdgeFilter::Coverage, vb, flat)
}

/// Every blend, in scene order (object, then edge).
fn find_blends(
    scene: &Scene,
    vb: &VisibilityBuffer,
    (edges, clips): (&[Option<Arc<MeshEdges>>], &[ClipMap]),
    mode: EdgeMode,
) -> Vec<EdgeBlend> {
    let camera = &scene.camera;
    let (w, h) = (vb.width(), vb.height());
    let walker = Walker { scene, vb, clips, mode, depth: DepthScale::of(camera, h), screen: Screen::of(camera, w, h) };
    let objects: Vec<WalkedObject> = scene
        .objects
        .par_iter()
        .zip(edges)
        .enumerate()
        .filter_map(|(index, (o, edges))| {
            // Solids' outlines are not mesh edges: they keep their aliased edges.
            let (mesh, edges) = (o.triangles()?, edges.as_deref()?);
            let material = &scene.materials[o.material];
            // A translucent surface is blended over the opaque frame later; its
            // edges are not walked.
            (!material.translucent()).then(|| {
                let facing = Facing::new(camera, o.transform.inverse());
                let front = edges.planes.par_iter().map(|&plane| facing.front(plane)).collect();
                WalkedObject { index: index as u32, mesh, edges, front, two_sided: material.two_sided }
            })
        })
        .collect();
    // One parallel sweep over the selected edges of all objects (a scene of
    // many small parts has few edges per object).
    let selected: Vec<(usize, usize)> = objects
        .par_iter()
        .enumerate()
        .flat_map_iter(|(j, o)| {
            let edges = o.edges.edges.iter().enumerate();
            edges.filter(|(_, e)| selected(e, &o.front, o.two_sided, mode.selection)).map(move |(k, _)| (j, k))
        })
        .collect();
    let chunks: Vec<Vec<EdgeBlend>> = selected
        .par_iter()
        .fold(Vec::new, |mut out, &(j, k)| {
            walker.walk_edge(&objects[j], k, &mut out);
            out
        })
        .collect();
    chunks.concat()
}

/// An object whose edges the pass walks, as this frame sees it.
struct WalkedObject<'a> {
    index: u32,
    mesh: &'a Mesh,
    edges: &'a MeshEdges,
    /// Per face, whether it looks at the eye.
    front: Vec<bool>,
    two_sided: bool,
}

/// What walking an edge reads: the frame's visibility buffer and the view.
struct Walker<'a> {
    scene: &'a Scene,
    vb: &'a VisibilityBuffer,
    clips: &'a [ClipMap],
    mode: EdgeMode,
    depth: DepthScale,
    screen: Screen,
}

impl Walker<'_> {
    /// Walks edge `k` of `object`, adding its blends to `out`.
    fn walk_edge(&self, object: &WalkedObject, k: usize, out: &mut Vec<EdgeBlend>) {
        let (mesh, e, clip) = (object.mesh, &object.edges.edges[k], &self.clips[object.index as usize]);
        let source = (u64::from(object.index) << 32) | k as u64;
        let [a, b] = e.v.map(|i| clip.points * mesh.positions[i as usize].as_dvec3().extend(1.0));
        let Some((a, b)) = self.screen.clip_and_project(a, b) else { return };
        let near = object.edges.neighbourhood(mesh, e);
        let mut planes = LastTwo::new();
        // A column the edge crosses in two rows visits both pixels twice, each
        // as the other's neighbour.
        let mut sides = LastTwo::new();
        let (w, h) = (self.vb.width(), self.vb.height());
        let items = self.vb.items();
        let visit = |c: (u32, u32), other: (u32, u32), alpha, point: glam::DVec3, far: PartBeyond| {
            // Only a pixel of the edge's own object can be its own surface, and
            // a blend needs one.
            let ours = |(x, y): (u32, u32)| items[(y * w + x) as usize].object == object.index;
            if !ours(c) && !ours(other) {
                return;
            }
            let mut side = |i: usize| sides.get((i, point), || self.side((object, e), &near, &mut planes, i, point));
            if let Some(blend) = depth_tested(w, &mut side, c, other, alpha, self.mode.filter) {
                out.push(EdgeBlend { source, far: far.centroid(), ..blend });
            }
        };
        walk(a, b, visit, (w, h), self.mode.filter);
    }

    /// How pixel `i` relates to `edge` of `object`, whose point there is
    /// `point` (screen x, y, depth); `near` is the edge's neighbourhood.
    fn side(
        &self,
        (object, edge): (&WalkedObject, &MeshEdge),
        near: &[u32; 6],
        planes: &mut LastTwo<ItemId, Option<DepthPlane>>,
        i: usize,
        point: DVec3,
    ) -> Side {
        let item = self.vb.items()[i];
        if item.is_none() {
            return Side::Behind;
        }
        let ours = item.object == object.index;
        if ours && (edge.faces.contains(&item.triangle) || object.edges.touches(object.mesh, item.triangle, near)) {
            return Side::Own; // a face of the edge, or a triangle touching one
        }
        // The pixel's surface plane carried to the edge's point (a surface
        // resting on another meets it at the edge's depth, though its pixel
        // beside the edge lies nearer), else the pixel's own depth.
        let plane = planes.get(item, || {
            let mesh = self.scene.objects[item.object as usize].triangles()?;
            let clip = &self.clips[item.object as usize];
            item.primitive().is_none().then(|| self.screen.depth_plane(clip, mesh, item.triangle))?
        });
        let z = plane.map(|plane| plane.at(point.x, point.y));
        if ours && z.is_some_and(|z| self.depth.close(z, point.z)) {
            // A fine mesh: the triangle at the pixel is a few rings away from
            // the edge, but its plane passes near it.
            Side::Own
        } else if self.depth.in_front(z.unwrap_or(f64::from(self.vb.depths()[i])), point.z) {
            Side::Occluder
        } else {
            Side::Behind
        }
    }
}

/// One blend per pixel and neighbour, from all the edges that cross the pixel
/// towards that neighbour, in a fixed order (by pixel, then neighbour). Where a
/// pixel inside an outline faces a neighbour crossed by another edge from outside
/// (a rim thinner than a pixel lies between them), the inside pixel is left alone.
///
/// Several edges crossing one pixel towards the same neighbour are nested outlines
/// (a rim seen edge-on in front of a body's silhouette): only the part beyond the
/// edge nearest the neighbour shows the neighbour's colour. Seen from inside (the
/// pixel shows the edges' surface) that is the smallest share; seen from outside
/// (the pixel shows what lies behind) the object covers the union, the largest
/// share. Then a pixel's shares are scaled to sum to at most `cap` where edges crowd
/// (a vertex many edges leave, a spout's thin rim): ½ for the coverage filter —
/// one straight edge never takes more (the half-plane holding the pixel centre holds
/// the larger part), so a pixel keeps at least half its own colour — and 1 for the
/// paper's weights, instead of overshooting.
fn merge(blends: Vec<EdgeBlend>, cap: f32, width: u32) -> Vec<EdgeBlend> {
    let key = |c: u32, o: u32| (u64::from(c) << 32) | u64::from(o);
    let mut blends = sorted_by_pixel(blends, width);
    // A sliver: the pixel across is itself crossed by another edge, from outside,
    // towards this pixel — a thin surface lies between the two edges, so nothing of
    // this pixel shows the colour across. Only towards a pixel crossed from
    // outside at all can a blend be one.
    let mut crossed_from_outside = PixelSet::new(blends.iter().map(|b| b.c.max(b.o) + 1).max().unwrap_or(0));
    blends.iter().filter(|b| !b.inside).for_each(|b| crossed_from_outside.insert(b.c));
    let sliver = |b: &EdgeBlend| {
        let reverse = key(b.o, b.c);
        let from = blends.partition_point(|x| key(x.c, x.o) < reverse);
        blends[from..].iter().take_while(|x| key(x.c, x.o) == reverse).any(|x| !x.inside && x.source != b.source)
    };
    let slivers: Vec<bool> =
        blends.par_iter().map(|b| b.inside && crossed_from_outside.contains(b.o) && sliver(b)).collect();
    let mut kept = slivers.iter();
    blends.retain(|_| !kept.next().is_some_and(|&s| s));
    let mut merged: Vec<EdgeBlend> = Vec::with_capacity(blends.len());
    for b in blends {
        match merged.last_mut().filter(|m| (m.c, m.o) == (b.c, b.o)) {
            Some(m) => {
                m.inside |= b.inside;
                m.alpha = if m.inside { m.alpha.min(b.alpha) } else { m.alpha.max(b.alpha) };
            }
            None => merged.push(b),
        }
    }
    for pixel in merged.chunk_by_mut(|a, b| a.c == b.c) {
        let total: f32 = pixel.iter().map(|b| b.alpha).sum();
        if total > cap {
            pixel.iter_mut().for_each(|b| b.alpha *= cap / total);
        }
    }
    merged
}

/// `blends` sorted by pixel, neighbour, then (for a fixed order of the edges
/// meeting there) outside first and by edge: bucketed by image row (a counting
/// sort on a `width` pixels wide frame), then each row's few blends compared.
fn sorted_by_pixel(blends: Vec<EdgeBlend>, width: u32) -> Vec<EdgeBlend> {
    let rows: Vec<u32> = blends.iter().map(|b| b.c / width.max(1)).collect();
    let count = rows.iter().max().map_or(0, |&r| r as usize + 1);
    let mut starts = vec![0; count + 1];
    rows.iter().for_each(|&r| starts[r as usize + 1] += 1);
    for r in 0..count {
        starts[r + 1] += starts[r];
    }
    let mut order = vec![0u32; blends.len()];
    let mut next = starts.clone();
    for (i, &r) in rows.iter().enumerate() {
        order[next[r as usize]] = i as u32;
        next[r as usize] += 1;
    }
    let mut sorted: Vec<EdgeBlend> = order.iter().map(|&i| blends[i as usize]).collect();
    // Pixel and neighbour as one number: most comparisons end there.
    let key = |b: &EdgeBlend| ((u64::from(b.c) << 32) | u64::from(b.o), b.inside, b.source);
    for r in 0..count {
        sorted[starts[r]..starts[r + 1]].sort_unstable_by_key(key);
    }
    sorted
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

/// Whether edge `e` is walked, given which faces look at the eye (`front`).
fn selected(e: &MeshEdge, front: &[bool], two_sided: bool, selection: EdgeSelection) -> bool {
    let drawn = |f: u32| f != NO_FACE && (two_sided || front[f as usize]);
    if !(drawn(e.faces[0]) || drawn(e.faces[1])) {
        return false; // both faces culled: nothing of it is drawn
    }
    match selection {
        EdgeSelection::All => true,
        EdgeSelection::Outline => {
            let boundary = e.faces[1] == NO_FACE;
            let silhouette = !boundary && front[e.faces[0] as usize] != front[e.faces[1] as usize];
            boundary || silhouette || e.crease
        }
    }
}

/// Clip space to the pixel grid, as the polygon pass maps it.
pub(super) struct Screen {
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
        (a.w > 0.0 && b.w > 0.0).then(|| (self.project(a), self.project(b)))
    }

    /// A clip-space point in front of the eye as a screen point (x, y in pixels,
    /// z = depth).
    pub(super) fn project(&self, c: DVec4) -> glam::DVec3 {
        let inv_w = 1.0 / c.w;
        glam::DVec3::new((c.x * inv_w * 0.5 + 0.5) * self.width, (0.5 - c.y * inv_w * 0.5) * self.height, c.z * inv_w)
    }

    /// The screen from `scene`'s camera onto a `width` × `height` image.
    pub(super) fn of(camera: &Camera, width: u32, height: u32) -> Screen {
        Screen { width: f64::from(width), height: f64::from(height), far: f64::from(camera.far_plane_factor()) }
    }

    /// Triangle `t`'s plane as the depth it stores over the screen (depth is
    /// affine in screen x, y over a plane, in perspective too: z/w and 1/w
    /// are), found from the plane itself, so a triangle reaching behind the eye
    /// (a large floor) has one too. `None` if the plane is seen edge-on.
    pub(super) fn depth_plane(&self, clip: &ClipMap, mesh: &Mesh, t: u32) -> Option<DepthPlane> {
        let [a, b, c] = mesh.triangles.get(t as usize)?.map(|v| mesh.positions[v as usize].as_dvec3());
        let n = (b - a).cross(c - a);
        // The plane a·x + b·y + c·z + d = 0 in clip space over NDC (x, y, z).
        let p = clip.planes * n.extend(-n.dot(a));
        if p.z.abs() < 1e-12 * p.truncate().length().max(f64::MIN_POSITIVE) {
            return None;
        }
        // NDC x = 2·sx/width − 1, y = 1 − 2·sy/height; z = −(p.x·x + p.y·y + p.w)/p.z.
        let gx = -2.0 * p.x / (p.z * self.width);
        let gy = 2.0 * p.y / (p.z * self.height);
        Some(DepthPlane { z0: (p.x - p.y - p.w) / p.z, gx, gy })
    }
}

/// An object's map from its own space to clip space, for points and for
/// planes (`n·x + d = 0` as (n, d): the inverse transpose).
#[derive(Debug, Clone, Copy)]
pub(super) struct ClipMap {
    pub(super) points: glam::DMat4,
    pub(super) planes: glam::DMat4,
}

impl ClipMap {
    /// Every object's, for a `width` × `height` view of `scene`.
    pub(super) fn of_objects(scene: &Scene, width: u32, height: u32) -> Vec<ClipMap> {
        let view_proj = scene.camera.view_projection(width as f32 / height as f32);
        let clip = |o: &crate::scene::Object| (view_proj * Mat4::from(o.transform)).as_dmat4();
        scene.objects.iter().map(clip).map(|points| ClipMap { points, planes: points.inverse().transpose() }).collect()
    }
}

/// A surface's stored depth over the screen: `z0 + gx·x + gy·y` (pixels).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct DepthPlane {
    pub(super) z0: f64,
    pub(super) gx: f64,
    pub(super) gy: f64,
}

impl DepthPlane {
    /// The depth at screen point (x, y).
    pub(super) fn at(&self, x: f64, y: f64) -> f64 {
        self.z0 + self.gx * x + self.gy * y
    }
}

/// View distance from stored depth, and the size of a pixel there, to compare
/// depths on the scale of the image.
struct DepthScale {
    projection: Projection,
    near: f64,
    far: f64,
    /// Perspective: a pixel's size at unit distance; orthographic: its size.
    pixel: f64,
}

impl DepthScale {
    fn of(camera: &Camera, height: u32) -> DepthScale {
        let pixel = match camera.projection {
            Projection::Perspective { fov_y_deg } => 2.0 * (f64::from(fov_y_deg).to_radians() * 0.5).tan(),
            Projection::Orthographic { height } => f64::from(height),
        } / f64::from(height.max(1));
        DepthScale { projection: camera.projection, near: f64::from(camera.near), far: f64::from(camera.far), pixel }
    }

    fn distance(&self, z: f64) -> f64 {
        match self.projection {
            Projection::Perspective { .. } => self.near / z.max(f64::MIN_POSITIVE),
            Projection::Orthographic { .. } => self.far - z * (self.far - self.near),
        }
    }

    /// Whether depths `a` and `b` lie within eight pixels' size of each other: a
    /// surface's plane carried a few pixels to its silhouette stays that close; the
    /// far side of a solid is farther (measured: 4 and 16 do worse and no better
    /// against the supersampled truth).
    fn close(&self, a: f64, b: f64) -> bool {
        let (da, db) = (self.distance(a), self.distance(b));
        (da - db).abs() <= 8.0 * self.pixel_at(db)
    }

    /// Whether depth `a` lies in front of depth `b` by more than a hundredth
    /// of a pixel's size (surfaces that meet differ only by rounding).
    fn in_front(&self, a: f64, b: f64) -> bool {
        let (da, db) = (self.distance(a), self.distance(b));
        da < db - 0.01 * self.pixel_at(db)
    }

    /// A pixel's size at view distance `d`.
    fn pixel_at(&self, d: f64) -> f64 {
        match self.projection {
            Projection::Perspective { .. } => self.pixel * d,
            Projection::Orthographic { .. } => self.pixel,
        }
    }
}

/// How a pixel relates to the edge at the edge's depth `z`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    /// The edge's own surface (a triangle touching the faces beside the edge).
    Own,
    /// Something nearer than the edge: the edge is hidden there.
    Occluder,
    /// Something behind the edge (or the background).
    Behind,
}

/// The blend of `c` towards `o` if the depth test lets the edge show: neither pixel
/// hides it, and one of them is its own surface.
fn depth_tested(
    width: u32,
    side: &mut impl FnMut(usize) -> Side,
    c: (u32, u32),
    o: (u32, u32),
    alpha: f32,
    filter: EdgeFilter,
) -> Option<EdgeBlend> {
    let index = |(x, y): (u32, u32)| y * width + x;
    // An occluder at `c` hides the edge whatever `o` shows (half the visits
    // along a hidden silhouette end here).
    let sc = side(index(c) as usize);
    if sc == Side::Occluder {
        return None;
    }
    let so = side(index(o) as usize);
    // The paper blends the edge's own colour: the pixel across must show it.
    let source = match filter {
        EdgeFilter::Coverage => sc == Side::Own || so == Side::Own,
        EdgeFilter::Paper => so == Side::Own && sc != Side::Own,
    };
    let shows = sc != Side::Occluder && so != Side::Occluder && source;
    shows.then(|| EdgeBlend { c: index(c), o: index(o), alpha, inside: sc == Side::Own, source: 0, far: Vec2::ZERO })
}

/// The values of the last two keys an edge's walk asked for: neighbouring
/// steps along an edge mostly meet the same few triangles (their depth
/// planes) and the same pixels (their sides).
struct LastTwo<K, V> {
    last: [Option<(K, V)>; 2],
}

impl<K: PartialEq + Copy, V: Copy> LastTwo<K, V> {
    fn new() -> Self {
        LastTwo { last: [None, None] }
    }

    /// `key`'s value, found by `find` unless asked for just before.
    fn get(&mut self, key: K, find: impl FnOnce() -> V) -> V {
        match self.last {
            [Some((k, v)), _] if k == key => v,
            [_, Some((k, v))] if k == key => {
                self.last.swap(0, 1);
                v
            }
            _ => {
                let v = find();
                self.last = [Some((key, v)), self.last[0]];
                v
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// The row-bucketed sort orders blends as one comparison sort would.
        #[test]
        fn blends_sorted_by_row_buckets_are_sorted(raw in proptest::collection::vec((0u32..600, 0u32..600, proptest::prelude::any::<bool>(), 0u64..4), 0..200)) {
            let blends: Vec<EdgeBlend> = raw
                .iter()
                .map(|&(c, o, inside, source)| EdgeBlend { c, o, alpha: 0.1, inside, source, far: Vec2::ZERO })
                .collect();
            let mut expected = blends.clone();
            expected.sort_by_key(|b| (b.c, b.o, b.inside, b.source));
            proptest::prop_assert_eq!(sorted_by_pixel(blends, 20), expected);
        }
    }

    #[test]
    fn a_flat_shaded_cube_is_flat_and_a_smooth_sphere_is_not() {
        let cube = MeshEdges::new(&crate::scene::mesh::shapes::cube(), 30.0);
        assert!(cube.flat.len() == 12 && cube.flat.iter().all(|&f| f));
        let sphere = MeshEdges::new(&crate::scene::mesh::shapes::sphere(12), 30.0);
        assert!(sphere.flat.iter().all(|&f| !f), "a smooth sphere's faces turn within each face");
    }
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
