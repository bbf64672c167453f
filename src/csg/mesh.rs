//! A closed triangle mesh as a primitive of a solid: a polyhedron that is not
//! convex, an imported STL, a twisted extrusion — beyond seed 003, whose
//! primitives are convex and meet a ray in one interval at most.
//!
//! A ray meets such a mesh in several intervals: sorted, its crossings of the
//! surface alternate entry and exit (their parity), whichever way each
//! triangle is wound. So that every other part of the walk and the caster
//! keeps its one interval per primitive, the mesh stands in the tree as a
//! union of *layers* ([`Shape::Mesh`]): layer `k` is the `k`-th interval
//! along each ray, and the last layer runs from its own entry to the last exit
//! (on the rare ray with more intervals than the mesh has layers, the gaps
//! between the deepest ones are filled). A mesh gets one layer more than the
//! most intervals found along a probe of rays in 13 directions.
//!
//! A ray's crossings come from a BVH over the triangles and the watertight
//! triangle test, along the whole line (both ways from the ray's origin), so
//! the parity starts outside the mesh whatever the origin. A crossing's face
//! is its triangle, with a bit ([`FLIP`]) saying that its outward normal is
//! the triangle's reversed (an entry through a triangle wound inwards).

use std::cell::RefCell;
use std::sync::Arc;

use glam::Vec3;

use crate::bvh::{Aabb, Bvh};
use crate::camera::Ray;
use crate::triangle::ShearedRay;

/// The bit of a mesh crossing's face saying its outward normal is its
/// triangle's normal reversed.
pub const FLIP: u32 = 1 << 30;

/// Triangles a mesh primitive may hold (its faces' indices stay below [`FLIP`]).
pub const MAX_TRIANGLES: usize = (FLIP - 1) as usize;

/// Directions of the probe that counts a mesh's layers: the axes, the face
/// diagonals and the body diagonals of a cube.
const PROBE_DIRECTIONS: [[f32; 3]; 13] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, 1.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Rays per side of the probe's square grid in each direction.
const PROBE_GRID: usize = 24;

/// A closed triangle mesh, ready for rays.
pub struct ClosedMesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Unit normals as the triangles are wound.
    normals: Vec<Vec3>,
    bvh: Bvh,
    bounds: (Vec3, Vec3),
    layers: u32,
}

impl std::fmt::Debug for ClosedMesh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ClosedMesh")
            .field("positions", &self.positions.len())
            .field("triangles", &self.triangles.len())
            .field("layers", &self.layers)
            .finish()
    }
}

impl PartialEq for ClosedMesh {
    fn eq(&self, other: &Self) -> bool {
        self.positions == other.positions && self.triangles == other.triangles
    }
}

/// One interval of a ray inside the mesh: entry and exit `t` with their faces.
pub type MeshInterval = ((f32, u32), (f32, u32));

impl ClosedMesh {
    /// The mesh of `triangles` (indices into `positions`); triangles of no
    /// area are left out. `None` when none is left or there are more than
    /// [`MAX_TRIANGLES`].
    #[must_use]
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Option<ClosedMesh> {
        let (positions, triangles) = welded(positions, triangles);
        let corner = |t: &[u32; 3], k: usize| positions.get(t[k] as usize).copied();
        let mut kept = Vec::with_capacity(triangles.len());
        let mut normals = Vec::with_capacity(triangles.len());
        for t in triangles {
            let (Some(a), Some(b), Some(c)) = (corner(&t, 0), corner(&t, 1), corner(&t, 2)) else { continue };
            let Some(n) = (b - a).cross(c - a).try_normalize() else { continue };
            kept.push(t);
            normals.push(n);
        }
        if kept.is_empty() || kept.len() > MAX_TRIANGLES {
            return None;
        }
        let boxes: Vec<Aabb> = kept.iter().map(|t| Aabb::around(&t.map(|i| positions[i as usize]))).collect();
        let bvh = Bvh::build(&boxes);
        let bounds = kept.iter().flatten().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &i| {
            (lo.min(positions[i as usize]), hi.max(positions[i as usize]))
        });
        let mut mesh = ClosedMesh { positions, triangles: kept, normals, bvh, bounds, layers: 1 };
        mesh.layers = mesh.probe_layers() + 1;
        Some(mesh)
    }

    /// How many edges are not shared by an even number of triangles: 0 for a
    /// closed surface (its corners welded by position, as [`ClosedMesh::new`]
    /// welds them).
    #[must_use]
    pub fn open_edges(&self) -> usize {
        let mut count: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
        for t in &self.triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *count.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        count.values().filter(|&&n| n % 2 == 1).count()
    }

    /// The vertices.
    #[must_use]
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The triangles (indices into [`ClosedMesh::positions`]).
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The box `(min, max)` around the mesh.
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// How many layers the mesh stands for in a tree.
    #[must_use]
    pub fn layers(&self) -> u32 {
        self.layers
    }

    /// The unit outward normal of a crossing's face (its triangle's, reversed
    /// where the face says so).
    #[must_use]
    pub fn normal(&self, face: u32) -> Vec3 {
        let n = self.normals.get((face & (FLIP - 1)) as usize).copied().unwrap_or(Vec3::ZERO);
        if face & FLIP != 0 {
            -n
        } else {
            n
        }
    }

    /// Triangle `i`'s plane: its unit normal as wound, and the normal's dot
    /// product with its points.
    #[must_use]
    pub fn plane(&self, i: usize) -> (Vec3, f32) {
        let n = self.normals[i];
        (n, n.dot(self.positions[self.triangles[i][0] as usize]))
    }

    /// The triangle `i`'s corners.
    #[must_use]
    pub fn corners(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].map(|k| self.positions[k as usize])
    }

    /// Every crossing of the line `o + t·d` (all `t`) with the surface, into
    /// `out` as `(t, triangle)`, sorted by `t`.
    pub fn crossings(&self, o: Vec3, d: Vec3, out: &mut Vec<(f32, u32)>) {
        out.clear();
        for (dir, sign) in [(d, 1.0f32), (-d, -1.0)] {
            let ray = Ray { origin: o, dir };
            let sheared = ShearedRay::new(&ray);
            self.bvh.intersect(&ray, f32::INFINITY, |i, _| {
                if let Some((t, _)) = sheared.intersect(&self.corners(i as usize), 0.0, f32::INFINITY) {
                    out.push((sign * t, i));
                }
                // Every crossing: the walk is never cut short.
                None
            });
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        // A line through an edge or corner crosses the surface once but may
        // be found in each triangle there (and one at the origin both
        // ways): crossings at the same `t` facing the same way are one.
        let facing = |i: u32| self.normals[i as usize].dot(d) > 0.0;
        out.dedup_by(|b, a| a.0 == b.0 && facing(a.1) == facing(b.1));
    }

    /// The intervals of the line `o + t·d` inside the mesh (crossings paired
    /// by parity; an odd last crossing, of a mesh that is not closed, is
    /// dropped), each face marked with [`FLIP`] where the outward normal is
    /// the triangle's reversed.
    pub fn intervals(&self, o: Vec3, d: Vec3, crossings: &mut Vec<(f32, u32)>, out: &mut Vec<MeshInterval>) {
        self.crossings(o, d, crossings);
        out.clear();
        out.extend(crossings.chunks_exact(2).map(|pair| {
            let face = |(t, i): (f32, u32), entering: bool| {
                let along = self.normals[i as usize].dot(d);
                let flip = if entering { along > 0.0 } else { along < 0.0 };
                (t, i | if flip { FLIP } else { 0 })
            };
            (face(pair[0], true), face(pair[1], false))
        }));
    }

    /// Layer `layer`'s interval along `o + t·d`: the `layer`-th interval, or
    /// for the last layer, from its entry to the last exit. Each thread keeps
    /// the intervals of the last line it asked of each mesh, so the layers of
    /// one mesh, asked in turn for one ray, cost one cast.
    #[must_use]
    pub fn layer_interval(self: &Arc<Self>, layer: u32, o: Vec3, d: Vec3) -> Option<MeshInterval> {
        LAST.with_borrow_mut(|last| {
            let key = (Arc::as_ptr(self) as usize, o.to_array().map(f32::to_bits), d.to_array().map(f32::to_bits));
            if last.key != Some(key) {
                last.key = Some(key);
                let LastLine { crossings, intervals, .. } = last;
                self.intervals(o, d, crossings, intervals);
            }
            pick_layer(&last.intervals, layer, self.layers)
        })
    }

    /// Whether `p` lies inside (the parity of the crossings on one side of
    /// it along a fixed direction).
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        self.layer_of(p).is_some()
    }

    /// The layer whose interval holds `p` along a fixed direction, if any.
    #[must_use]
    pub fn layer_of(&self, p: Vec3) -> Option<u32> {
        let d = Vec3::new(0.5773, 0.4071, 0.6932);
        let (mut crossings, mut intervals) = (Vec::new(), Vec::new());
        self.intervals(p, d, &mut crossings, &mut intervals);
        let k = intervals.iter().position(|((t0, _), (t1, _))| *t0 <= 0.0 && 0.0 <= *t1)?;
        Some((k as u32).min(self.layers - 1))
    }

    /// The most intervals along the probe's rays.
    fn probe_layers(&self) -> u32 {
        let (lo, hi) = self.bounds;
        let (centre, radius) = ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-6));
        let (mut crossings, mut intervals) = (Vec::new(), Vec::new());
        let mut most = 0;
        for dir in PROBE_DIRECTIONS {
            let d = Vec3::from(dir).normalize();
            let u = d.any_orthonormal_vector();
            let v = d.cross(u);
            for i in 0..PROBE_GRID {
                for j in 0..PROBE_GRID {
                    // Cell centres, a little off the grid so rays miss edges.
                    let s = ((i as f32 + 0.5123) / PROBE_GRID as f32 * 2.0 - 1.0) * radius;
                    let r = ((j as f32 + 0.4871) / PROBE_GRID as f32 * 2.0 - 1.0) * radius;
                    self.intervals(centre + u * s + v * r, d, &mut crossings, &mut intervals);
                    most = most.max(intervals.len());
                }
            }
        }
        most.max(1) as u32
    }
}

/// `triangles` over `positions` with the corners that lie at the same point
/// made one (an STL repeats each corner per facet): neighbours then share the
/// very corners, as a rasterizer's exact edge tests need. Indices past the
/// positions are kept out.
fn welded(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut first: std::collections::HashMap<[u32; 3], u32> = std::collections::HashMap::with_capacity(positions.len());
    let mut kept = Vec::with_capacity(positions.len());
    let index: Vec<u32> = positions
        .iter()
        .map(|p| {
            // −0 and 0 are one point.
            let key = (*p + Vec3::ZERO).to_array().map(f32::to_bits);
            *first.entry(key).or_insert_with(|| {
                kept.push(*p);
                kept.len() as u32 - 1
            })
        })
        .collect();
    let triangles = triangles
        .into_iter()
        .filter_map(|t| {
            let t = [index.get(t[0] as usize)?, index.get(t[1] as usize)?, index.get(t[2] as usize)?].map(|i| *i);
            (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]).then_some(t)
        })
        .collect();
    (kept, triangles)
}

/// Layer `layer` of `layers` among a line's `intervals`.
#[must_use]
pub fn pick_layer(intervals: &[MeshInterval], layer: u32, layers: u32) -> Option<MeshInterval> {
    let (k, last) = (layer as usize, layers as usize - 1);
    let own = *intervals.get(k)?;
    Some(if k == last { (own.0, intervals[intervals.len() - 1].1) } else { own })
}

/// The last line a thread cast at a mesh, and what it found.
#[derive(Default)]
struct LastLine {
    key: Option<(usize, [u32; 3], [u32; 3])>,
    crossings: Vec<(f32, u32)>,
    intervals: Vec<MeshInterval>,
}

thread_local! {
    static LAST: RefCell<LastLine> = RefCell::default();
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two unit cubes side by side with a gap: a ray along x meets two
    /// intervals. Their faces are wound any way (some inwards).
    fn two_cubes() -> ClosedMesh {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for (k, x0) in [0.0f32, 2.0].into_iter().enumerate() {
            let base = positions.len() as u32;
            positions.extend((0..8).map(|i| Vec3::new(x0 + (i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32)));
            let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
            for q in quads {
                let q = q.map(|i| base + i);
                // The second cube wound inwards.
                let (a, b) = if k == 0 {
                    ([q[0], q[1], q[2]], [q[0], q[2], q[3]])
                } else {
                    ([q[0], q[2], q[1]], [q[0], q[3], q[2]])
                };
                triangles.extend([a, b]);
            }
        }
        ClosedMesh::new(positions, triangles).unwrap()
    }

    #[test]
    fn closed_cubes_have_no_open_edge_and_a_cube_without_its_top_has_four() {
        assert_eq!(two_cubes().open_edges(), 0);
        // One cube as an STL has it (every triangle its own corners), less its top.
        let cube = two_cubes();
        let soup: Vec<Vec3> = cube.triangles[..12].iter().flatten().map(|&i| cube.positions[i as usize]).collect();
        let triangles: Vec<[u32; 3]> = (0..12u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        assert_eq!(ClosedMesh::new(soup.clone(), triangles.clone()).unwrap().open_edges(), 0);
        let top = |t: &[u32; 3]| t.iter().all(|&i| soup[i as usize].z == 1.0);
        let open: Vec<[u32; 3]> = triangles.into_iter().filter(|t| !top(t)).collect();
        assert_eq!(open.len(), 10);
        assert_eq!(ClosedMesh::new(soup, open).unwrap().open_edges(), 4);
    }

    #[test]
    fn a_line_meets_each_cube_once_and_normals_face_out() {
        let mesh = two_cubes();
        assert!(mesh.layers() >= 3, "{}", mesh.layers());
        let (mut c, mut out) = (Vec::new(), Vec::new());
        let (o, d) = (Vec3::new(-1.0, 0.3, 0.6), Vec3::X);
        mesh.intervals(o, d, &mut c, &mut out);
        let ts: Vec<(f32, f32)> = out.iter().map(|((a, _), (b, _))| (*a, *b)).collect();
        assert_eq!(ts, vec![(1.0, 2.0), (3.0, 4.0)]);
        for ((_, enter), (_, exit)) in &out {
            assert_eq!(mesh.normal(*enter), Vec3::NEG_X);
            assert_eq!(mesh.normal(*exit), Vec3::X);
        }
        // From inside the first cube: the line's parity still starts outside.
        mesh.intervals(Vec3::new(0.5, 0.3, 0.6), d, &mut c, &mut out);
        assert_eq!(out.len(), 2);
        assert!((out[0].0 .0 + 0.5).abs() < 1e-6);
    }

    #[test]
    fn layers_split_a_line_and_the_last_takes_the_rest() {
        let mesh = Arc::new(two_cubes());
        let (o, d) = (Vec3::new(-1.0, 0.3, 0.6), Vec3::X);
        let first = mesh.layer_interval(0, o, d).unwrap();
        assert_eq!((first.0 .0, first.1 .0), (1.0, 2.0));
        assert_eq!(
            pick_layer(&[((0.0, 0), (1.0, 0)), ((2.0, 0), (3.0, 0)), ((4.0, 0), (5.0, 0))], 1, 2),
            Some(((2.0, 0), (5.0, 0)))
        );
        assert!(mesh.contains(Vec3::new(2.5, 0.5, 0.5)) && !mesh.contains(Vec3::new(1.5, 0.5, 0.5)));
    }
}
