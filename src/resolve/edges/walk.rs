//! Walking the meshes' edges (seed 004 §3 (2)): each selected edge of each
//! object, clipped and projected, is stepped along by the DDA, and every pixel
//! pair it passes between is depth-tested against it; the blends of all edges
//! are then merged into one per pixel and neighbour, in a fixed order.

use std::sync::Arc;

use glam::{DVec3, Vec2, Vec4};
use rayon::prelude::*;

use super::blend::{EdgeBlend, PixelSet};
use super::dda::{walk, PartBeyond};
use super::mesh_edges::{meshes_with_edges, MeshEdge, MeshEdges, NO_FACE};
use super::screen::{ClipMap, DepthPlane, Screen};
use crate::camera::{Camera, Projection};
use crate::scene::{EdgeFilter, EdgeMode, EdgeSelection, Mesh, Scene};
use crate::visibility::{ItemId, VisibilityBuffer};

/// Every blend, in scene order (object, then edge).
pub(super) fn find_blends(
    scene: &Scene,
    vb: &VisibilityBuffer,
    edges: &[Option<Arc<MeshEdges>>],
    clips: &[ClipMap],
    mode: EdgeMode,
) -> Vec<EdgeBlend> {
    let camera = &scene.camera;
    let (w, h) = (vb.width(), vb.height());
    let walker = Walker { scene, vb, clips, mode, depth: DepthScale::of(camera, h), screen: Screen::of(camera, w, h) };
    // Solids' outlines are not mesh edges: they keep their aliased edges.
    let objects: Vec<WalkedObject> = meshes_with_edges(scene, edges)
        .filter_map(|(index, o, mesh, edges)| {
            let material = &scene.materials[o.material];
            // A translucent surface is blended over the opaque frame later; its
            // edges are not walked.
            (!material.translucent()).then(|| {
                let front = Facing::faces(camera, o, edges);
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

/// The edge being walked: its object, the edge, and the welded vertices of
/// the faces beside it (a pixel showing a triangle that touches one shows
/// the edge's own surface).
struct WalkedEdge<'a> {
    object: &'a WalkedObject<'a>,
    edge: &'a MeshEdge,
    near: [u32; 6],
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
        let edge = WalkedEdge { object, edge: e, near: object.edges.neighbourhood(mesh, e) };
        let mut planes = LastTwo::new();
        // A column the edge crosses in two rows visits both pixels twice, each
        // as the other's neighbour.
        let mut sides = LastTwo::new();
        let (w, h, held) = (self.vb.width(), self.vb.height(), self.vb.rect());
        let index = |(x, y): (u32, u32)| self.vb.index(x, y) as u32;
        let visit = |c: (u32, u32), other: (u32, u32), alpha, point: glam::DVec3, far: PartBeyond| {
            // Pixels the buffer does not hold (outside a tile's guard band)
            // are not blended.
            if !held.contains(c.0, c.1) || !held.contains(other.0, other.1) {
                return;
            }
            // Only a pixel of the edge's own object can be its own surface, and
            // a blend needs one.
            let ours = |(x, y): (u32, u32)| self.vb.item(x, y).object == object.index;
            if !ours(c) && !ours(other) {
                return;
            }
            let mut side = |i: usize| sides.get((i, point), || self.side(&edge, &mut planes, i, point));
            if let Some(blend) = depth_tested(index, &mut side, c, other, alpha, self.mode.filter) {
                out.push(EdgeBlend { source, far: far.centroid(), ..blend });
            }
        };
        walk(a, b, visit, (w, h), self.mode.filter);
    }

    /// How pixel `i` (its index among those held) relates to `walked`, whose
    /// point there is `point` (screen x, y, depth).
    fn side(
        &self,
        walked: &WalkedEdge,
        planes: &mut LastTwo<ItemId, Option<DepthPlane>>,
        i: usize,
        point: DVec3,
    ) -> Side {
        let WalkedEdge { object, edge, near } = walked;
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
pub(super) fn merge(blends: Vec<EdgeBlend>, cap: f32, width: u32) -> Vec<EdgeBlend> {
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
/// meeting there) outside first and by edge: bucketed by row (a counting
/// sort on pixels indexed `width` to a row), then each row's few blends compared.
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
pub(super) struct Facing {
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

    /// Per face of `edges` (the mesh of `object`), whether it looks at the
    /// eye of `camera`.
    pub(super) fn faces(camera: &Camera, object: &crate::scene::Object, edges: &MeshEdges) -> Vec<bool> {
        let facing = Facing::new(camera, object.transform.inverse());
        edges.planes.par_iter().map(|&plane| facing.front(plane)).collect()
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

/// View distance from stored depth, and the size of a pixel there, to compare
/// depths on the scale of the image.
pub(super) struct DepthScale {
    projection: Projection,
    near: f64,
    far: f64,
    /// Perspective: a pixel's size at unit distance; orthographic: its size.
    pixel: f64,
}

impl DepthScale {
    pub(super) fn of(camera: &Camera, height: u32) -> DepthScale {
        let pixel = match camera.projection {
            Projection::Perspective { fov_y_deg } => 2.0 * (f64::from(fov_y_deg).to_radians() * 0.5).tan(),
            Projection::Orthographic { height } => f64::from(height),
        } / f64::from(height.max(1));
        DepthScale { projection: camera.projection, near: f64::from(camera.near), far: f64::from(camera.far), pixel }
    }

    pub(super) fn distance(&self, z: f64) -> f64 {
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
    pub(super) fn pixel_at(&self, d: f64) -> f64 {
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
/// hides it, and one of them is its own surface; pixels are named in it by
/// `index`.
fn depth_tested(
    index: impl Fn((u32, u32)) -> u32,
    side: &mut impl FnMut(usize) -> Side,
    c: (u32, u32),
    o: (u32, u32),
    alpha: f32,
    filter: EdgeFilter,
) -> Option<EdgeBlend> {
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
}
