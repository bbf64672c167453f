//! Closed meshes' layers as one camera sees them: every pixel's intervals
//! inside each mesh, found by rasterizing its triangles once per frame
//! instead of casting a ray per pixel and layer through its BVH.
//!
//! Each triangle covers the pixel centres its projection holds, by exact
//! edge tests: an edge's function is evaluated from its two corners in one
//! order whichever triangle asks, so the two triangles beside it give exactly
//! opposite answers, and a centre on the edge goes to the one of them that
//! runs along it "upwards" (down the image, or rightwards on a level edge):
//! one crossing per surface a pixel's ray passes. A covered pixel's `t` is
//! where its own ray (the walk's row line, in the mesh's space) meets the
//! triangle's plane. Sorted, a pixel's crossings pair by parity into its
//! intervals, layer `k` the `k`-th ([`crate::csg::pick_layer`]).
//!
//! Only whole frames of a mesh in front of the eye are rasterized: a mesh
//! with a corner at or behind the eye plane, or round the eye, is left to the
//! caster's rays (the same intervals, slower). A tile rasterizes the rows it
//! walks alone.

use std::sync::Arc;

use glam::{DVec2, Mat4};
use rayon::prelude::*;

use crate::camera::PixelRays;
use crate::csg::outline::{Extent, Outline};
use crate::csg::{pick_layer, ClosedMesh, CsgCaster, Hit, Interval, IntervalLanes, MeshInterval, Shape, MESH_FLIP};
use crate::image::PixelRect;

/// Rows of a band rasterized by one task.
const BAND: usize = 16;

/// Every mesh's layers in one frame.
#[derive(Default)]
pub(super) struct MeshLayers {
    /// Per primitive: its mesh's view and its layer, where a view was made.
    of: Vec<Option<(u32, u32)>>,
    views: Vec<LayerView>,
}

/// One mesh's intervals at every pixel of its box.
struct LayerView {
    /// The box's first column and row, and its size.
    x0: usize,
    y0: usize,
    w: usize,
    h: usize,
    /// Where each pixel's intervals start in `intervals` (and where the
    /// last ends).
    offsets: Vec<u32>,
    intervals: Vec<MeshInterval>,
    layers: u32,
    /// Per layer, per row of the box: the columns where the layer shows.
    extents: Vec<Vec<Option<(i64, i64)>>>,
}

impl MeshLayers {
    /// The layers of every mesh of `caster`'s solid seen through `vp` (its
    /// pixel rays `rays`) in a `size` frame, on the pixels of `window` (a
    /// tile's rasterizes its own alone).
    pub(super) fn new(
        caster: &CsgCaster,
        vp: Mat4,
        rays: &PixelRays,
        size: (usize, usize),
        window: PixelRect,
    ) -> MeshLayers {
        let primitives = &caster.solid().primitives;
        let mut firsts: Vec<(usize, Arc<ClosedMesh>)> = Vec::new();
        for (i, p) in primitives.iter().enumerate() {
            if let Shape::Mesh { mesh, layer: 0 } = &p.shape {
                firsts.push((i, Arc::clone(mesh)));
            }
        }
        if firsts.is_empty() {
            return MeshLayers::default();
        }
        let mut out = MeshLayers { of: vec![None; primitives.len()], views: Vec::new() };
        for (first, mesh) in firsts {
            let Some(view) = LayerView::new(caster, first, &mesh, vp, rays, size, window) else { continue };
            let index = out.views.len() as u32;
            for layer in 0..mesh.layers() {
                out.of[first + layer as usize] = Some((index, layer));
            }
            out.views.push(view);
        }
        out
    }

    /// Primitive `i`'s outline narrowed to where its layer shows, if it is a
    /// layer this frame rasterized (`None`: it shows nowhere).
    pub(super) fn narrow(&self, i: usize, outline: Option<Outline>) -> Option<Outline> {
        let Some(&Some((v, layer))) = self.of.get(i) else { return outline };
        let view = &self.views[v as usize];
        let rows = &view.extents[layer as usize];
        let first = rows.iter().position(Option::is_some)?;
        let last = rows.iter().rposition(Option::is_some)?;
        let (x0, x1) = rows.iter().flatten().fold((i64::MAX, i64::MIN), |(a, b), &(c, d)| (a.min(c), b.max(d)));
        let extent = Extent { x0, x1, y0: (view.y0 + first) as i64, y1: (view.y0 + last) as i64 };
        let table = rows[first..=last].to_vec();
        Some(outline?.with_rows(extent, table))
    }

    /// Primitive `i`'s lanes at block `block` of row `y` into `out`, if it is
    /// a layer this frame rasterized (`false`: ask the caster).
    pub(super) fn fill(&self, i: usize, y: usize, block: usize, out: &mut IntervalLanes) -> bool {
        let Some(&Some((v, layer))) = self.of.get(i) else { return false };
        let view = &self.views[v as usize];
        *out = IntervalLanes::from_fn(i, |j| view.at(layer, block * 8 + j, y).map(|s| interval(i, s)));
        true
    }
}

/// A mesh interval as primitive `i`'s.
fn interval(i: usize, ((t0, f0), (t1, f1)): MeshInterval) -> Interval {
    Interval { enter: Hit::new(t0, i, f0), exit: Hit::new(t1, i, f1) }
}

impl LayerView {
    /// Layer `layer`'s interval at pixel `(x, y)`.
    fn at(&self, layer: u32, x: usize, y: usize) -> Option<MeshInterval> {
        let (cx, cy) = (x.checked_sub(self.x0)?, y.checked_sub(self.y0)?);
        if cx >= self.w || cy >= self.h {
            return None;
        }
        let k = cy * self.w + cx;
        let (a, b) = (self.offsets[k] as usize, self.offsets[k + 1] as usize);
        pick_layer(&self.intervals[a..b], layer, self.layers)
    }

    /// The mesh of primitive `first` (its first layer) rasterized on the
    /// pixels of `window`, or `None` when it reaches the eye plane or holds
    /// the eye.
    fn new(
        caster: &CsgCaster,
        first: usize,
        mesh: &ClosedMesh,
        vp: Mat4,
        rays: &PixelRays,
        (width, height): (usize, usize),
        window: PixelRect,
    ) -> Option<LayerView> {
        let to_solid = caster.solid().primitives[first].transform;
        if !rays.ortho && mesh.contains(to_solid.inverse().transform_point3(rays.origin)) {
            return None;
        }
        let clip: Vec<glam::Vec4> =
            mesh.positions().iter().map(|p| vp * to_solid.transform_point3(*p).extend(1.0)).collect();
        let size = DVec2::new(width as f64, height as f64);
        let screen: Vec<DVec2> = clip
            .iter()
            .map(|c| {
                (c.w > 1e-6 * c.truncate().abs().max_element().max(1e-30)).then(|| {
                    let ndc = DVec2::new(f64::from(c.x / c.w), f64::from(c.y / c.w));
                    DVec2::new((ndc.x * 0.5 + 0.5) * size.x, (0.5 - ndc.y * 0.5) * size.y)
                })
            })
            .collect::<Option<_>>()?;
        let (lo, hi) = screen.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(a, b), p| (a.min(*p), b.max(*p)));
        let x0 = ((lo.x - 0.5).ceil().max(0.0) as usize).max(window.x0 as usize);
        let x1 = ((hi.x - 0.5).floor().min(width as f64 - 1.0)).max(-1.0).min(f64::from(window.x1) - 1.0) as i64;
        let y0 = ((lo.y - 0.5).ceil().max(0.0) as usize).max(window.y0 as usize);
        let y1 = ((hi.y - 0.5).floor().min(height as f64 - 1.0)).max(-1.0).min(f64::from(window.y1) - 1.0) as i64;
        if x1 < x0 as i64 || y1 < y0 as i64 {
            return None;
        }
        let (w, h) = (x1 as usize + 1 - x0, y1 as usize + 1 - y0);
        // Each band of rows: the triangles whose rows reach it.
        let bands = h.div_ceil(BAND);
        let mut binned: Vec<Vec<u32>> = vec![Vec::new(); bands];
        for (t, tri) in mesh.triangles().iter().enumerate() {
            let ys = tri.map(|k| screen[k as usize].y);
            let (a, b) = (ys[0].min(ys[1]).min(ys[2]), ys[0].max(ys[1]).max(ys[2]));
            let (r0, r1) = ((a - 0.5).ceil().max(y0 as f64), (b - 0.5).floor().min(y1 as f64));
            if r0 > r1 {
                continue;
            }
            let bands = (r0 as usize - y0) / BAND..=(r1 as usize - y0) / BAND;
            binned[bands].iter_mut().for_each(|b| b.push(t as u32));
        }
        let raster = Raster { caster, first, mesh, screen: &screen, rays, x0, w };
        let per_band: Vec<(Vec<u32>, Vec<MeshInterval>)> = binned
            .par_iter()
            .enumerate()
            .map(|(band, tris)| raster.band(y0 + band * BAND..y0 + ((band + 1) * BAND).min(h), tris))
            .collect();
        let mut offsets = Vec::with_capacity(w * h + 1);
        let mut intervals = Vec::new();
        for (counts, found) in per_band {
            let mut at = 0;
            for c in counts {
                offsets.push(intervals.len() as u32);
                intervals.extend_from_slice(&found[at..at + c as usize]);
                at += c as usize;
            }
        }
        offsets.push(intervals.len() as u32);
        let layers = mesh.layers();
        let extents = (0..layers)
            .map(|layer| {
                (0..h)
                    .map(|r| {
                        let shows = |c: &usize| offsets[r * w + c + 1] - offsets[r * w + c] > layer;
                        let a = (0..w).find(shows)?;
                        let b = (0..w).rfind(shows)?;
                        Some(((x0 + a) as i64, (x0 + b) as i64))
                    })
                    .collect()
            })
            .collect();
        Some(LayerView { x0, y0, w, h, offsets, intervals, layers, extents })
    }
}

/// One mesh's triangles on the screen, rasterized a band of rows at a time.
struct Raster<'a> {
    caster: &'a CsgCaster,
    first: usize,
    mesh: &'a ClosedMesh,
    /// Each corner's pixel coordinates (centres at `x + ½`).
    screen: &'a [DVec2],
    rays: &'a PixelRays,
    x0: usize,
    w: usize,
}

impl Raster<'_> {
    /// Rows `rows` (each `w` pixels from `x0`) of the triangles `tris`: per
    /// pixel, row by row, how many intervals, and the intervals in order.
    fn band(&self, rows: std::ops::Range<usize>, tris: &[u32]) -> (Vec<u32>, Vec<MeshInterval>) {
        let mut counts = Vec::with_capacity(rows.len() * self.w);
        let mut found = Vec::new();
        let mut row_hits: Vec<(u32, f32, u32)> = Vec::new();
        let mut pixel: Vec<(f32, u32)> = Vec::new();
        for y in rows {
            row_hits.clear();
            let unit = self.caster.unit_line(self.first, &self.rays.row_line(y));
            let cy = y as f64 + 0.5;
            for &t in tris {
                self.cover(t, cy, |x| {
                    let ray = unit.at(x as f32);
                    let (n, d) = self.mesh.plane(t as usize);
                    let along = n.dot(ray.dir);
                    let at = (d - n.dot(ray.origin)) / if along == 0.0 { f32::MIN_POSITIVE } else { along };
                    row_hits.push(((x - self.x0) as u32, at, t));
                });
            }
            row_hits.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
            let mut k = 0;
            for column in 0..self.w as u32 {
                pixel.clear();
                while k < row_hits.len() && row_hits[k].0 == column {
                    pixel.push((row_hits[k].1, row_hits[k].2));
                    k += 1;
                }
                let before = found.len();
                if pixel.len() >= 2 {
                    let dir = unit.at((self.x0 + column as usize) as f32).dir;
                    found.extend(pixel.chunks_exact(2).map(|pair| {
                        let face = |(t, i): (f32, u32), entering: bool| {
                            let along = self.mesh.plane(i as usize).0.dot(dir);
                            let flip = if entering { along > 0.0 } else { along < 0.0 };
                            (t, i | if flip { MESH_FLIP } else { 0 })
                        };
                        (face(pair[0], true), face(pair[1], false))
                    }));
                }
                counts.push((found.len() - before) as u32);
            }
        }
        (counts, found)
    }

    /// Calls `covered(x)` for each pixel column of the row at height `cy`
    /// (a centre) inside triangle `t` by the exact edge tests.
    fn cover(&self, t: u32, cy: f64, mut covered: impl FnMut(usize)) {
        let tri = self.mesh.triangles()[t as usize];
        let p = tri.map(|k| self.screen[k as usize]);
        let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        if area == 0.0 {
            return;
        }
        // The corners counter-clockwise on the screen (y down: area > 0).
        let order = if area > 0.0 { [0, 1, 2] } else { [0, 2, 1] };
        let corner = |k: usize| (tri[order[k]], p[order[k]]);
        // Where the row's centre line crosses the triangle: the columns to test.
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..3 {
            let ((_, a), (_, b)) = (corner(k), corner((k + 1) % 3));
            if (a.y <= cy && cy <= b.y) || (b.y <= cy && cy <= a.y) {
                let x = if a.y == b.y { a.x.min(b.x) } else { a.x + (cy - a.y) / (b.y - a.y) * (b.x - a.x) };
                let x2 = if a.y == b.y { a.x.max(b.x) } else { x };
                lo = lo.min(x);
                hi = hi.max(x2);
            }
        }
        if lo > hi {
            return;
        }
        let first = ((lo - 0.5).floor() as i64).max(self.x0 as i64);
        let last = ((hi - 0.5).ceil() as i64).min((self.x0 + self.w) as i64 - 1);
        for x in first..=last {
            let c = DVec2::new(x as f64 + 0.5, cy);
            let inside = (0..3).all(|k| {
                let ((i, a), (j, b)) = (corner(k), corner((k + 1) % 3));
                let e = edge((i, a), (j, b), c);
                let d = b - a;
                e > 0.0 || (e == 0.0 && (d.y > 0.0 || (d.y == 0.0 && d.x > 0.0)))
            });
            if inside {
                covered(x as usize);
            }
        }
    }
}

/// The edge function of `a → b` at `c` (positive on its left as the screen
/// shows it, y down: the inside of a counter-clockwise triangle), computed
/// from the corners in index order whichever way the edge runs, so the two
/// triangles beside an edge get exactly opposite values.
fn edge((i, a): (u32, DVec2), (j, b): (u32, DVec2), c: DVec2) -> f64 {
    let (p, q, sign) = if i < j { (a, b, 1.0) } else { (b, a, -1.0) };
    sign * (q - p).perp_dot(c - p)
}

#[cfg(test)]
mod tests {
    use glam::{Affine3A, Vec2, Vec3};

    use super::*;
    use crate::camera::{Camera, Projection};
    use crate::csg::{CsgSolid, CsgTree, Primitive};

    /// A ring of `n` × `m` quads round the z axis (a torus), as a closed mesh.
    fn ring(n: usize, m: usize) -> ClosedMesh {
        let point = |i: usize, j: usize| {
            let (u, v) = (std::f32::consts::TAU * i as f32 / n as f32, std::f32::consts::TAU * j as f32 / m as f32);
            Vec3::new((1.0 + 0.4 * v.cos()) * u.cos(), (1.0 + 0.4 * v.cos()) * u.sin(), 0.4 * v.sin())
        };
        let positions = (0..n).flat_map(|i| (0..m).map(move |j| point(i, j))).collect();
        let index = |i: usize, j: usize| ((i % n) * m + j % m) as u32;
        let triangles = (0..n)
            .flat_map(|i| {
                (0..m).flat_map(move |j| {
                    [
                        [index(i, j), index(i + 1, j), index(i + 1, j + 1)],
                        [index(i, j), index(i + 1, j + 1), index(i, j + 1)],
                    ]
                })
            })
            .collect();
        ClosedMesh::new(positions, triangles).unwrap()
    }

    /// Every pixel's rasterized layers are the caster's, ray by ray: the
    /// same intervals, their ends within rounding, their faces alike.
    #[test]
    fn rasterized_layers_are_the_casters_intervals() {
        let mesh = Arc::new(ring(40, 20));
        let turn = Affine3A::from_rotation_x(0.7) * Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.2));
        let primitives = (0..mesh.layers())
            .map(|layer| Primitive {
                shape: Shape::Mesh { mesh: mesh.clone(), layer },
                transform: turn,
                color: None,
                source: 0..0,
            })
            .collect();
        let caster = CsgCaster::new(&CsgSolid { primitives, tree: Some(CsgTree::mesh_layers(0, mesh.layers())) });
        for projection in [Projection::Perspective { fov_y_deg: 50.0 }, Projection::Orthographic { height: 3.0 }] {
            let camera = Camera {
                eye: Vec3::new(0.5, -3.0, 2.0),
                target: Vec3::ZERO,
                up: Vec3::Z,
                near: 0.1,
                far: 20.0,
                projection,
                shift: Vec2::ZERO,
            };
            let (w, h) = (64usize, 48usize);
            let vp = camera.view_projection(w as f32 / h as f32);
            let rays = camera.pixel_rays(Vec2::new(w as f32, h as f32));
            let layers = MeshLayers::new(&caster, vp, &rays, (w, h), PixelRect::full(w as u32, h as u32));
            assert_eq!(layers.views.len(), 1, "{projection:?}: the mesh is rasterized");
            let (mut met, mut lanes) = (0, IntervalLanes::default());
            for y in 0..h {
                let unit = caster.unit_line(0, &rays.row_line(y));
                for layer in 0..mesh.layers() as usize {
                    for block in 0..w / 8 {
                        assert!(layers.fill(layer, y, block, &mut lanes));
                        for j in 0..8 {
                            let x = block * 8 + j;
                            let (ours, theirs) = (lanes.get(j), caster.span_on(layer, &unit, x as f32));
                            assert_eq!(ours.is_some(), theirs.is_some(), "{projection:?} ({x}, {y}) layer {layer}");
                            if let (Some(a), Some(b)) = (ours, theirs) {
                                met += 1;
                                let near = |p: f32, q: f32| (p - q).abs() <= 1e-4 * p.abs().max(1.0);
                                assert!(
                                    near(a.enter.t, b.enter.t) && near(a.exit.t, b.exit.t),
                                    "({x}, {y}): {a:?} {b:?}"
                                );
                                assert!(a.enter.same_face(&b.enter) && a.exit.same_face(&b.exit), "({x}, {y})");
                            }
                        }
                    }
                }
            }
            assert!(met > 500, "{projection:?}: {met} intervals");
        }
    }
}
