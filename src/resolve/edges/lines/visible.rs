//! Which mesh edges are feature lines, and which stretches of them show: an
//! edge is stepped along a pixel at a time and each step depth-tested
//! against the surface its pixel shows.

use std::sync::Arc;

use glam::{DVec2, DVec3, Vec4};
use rayon::prelude::*;

use super::super::mesh_edges::{meshes_with_edges, MeshEdge, MeshEdges, NO_FACE};
use super::super::screen::{ClipMap, Screen};
use super::super::walk::{DepthScale, Facing};
use super::{Stroke, Strokes};
use crate::scene::{FeatureLines, Mesh, Scene};
use crate::visibility::VisibilityBuffer;

/// Pixels between an edge's depth tests: each step is a stroke of its own.
const STEP: f64 = 1.0;

/// The strokes of every mesh's feature lines (`lines`, drawn `width` pixels
/// wide), shown and hidden, from the edge lists `edges` (per object).
pub(super) fn mesh_strokes(
    scene: &Scene,
    vb: &VisibilityBuffer,
    edges: &[Option<Arc<MeshEdges>>],
    lines: &FeatureLines,
    width: f32,
) -> Strokes {
    let camera = &scene.camera;
    let (w, h) = (vb.width(), vb.height());
    let held = vb.rect();
    // Strokes are cut to the pixels held and a line's width around them.
    let margin = f64::from(width) + 1.0;
    let lo = DVec2::new(f64::from(held.x0), f64::from(held.y0)) - margin;
    let hi = DVec2::new(f64::from(held.x1), f64::from(held.y1)) + margin;
    let tester = Tester {
        scene,
        vb,
        screen: Screen::of(camera, w, h),
        clips: ClipMap::of_objects(scene, w, h),
        depth: DepthScale::of(camera, h),
        window: (lo, hi),
        hidden: lines.hidden,
    };
    let cos_crease = lines.crease_deg.to_radians().cos();
    let per_object: Vec<Strokes> = meshes_with_edges(scene, edges)
        .map(|(index, o, mesh, edges)| {
            let front = Facing::faces(camera, o, edges);
            let two_sided = scene.materials[o.material].two_sided;
            let feature = |e: &&MeshEdge| is_feature(e, &front, two_sided, &edges.planes, cos_crease, lines.hidden);
            // The few lines first, then walked in chunks (folding the walk
            // into the sweep over every edge cost ten times the walk).
            let chosen: Vec<&MeshEdge> = edges.edges.par_iter().filter(feature).collect();
            let chunks: Vec<Strokes> = chosen
                .par_chunks(64)
                .map(|chunk| {
                    let mut out = Strokes::default();
                    chunk.iter().for_each(|e| tester.edge(index, mesh, e, &mut out));
                    out
                })
                .collect();
            chunks.into_iter().fold(Strokes::default(), join)
        })
        .collect();
    per_object.into_iter().fold(Strokes::default(), join)
}

fn join(mut a: Strokes, b: Strokes) -> Strokes {
    a.shown.extend(b.shown);
    a.hidden.extend(b.hidden);
    a
}

/// Whether edge `e` is a feature line: a boundary, a silhouette (one face
/// towards the eye, `front`, the other away) or a crease (face normals more
/// than the crease angle apart: cosine below `cos_crease`), with a face
/// drawn beside it — or, for `hidden` lines, a boundary or crease between
/// faces turned away (the far side of a closed mesh).
fn is_feature(e: &MeshEdge, front: &[bool], two_sided: bool, planes: &[Vec4], cos_crease: f32, hidden: bool) -> bool {
    let [f0, f1] = e.faces;
    let drawn = |f: u32| f != NO_FACE && (two_sided || front[f as usize]);
    let seen = drawn(f0) || drawn(f1);
    if !(seen || hidden) {
        return false;
    }
    if f1 == NO_FACE {
        return true;
    }
    let (n0, n1) = (planes[f0 as usize].truncate(), planes[f1 as usize].truncate());
    // A face without area has no normal: no crease beside it.
    let folded = n0.length_squared() > 0.25 && n1.length_squared() > 0.25 && n0.dot(n1) < cos_crease;
    (seen && front[f0 as usize] != front[f1 as usize]) || folded
}

/// What depth-testing an edge reads: the frame's visibility buffer and the view.
struct Tester<'a> {
    scene: &'a Scene,
    vb: &'a VisibilityBuffer,
    screen: Screen,
    clips: Vec<ClipMap>,
    depth: DepthScale,
    /// The screen window strokes are cut to (min, max).
    window: (DVec2, DVec2),
    /// Whether hidden stretches are kept.
    hidden: bool,
}

impl Tester<'_> {
    /// Adds the strokes of edge `e` of object `object` (mesh `mesh`) to `out`:
    /// one a step, each step [`STEP`] long counted from the edge's projected
    /// start, so a step is the same stroke in every tile of a frame (only
    /// the steps inside the window are drawn).
    fn edge(&self, object: usize, mesh: &Mesh, e: &MeshEdge, out: &mut Strokes) {
        let clip = &self.clips[object];
        let [a, b] = e.v.map(|i| clip.points * mesh.positions[i as usize].as_dvec3().extend(1.0));
        let Some((a, b)) = self.screen.clip_and_project(a, b) else { return };
        let Some((t0, t1)) = window_span(a, b, self.window) else { return };
        let length = (b.truncate() - a.truncate()).length();
        let steps = (length / STEP).ceil().max(1.0);
        let at = |t: f64| a.lerp(b, t);
        let first = (t0 * steps).floor() as u64;
        let last = ((t1 * steps).ceil() as u64).max(first + 1);
        for i in first..last {
            let (from, to) = (i as f64 / steps, ((i + 1) as f64 / steps).min(1.0));
            let hidden = self.hidden_at(object as u32, e, at(0.5 * (from + to)));
            let stroke = Stroke { a: at(from).truncate(), b: at(to).truncate(), start: from * length };
            match hidden {
                false => out.shown.push(stroke),
                true if self.hidden => out.hidden.push(stroke),
                true => {}
            }
        }
    }

    /// Whether the edge `e` of `object` is hidden at screen point `q` (x, y
    /// in pixels, z stored depth): the surface the pixel under `q` shows lies
    /// nearer than `q` even a pixel to either side (a surface seen at a
    /// grazing angle beside a silhouette, whose plane passes close to the
    /// edge, does not hide it), and is not a face beside the edge.
    fn hidden_at(&self, object: u32, e: &MeshEdge, q: DVec3) -> bool {
        let held = self.vb.rect();
        let x = (q.x.floor().max(0.0) as u32).clamp(held.x0, held.x1 - 1);
        let y = (q.y.floor().max(0.0) as u32).clamp(held.y0, held.y1 - 1);
        let i = self.vb.index(x, y);
        let item = self.vb.items()[i];
        if item.is_none() {
            return false;
        }
        if item.object == object && item.primitive().is_none() && e.faces.contains(&item.triangle) {
            return false;
        }
        let d = &self.depth;
        let edge = d.distance(q.z);
        let farthest = match item.primitive() {
            None => {
                let mesh = self.scene.objects.get(item.object as usize).and_then(|o| o.triangles());
                let plane =
                    mesh.and_then(|m| self.screen.depth_plane(&self.clips[item.object as usize], m, item.triangle));
                match plane {
                    // Stored depth falls with distance: the farthest of the
                    // plane at q and a pixel to either side is its least depth.
                    Some(p) => d.distance(p.at(q.x, q.y) - p.gx.abs().max(p.gy.abs())),
                    None => return false, // seen edge-on: it hides nothing
                }
            }
            // A solid's surface: its depth at the pixel's centre, a pixel's
            // size farther.
            Some(_) => {
                let at = d.distance(f64::from(self.vb.depths()[i]));
                at + d.pixel_at(at)
            }
        };
        farthest < edge - 0.01 * d.pixel_at(edge)
    }
}

/// The span `t0 ..= t1` of segment `a`–`b` (screen points, `a + t·(b − a)`)
/// inside the window `(lo, hi)` in x and y; `None` if it misses it.
fn window_span(a: DVec3, b: DVec3, (lo, hi): (DVec2, DVec2)) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let d = b - a;
    for (p, q) in [(-d.x, a.x - lo.x), (d.x, hi.x - a.x), (-d.y, a.y - lo.y), (d.y, hi.y - a.y)] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segment_is_cut_to_the_window() {
        let window = (DVec2::ZERO, DVec2::new(10.0, 10.0));
        let span = window_span(DVec3::new(-5.0, 5.0, 0.0), DVec3::new(15.0, 5.0, 1.0), window);
        assert_eq!(span, Some((0.25, 0.75)));
        assert!(window_span(DVec3::new(-5.0, -1.0, 0.0), DVec3::new(15.0, -1.0, 0.0), window).is_none());
    }

    #[test]
    fn features_are_silhouettes_boundaries_and_folds() {
        let plane = |n: glam::Vec3| n.extend(0.0);
        let planes = [plane(glam::Vec3::Z), plane(glam::Vec3::Z), plane(glam::Vec3::X), plane(glam::Vec3::ZERO)];
        let edge = |f0, f1| MeshEdge { v: [0, 1], faces: [f0, f1], crease: false };
        let cos = 30f32.to_radians().cos();
        let all_front = [true; 4];
        let feature = |e, front: &[bool], two_sided, hidden| is_feature(&e, front, two_sided, &planes, cos, hidden);
        assert!(!feature(edge(0, 1), &all_front, false, false), "coplanar faces");
        assert!(feature(edge(0, 2), &all_front, false, false), "a 90° fold");
        assert!(feature(edge(0, NO_FACE), &all_front, false, false), "a boundary");
        assert!(!feature(edge(0, 3), &all_front, false, false), "a face without area");
        let silhouette = [true, false, true, true];
        assert!(feature(edge(0, 1), &silhouette, false, false), "one face away from the eye");
        let back = [false; 4];
        assert!(!feature(edge(0, 2), &back, false, false), "both faces culled");
        assert!(feature(edge(0, 2), &back, false, true), "a fold on the far side, for hidden lines");
        assert!(!feature(edge(0, 1), &back, false, true), "no silhouette between two culled faces");
        assert!(feature(edge(0, 2), &back, true, false), "both drawn when two-sided");
    }
}
