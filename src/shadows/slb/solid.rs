//! A CSG solid's outline as a light sees it, for the silhouette-line buffer.
//!
//! A solid has no triangles to walk. Its outline is traced on a lattice of
//! sample points: the light's texel centres, where seed 003's scanline walk
//! finds which the solid covers and its depth there (the map it would cast
//! alone); or, for a solid less than [`FINE_CELLS`] texels across (the
//! virtual projection space makes most of them so), a lattice 2 to 16 times
//! finer over its projection, sampled by rays, so that a solid a texel wide
//! still has an outline [`FINE_CELLS`] cells long each way. Where two
//! neighbouring samples disagree,
//! the outline crosses the segment between them, and rays from the light
//! find where, by bisection, to 2^−(k + 4) of a cell (or the rays' own
//! single precision). Each square of four neighbouring centres the outline
//! crosses (marching squares; a saddle is settled by a ray at its middle),
//! and each square next to one, becomes the polygon of its covered part,
//! fanned into triangles whose corners carry the solid's depth: the buffer
//! then walks the outline as it walks a mesh's silhouette, the squares'
//! shared sides cancel as a mesh's shared edges do, and the sides of the
//! band that lie inside the solid are left unwalked. Every edge texel the
//! band does not reach keeps the solid as a layer over its centre
//! ([`SolidCoverage`]).
//!
//! Exact where the outline is straight between two neighbouring centres'
//! crossings (a polyhedron's edge away from its corners); a curved outline
//! becomes chords at most a cell long, off by 1/(8r) of a cell for a circle
//! of radius r cells (1/256 at r = 32). An outline that crosses a square's
//! side twice, or a part narrower than a cell lying between samples, is
//! missed as a shadow map misses what lies between its texel centres. The
//! band follows where the solid covers the map, not where one part of it
//! lies in front of another: those steps are left to the eye pass, which
//! casts a ray through the solid from a point next to one
//! ([`SolidOutlines::casters`]).

use glam::{DVec2, DVec3, Vec2};
use rayon::prelude::*;

use super::light::LightTriangle;
use super::line::{Facing, Layer, TexelDepth};
use crate::camera::{Camera, PixelRays};
use crate::csg::{CsgCaster, CsgSolid};
use crate::scene::Scene;
use crate::shadows::map::DepthMap;
use crate::visibility::solids::draw_solids;
use crate::visibility::VisibilityBuffer;

/// Cells across a solid's projection below which its outline is traced on a
/// finer lattice than the texels.
pub const FINE_CELLS: f64 = 64.0;

/// The finest lattice: this many cells per texel.
const MAX_FINENESS: u32 = 16;

/// One polygon vertex: texel coordinates and reversed depth.
type Corner = DVec3;

/// Sample points `origin + (i, j)·step` for `i < nx`, `j < ny`, in texel
/// coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lattice {
    /// Sample (0, 0).
    pub origin: DVec2,
    /// Texels between neighbouring samples (1, or a power of ½).
    pub step: f64,
    /// Samples along x.
    pub nx: usize,
    /// Samples along y.
    pub ny: usize,
}

impl Lattice {
    /// The texel centres of a `resolution`² map.
    #[must_use]
    pub fn centres(resolution: u32) -> Lattice {
        let n = resolution as usize;
        Lattice { origin: DVec2::splat(0.5), step: 1.0, nx: n, ny: n }
    }

    /// Sample `(i, j)`.
    fn at(&self, i: usize, j: usize) -> DVec2 {
        self.origin + DVec2::new(i as f64, j as f64) * self.step
    }

    /// The square (lower corner's sample) holding texel point `p` nudged by
    /// (ε, ε²), as the buffer's centre tests nudge it; `None` outside.
    #[must_use]
    pub fn square_of(&self, p: DVec2) -> Option<(usize, usize)> {
        // Steps are powers of two and points on the texel grid's halves: the
        // division is exact, and a point on a sample line goes to the square
        // past it, as the nudge does.
        let q = (p - self.origin) / self.step;
        let (i, j) = (q.x.floor(), q.y.floor());
        let inside = i >= 0.0 && j >= 0.0 && (i as usize) + 1 < self.nx && (j as usize) + 1 < self.ny;
        inside.then_some((i as usize, j as usize))
    }
}

/// Where a CSG solid covers the light's texel centres, for the edge texels
/// its outline band ([`super::solid`]) does not reach: there the solid is a
/// layer over the centre at its depth (a flat plane: only the centre's depth
/// is read).
#[derive(Debug, Clone)]
pub struct SolidCoverage {
    /// The solid's object.
    pub object: u32,
    /// The samples its outline was traced on.
    pub lattice: Lattice,
    /// Per square of the lattice (row-major, by its lower corner), whether
    /// the band's triangles cover it.
    pub band: Vec<bool>,
    /// The texels `(x0, y0, width, height)` whose centres `depth` holds.
    pub texels: (usize, usize, usize, usize),
    /// Reversed depth of the solid alone at those centres (0: absent).
    pub depth: Vec<f32>,
}

impl SolidCoverage {
    /// The solid's layer over the centre of texel `(x, y)`, where no band
    /// triangle holds it.
    #[must_use]
    pub fn layer(&self, x: usize, y: usize) -> Option<Layer> {
        let (x0, y0, w, h) = self.texels;
        if x < x0 || y < y0 || x >= x0 + w || y >= y0 + h {
            return None;
        }
        let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
        let cells = self.lattice.nx.saturating_sub(1);
        if self.lattice.square_of(centre).is_some_and(|(i, j)| self.band[j * cells + i]) {
            return None;
        }
        let z = self.depth[(y - y0) * w + (x - x0)];
        (z > 0.0).then_some(Layer {
            depth: TexelDepth { c: z, dx: 0.0, dy: 0.0 },
            count: 1,
            object: self.object,
            facing: Facing::Unknown,
        })
    }
}

/// A solid seen by a light: its samples, its caster and the rays.
struct LightView<'a> {
    lattice: Lattice,
    /// Reversed depth per sample (0: not covered).
    depth: &'a [f32],
    caster: &'a CsgCaster,
    rays: &'a PixelRays,
    camera: &'a Camera,
    /// Bisection steps per crossing.
    steps: u32,
}

/// The reversed depth of `caster`'s solid at texel coordinates `p` of the map
/// `rays` make for `camera`, where the map would hold it (between its
/// planes); `None` where it does not.
pub(super) fn depth_at(caster: &CsgCaster, rays: &PixelRays, camera: &Camera, p: DVec2) -> Option<f64> {
    let ray = rays.ray(Vec2::new(p.x as f32, p.y as f32));
    let hit = caster.first_hit(&ray, 0.0, f32::INFINITY)?;
    let axis = (camera.target - camera.eye).normalize();
    let along = (ray.origin + ray.dir * hit.t - camera.eye).dot(axis);
    let z = camera.depth_at_view_distance(along);
    (z >= camera.far_plane_factor() && z <= 1.0).then_some(f64::from(z))
}

impl LightView<'_> {
    /// Whether the solid covers sample `(i, j)`.
    fn covers(&self, i: usize, j: usize) -> bool {
        self.depth[j * self.lattice.nx + i] > 0.0
    }

    /// Sample `(i, j)` with the solid's depth there.
    fn sample(&self, i: usize, j: usize) -> Corner {
        self.lattice.at(i, j).extend(f64::from(self.depth[j * self.lattice.nx + i]))
    }

    fn depth_at(&self, p: DVec2) -> Option<f64> {
        depth_at(self.caster, self.rays, self.camera, p)
    }

    /// Where the outline crosses from the covered sample `inside` towards
    /// the uncovered `outside`: bisection by rays, the last covered point's
    /// depth.
    fn bisect(&self, inside: Corner, outside: Corner) -> Corner {
        let (mut a, mut b) = (inside, outside);
        let mut z = inside.z;
        for _ in 0..self.steps {
            let m = (a + b) * 0.5;
            match self.depth_at(m.truncate()) {
                Some(d) => (a, z) = (m, d),
                None => b = m,
            }
        }
        let m = (a + b) * 0.5;
        DVec3::new(m.x, m.y, z)
    }
}

/// Side `s` of square `(i, j)` as the sample it starts from (the one of
/// lower index) and whether it runs along +y.
#[expect(clippy::type_complexity, reason = "a table of four small functions")]
const SIDES: [(fn(usize, usize) -> (usize, usize), bool); 4] =
    [(|i, j| (i, j), false), (|i, j| (i + 1, j), true), (|i, j| (i, j + 1), false), (|i, j| (i, j), true)];

/// Square `(i, j)` has corners at samples `(i, j)`, `(i + 1, j)`, `(i + 1,
/// j + 1)`, `(i, j + 1)`: its sides, in that order round it, are 0 top,
/// 1 right, 2 bottom, 3 left.
const CORNERS: [(usize, usize); 4] = [(0, 0), (1, 0), (1, 1), (0, 1)];

/// Texels `(x0, y0, width, height)` of the map.
type TexelRect = (usize, usize, usize, usize);

/// What the light pass keeps of the CSG solids among a light's casters.
#[derive(Debug, Default)]
pub struct SolidOutlines {
    /// Their outline bands' triangles.
    pub triangles: Vec<LightTriangle>,
    /// Where each covers the texel centres.
    pub coverages: Vec<SolidCoverage>,
    /// Each solid in world space, ready for rays, with its object.
    pub casters: Vec<(u32, CsgCaster)>,
}

/// The outline bands, coverages and casters of the CSG solids among the
/// casters `casters` marks, seen by `camera` in a `resolution`² map with
/// `bits`-bit lines.
#[must_use]
pub fn solid_outlines(scene: &Scene, camera: &Camera, resolution: u32, casters: &[bool], bits: u32) -> SolidOutlines {
    let mut out = SolidOutlines::default();
    for (object, o) in scene.objects.iter().enumerate().filter(|&(i, _)| casters.get(i) == Some(&true)) {
        let Some(solid) = o.solid() else { continue };
        // The solid alone, as the map would hold it.
        let map_depth = || {
            let mut alone = VisibilityBuffer::depth_only(resolution, resolution);
            draw_solids(scene, camera, |i| i == object, &mut alone);
            alone.depths().to_vec()
        };
        let world = solid.transformed(&o.transform);
        let (outline, coverage, caster) = solid_outline(&world, object as u32, camera, resolution, bits, map_depth);
        out.triangles.extend(outline);
        out.coverages.push(coverage);
        out.casters.push((object as u32, caster));
    }
    out
}

/// The triangles of `solid`'s outline band, its coverage of the texel
/// centres and the caster its rays were cast through, seen by `camera` in a
/// `resolution`² map with `bits`-bit lines. `map_depth` gives the solid's
/// reversed depth at every texel centre (0 where it is absent), asked for
/// only when the texels are the lattice. `solid` is in world space; its
/// triangles belong to object `object`.
#[must_use]
pub fn solid_outline(
    solid: &CsgSolid,
    object: u32,
    camera: &Camera,
    resolution: u32,
    bits: u32,
    map_depth: impl FnOnce() -> Vec<f32>,
) -> (Vec<LightTriangle>, SolidCoverage, CsgCaster) {
    let caster = CsgCaster::new(solid);
    let rays = camera.pixel_rays(Vec2::splat(resolution as f32));
    let sample = |p: DVec2| depth_at(&caster, &rays, camera, p).map_or(0.0, |z| z as f32);
    let (lattice, texels) = lattice_for(solid, camera, resolution);
    let (x0, y0, w, h) = texels;
    let (depth, centres) = if lattice.step < 1.0 {
        let depth = (0..lattice.nx * lattice.ny)
            .into_par_iter()
            .map(|k| sample(lattice.at(k % lattice.nx, k / lattice.nx)))
            .collect();
        let centre = |k: usize| DVec2::new((x0 + k % w) as f64 + 0.5, (y0 + k / w) as f64 + 0.5);
        (depth, Some((0..w * h).into_par_iter().map(|k| sample(centre(k))).collect()))
    } else {
        // The texel centres are the lattice: the solid's own map, cut to it.
        let map = map_depth();
        let n = resolution as usize;
        let rect: Vec<f32> = (0..h).flat_map(|j| &map[(y0 + j) * n + x0..(y0 + j) * n + x0 + w]).copied().collect();
        (rect, None)
    };
    let view = LightView { lattice, depth: &depth, caster: &caster, rays: &rays, camera, steps: (bits + 4).min(20) };
    let crossings = Crossings::new(&view);
    let band = band(&view);
    let (cx, cy) = (lattice.nx.saturating_sub(1), lattice.ny.saturating_sub(1));
    let triangles: Vec<LightTriangle> = (0..cx * cy)
        .into_par_iter()
        .filter(|&k| band[k])
        .flat_map_iter(|k| {
            let (i, j) = (k % cx, k / cx);
            let in_band = |a: Option<usize>, b: Option<usize>| match (a, b) {
                (Some(a), Some(b)) if a < cx && b < cy => band[b * cx + a],
                _ => false,
            };
            // Whether the square across each side is in the band.
            let across = [
                in_band(Some(i), j.checked_sub(1)),
                in_band(Some(i + 1), Some(j)),
                in_band(Some(i), Some(j + 1)),
                in_band(i.checked_sub(1), Some(j)),
            ];
            square_triangles(&view, &crossings, (i, j), across, object, k as u32)
        })
        .collect();
    let depth = centres.unwrap_or(depth);
    (triangles, SolidCoverage { object, lattice, band, texels, depth }, caster)
}

/// Where the outline crosses each side of the lattice's squares whose ends
/// disagree, found once for the two squares that share it: by the side's
/// key (`2 × sample + 0` towards +x, `+ 1` towards +y), sorted.
#[derive(Debug)]
struct Crossings {
    at: Vec<(usize, Corner)>,
}

impl Crossings {
    /// Every crossing of `view`'s lattice, by bisection.
    fn new(view: &LightView<'_>) -> Crossings {
        let (nx, ny) = (view.lattice.nx, view.lattice.ny);
        let at = (0..2 * nx * ny)
            .into_par_iter()
            .filter_map(|key| {
                let (k, up) = (key / 2, key % 2 == 1);
                let (i, j) = (k % nx, k / nx);
                let (a, b) = if up { (i, j + 1) } else { (i + 1, j) };
                if a >= nx || b >= ny || view.covers(i, j) == view.covers(a, b) {
                    return None;
                }
                let (p, q) = (view.sample(i, j), view.sample(a, b));
                let x = if view.covers(i, j) { view.bisect(p, q) } else { view.bisect(q, p) };
                Some((key, x))
            })
            .collect();
        Crossings { at }
    }

    /// The crossing between sample `(i, j)` and its neighbour along +x
    /// (`up` false) or +y, in a lattice `nx` samples wide.
    fn between(&self, nx: usize, (i, j): (usize, usize), up: bool) -> Corner {
        let key = 2 * (j * nx + i) + usize::from(up);
        let k = self.at.binary_search_by_key(&key, |c| c.0).expect("a crossing on every side whose ends disagree");
        self.at[k].1
    }
}

/// The lattice `solid`'s outline is traced on, and the texels it spans: its
/// projection's bounding box in the map with a texel's margin round it —
/// on the texel centres, or 2 to 16 times finer when the box is less than
/// [`FINE_CELLS`] texels across. The whole map where the box has a corner
/// behind the light.
fn lattice_for(solid: &CsgSolid, camera: &Camera, resolution: u32) -> (Lattice, TexelRect) {
    let n = f64::from(resolution);
    let whole = (Lattice::centres(resolution), (0, 0, resolution as usize, resolution as usize));
    let Some((min, max)) = projected_box(solid, camera, n) else { return whole };
    let across = (max - min).max_element();
    let step = if across < FINE_CELLS {
        let fineness = (FINE_CELLS / across.max(1e-9)).log2().floor().exp2().clamp(2.0, f64::from(MAX_FINENESS));
        1.0 / fineness
    } else {
        1.0
    };
    let x0 = (min.x - 1.0).floor().clamp(0.0, n - 1.0);
    let y0 = (min.y - 1.0).floor().clamp(0.0, n - 1.0);
    let x1 = (max.x + 1.0).ceil().clamp(x0 + 1.0, n);
    let y1 = (max.y + 1.0).ceil().clamp(y0 + 1.0, n);
    let origin = DVec2::new(x0, y0) + step * 0.5;
    let (nx, ny) = (((x1 - x0) / step) as usize, ((y1 - y0) / step) as usize);
    let texels = (x0 as usize, y0 as usize, (x1 - x0) as usize, (y1 - y0) as usize);
    (Lattice { origin, step, nx, ny }, texels)
}

/// The bounding box, in texel coordinates of an `n`² map of `camera`, of
/// the projection of `solid`'s bounds; `None` when a corner lies behind the
/// light or the solid has none.
fn projected_box(solid: &CsgSolid, camera: &Camera, n: f64) -> Option<(DVec2, DVec2)> {
    let (lo, hi) = solid.bounds()?;
    let m = camera.view_projection(1.0).as_dmat4();
    let (mut min, mut max) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for k in 0..8 {
        let pick = |bit: usize, l: f32, h: f32| f64::from(if k & bit == 0 { l } else { h });
        let p = m * DVec3::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z)).extend(1.0);
        if p.w <= 1e-9 {
            return None;
        }
        let t = DVec2::new((p.x / p.w * 0.5 + 0.5) * n, (0.5 - p.y / p.w * 0.5) * n);
        (min, max) = (min.min(t), max.max(t));
    }
    (min.is_finite() && max.is_finite()).then_some((min, max))
}

/// Per square of `view`'s lattice, whether it is in the band: the outline
/// crosses it or a neighbour, and the solid covers a corner.
fn band(view: &LightView<'_>) -> Vec<bool> {
    let (cx, cy) = (view.lattice.nx.saturating_sub(1), view.lattice.ny.saturating_sub(1));
    let corners = |i: usize, j: usize| CORNERS.map(|(dx, dy)| view.covers(i + dx, j + dy));
    let crossed: Vec<bool> = (0..cx * cy)
        .into_par_iter()
        .map(|k| {
            let c = corners(k % cx, k / cx);
            c.iter().any(|&v| v) && !c.iter().all(|&v| v)
        })
        .collect();
    (0..cx * cy)
        .into_par_iter()
        .map(|k| {
            let (i, j) = (k % cx, k / cx);
            let near = (j.saturating_sub(1)..=(j + 1).min(cy - 1))
                .any(|b| (i.saturating_sub(1)..=(i + 1).min(cx - 1)).any(|a| crossed[b * cx + a]));
            near && corners(i, j).iter().any(|&v| v)
        })
        .collect()
}
/// The covered part of square `(i, j)` as triangles, its outline through
/// `crossings`: `across[s]` says
/// whether the square beyond side `s` is in the band (a side with none is
/// not walked).
fn square_triangles(
    view: &LightView<'_>,
    crossings: &Crossings,
    (i, j): (usize, usize),
    across: [bool; 4],
    object: u32,
    polygon: u32,
) -> Vec<LightTriangle> {
    let corner = |c: usize| view.sample(i + CORNERS[c].0, j + CORNERS[c].1);
    let covered = CORNERS.map(|(dx, dy)| view.covers(i + dx, j + dy));
    // A saddle: two opposite corners covered; a ray at the middle decides
    // whether they join.
    let saddle = covered[0] == covered[2] && covered[1] == covered[3] && covered[0] != covered[1];
    let joined = saddle && view.depth_at(view.lattice.at(i, j) + view.lattice.step * 0.5).is_some();
    // Walk round the square: covered corners and crossings, each vertex with
    // the side it starts (the side the edge to the next vertex lies along,
    // if any).
    let mut polygons: Vec<Vec<(Corner, Option<usize>)>> = vec![Vec::new()];
    for (s, side) in SIDES.iter().enumerate() {
        let (a, b) = (s, (s + 1) % 4);
        if covered[a] {
            // The edge from a corner runs along side s to the next corner or
            // to the crossing on it.
            polygons.last_mut().expect("one polygon").push((corner(a), Some(s)));
        }
        if covered[a] != covered[b] {
            let x = crossings.between(view.lattice.nx, side.0(i, j), side.1);
            // From a crossing entering the covered part, the edge runs along
            // the side; from one leaving it, across the square (the outline).
            let along = if covered[a] { None } else { Some(s) };
            polygons.last_mut().expect("one polygon").push((x, along));
            if saddle && !joined && covered[a] {
                polygons.push(Vec::new());
            }
        }
    }
    // A walk that began inside a polygon split at a saddle ends with that
    // polygon's start: close it.
    if polygons.len() > 1 {
        let first = polygons.remove(0);
        polygons.last_mut().expect("one polygon").extend(first);
    }
    let mut out = Vec::new();
    for polygon_vertices in polygons.into_iter().filter(|p| p.len() >= 3) {
        fan(&polygon_vertices, across, object, polygon, &mut out);
    }
    out
}

/// Fans the convex polygon `v` (each vertex with the square's side its edge
/// to the next runs along) into triangles; an edge along a side with no
/// band square beyond it is marked open.
fn fan(v: &[(Corner, Option<usize>)], across: [bool; 4], object: u32, polygon: u32, out: &mut Vec<LightTriangle>) {
    let open_edge = |k: usize| v[k].1.is_some_and(|s| !across[s]);
    let last = v.len() - 1;
    for t in 1..last {
        // Edges of triangle (0, t, t + 1): 0→t is a polygon edge only for t = 1,
        // t→t+1 always, t+1→0 only for the last.
        let mut open = 0u8;
        if t == 1 && open_edge(0) {
            open |= 1;
        }
        if open_edge(t) {
            open |= 2;
        }
        if t + 1 == last && open_edge(last) {
            open |= 4;
        }
        let points = [v[0].0, v[t].0, v[t + 1].0];
        out.push(LightTriangle { points, object, polygon, open, facing: Facing::Unknown });
    }
}

/// The texels of `map` within one texel of a place where a CSG solid's own
/// depth (`coverages`, at the texel centres) breaks between two neighbouring
/// centres — a step, where one part of the solid lies in front of another,
/// or a crease sharp enough to hide one: the difference between the two
/// centres' distances is off the slope on either side (the differences to
/// the next centres out, where the solid covers them; with neither, any
/// difference) by more than `bias` texels, the small bias another object's
/// surface is held to; and every texel of a solid less than a few dozen
/// texels across (traced on a finer lattice). A point
/// there may lie on either side of the break within its texel, which the
/// map's centres cannot tell; the eye pass looks closer
/// ([`super::SlbMap`]). One bit per texel (none without solids).
#[must_use]
pub fn solid_steps(map: &DepthMap, coverages: &[SolidCoverage], bias: f32) -> Vec<u64> {
    if coverages.is_empty() {
        return Vec::new();
    }
    let n = map.resolution() as usize;
    let mut bits = vec![0u64; (n * n).div_ceil(64)];
    for c in coverages {
        let (x0, y0, w, h) = c.texels;
        let at = |i: isize, j: isize| -> Option<(f32, f32)> {
            let inside = i >= 0 && j >= 0 && (i as usize) < w && (j as usize) < h;
            let z = if inside { c.depth[j as usize * w + i as usize] } else { 0.0 };
            (z > 0.0).then(|| map.distance_and_texel(z))
        };
        let breaks = |i: isize, j: isize, (di, dj): (isize, isize)| {
            let (Some((a, texel)), Some((b, _))) = (at(i, j), at(i + di, j + dj)) else { return false };
            let step = b - a;
            let before = at(i - di, j - dj).map(|(p, _)| a - p);
            let after = at(i + 2 * di, j + 2 * dj).map(|(q, _)| q - b);
            [before, after].into_iter().flatten().all(|s| (step - s).abs() > texel * bias)
        };
        let mut mark = |i: isize, j: isize| {
            for y in (y0 as isize + j - 1).max(0)..=(y0 as isize + j + 1).min(n as isize - 1) {
                for x in (x0 as isize + i - 1).max(0)..=(x0 as isize + i + 1).min(n as isize - 1) {
                    let t = y as usize * n + x as usize;
                    bits[t / 64] |= 1 << (t % 64);
                }
            }
        };
        // A solid traced on a finer lattice than the texels is a few texels
        // across: a step may lie between any of its centres.
        let small = c.lattice.step < 1.0;
        for j in 0..h as isize {
            for i in 0..w as isize {
                for d in [(1, 0), (0, 1)] {
                    if small && at(i, j).is_some() || breaks(i, j, d) {
                        mark(i, j);
                        mark(i + d.0, j + d.1);
                    }
                }
            }
        }
    }
    bits
}
