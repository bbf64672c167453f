//! Scanline visibility of CSG solids (seed 003 §5; issue 6), first form.
//!
//! The frame is walked the paper's way: primitives are bucket-sorted by their
//! top scanline into the y-entry table; each scanline moves entering primitives
//! into the y-occupancy list and drops those whose bottom it passed, bucket-sorts
//! the occupants by left end into the x-entry table, and walks its pixels keeping
//! the x-occupancy list: primitives enter at their left end and leave after their
//! right end. A pixel with occupants gets its visible surface from the depth
//! intervals of the occupants only ([`crate::raytrace::csg::primitive_span`],
//! seed 003's procedure 3 in closed form).
//!
//! Beyond the paper (its own named defect, and OpenSCAD's aborted previews past
//! 100,000 terms): the boolean tree is not expanded into a sum of products up
//! front. Whenever the x-occupancy list changes, the tree is cut down to the
//! occupants ([`CsgTree::restricted`]) and the pixels until the next change share
//! that small tree — seed 003's coherence (§5.2.2) applied to the expression
//! instead of the visible-segment list. Intervals are combined along the cut-down
//! tree, so a difference costs no more than an intersection.
//!
//! Extents (procedures 1 and 2): an ellipsoid seen in perspective from outside
//! gets the paper's exact rows (scanline planes through the eye tangent to it)
//! and, per scanline, exact left and right ends (lines through the eye tangent to
//! it), both closed-form quadratics. Every other primitive —
//! frustums and polyhedra for now, and everything under an orthographic camera —
//! uses the projection of its bounding corners, the same columns on every row it
//! spans (the whole screen when a corner lies behind the eye). A too-wide extent
//! only costs time: where a primitive does not reach, its interval is empty.

use glam::{Mat4, Vec2, Vec3, Vec4};
use rayon::iter::IndexedParallelIterator;
use rayon::prelude::*;

use crate::raytrace::csg::{Crossing, CsgCaster, SpanScratch};
use crate::scene::camera::PixelRays;
use crate::scene::csg::{CsgSolid, CsgTree, Primitive, Shape};
use crate::scene::{Camera, Ray, Scene};
use crate::visibility::{ItemId, VisibilityBuffer};

/// Rows scanned by one worker in turn.
const BAND_ROWS: usize = 16;

/// How far (in pixels) an exact extent is widened, so that rounding never drops
/// a pixel whose ray grazes the primitive.
const ROUNDING_PX: f64 = 1e-3;

/// Pixels a primitive may cover: rows `y0..=y1`, columns `x0..=x1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Extent {
    x0: i64,
    x1: i64,
    y0: i64,
    y1: i64,
}

/// The visible surface of `solid` (in world space) at each pixel centre of a
/// `width` x `height` image seen by `camera`, rows top to bottom: the first
/// crossing beyond the near plane, or `None`.
#[must_use]
pub fn scan_solid(solid: &CsgSolid, camera: &Camera, width: u32, height: u32) -> Vec<Option<Crossing>> {
    let (w, h) = (width as usize, height as usize);
    let mut out = vec![None; w * h];
    let bands = out.par_chunks_mut(w * BAND_ROWS);
    scan_bands(solid, camera, (width, height), bands, |band, dy, row| {
        band[dy * w..(dy + 1) * w].copy_from_slice(row);
    });
    out
}

/// Draws every solid of `scene` seen by `camera` into `vb` (after its
/// polygons): where a solid's visible surface lies nearer than what the pixel
/// holds and between the near and far planes, the pixel takes its depth, its
/// item (object + primitive) and its outward normal. A depth-only buffer (a
/// shadow map) takes the depth alone. Returns the number of solids drawn.
pub fn draw_solids(scene: &Scene, camera: &Camera, vb: &mut VisibilityBuffer) -> usize {
    let (width, height) = (vb.width(), vb.height());
    let w = width as usize;
    let vp = camera.view_projection(width as f32 / height as f32);
    let far = camera.far_plane_factor();
    let rays = camera.pixel_rays(Vec2::new(width as f32, height as f32));
    let mut drawn = 0;
    for (object, o) in scene.objects.iter().enumerate() {
        let Some(solid) = o.solid() else { continue };
        let world = solid.transformed(&o.transform);
        let (depth, items, normals) = vb.solid_parts_mut();
        let n = w * BAND_ROWS;
        let (mut items, mut normals) = (items.chunks_mut(n), normals.chunks_mut(n));
        // Depth-only buffers have no items or normals: their bands get empty slices.
        let bands: Vec<(&mut [f32], &mut [ItemId], &mut [Vec3])> = depth
            .chunks_mut(n)
            .map(|d| (d, items.next().unwrap_or(&mut []), normals.next().unwrap_or(&mut [])))
            .collect();
        let bands = bands.into_par_iter().enumerate();
        scan_bands(&world, camera, (width, height), bands, |(band, (depth, items, normals)), dy, row| {
            let y = *band * BAND_ROWS + dy;
            for (x, c) in row.iter().enumerate().filter_map(|(x, c)| Some((x, c.as_ref()?))) {
                let point = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).at(c.t);
                let clip = vp * point.extend(1.0);
                let z = clip.z / clip.w;
                let i = dy * w + x;
                if z > depth[i] && z >= far && z <= 1.0 {
                    depth[i] = z;
                    if !items.is_empty() {
                        items[i] = ItemId::primitive_of(object as u32, c.primitive as u32);
                        normals[i] = c.normal;
                    }
                }
            }
        });
        drawn += 1;
    }
    drawn
}

/// The walk itself: for each band of [`BAND_ROWS`] rows (in parallel, `bands`
/// gives each its output), `visit(band, row_in_band, crossings)` with the row's
/// visible crossings.
fn scan_bands<B: Send>(
    solid: &CsgSolid,
    camera: &Camera,
    (width, height): (u32, u32),
    bands: impl IndexedParallelIterator<Item = B>,
    visit: impl Fn(&mut B, usize, &[Option<Crossing>]) + Sync,
) {
    let (w, h) = (width as usize, height as usize);
    let Some(tree) = &solid.tree else { return };
    let vp = camera.view_projection(width as f32 / height as f32);
    let rays = camera.pixel_rays(Vec2::new(width as f32, height as f32));
    let outlines: Vec<Option<Outline>> = solid.primitives.iter().map(|p| Outline::new(p, vp, &rays)).collect();
    // The y-entry table: the primitives that show at all, by top scanline.
    let mut entry: Vec<(usize, Extent)> =
        outlines.iter().enumerate().filter_map(|(i, o)| o.as_ref().map(|o| (i, o.rows))).collect();
    entry.sort_by_key(|(_, e)| e.y0);
    let caster = CsgCaster::new(solid);
    // Depth 1 is the near plane, under either projection.
    let near = |ray: &Ray| camera.distance_at_depth(ray, 1.0);
    bands.enumerate().for_each_init(
        || vec![None; w],
        |row, (band, mut out)| {
            let first = (band * BAND_ROWS) as i64;
            // The y-occupancy list as the band's first scanline finds it, then kept
            // row by row.
            let mut next = entry.partition_point(|(_, e)| e.y0 <= first);
            let mut occupied: Vec<(usize, Extent)> =
                entry[..next].iter().copied().filter(|(_, e)| e.y1 >= first).collect();
            for dy in 0..BAND_ROWS.min(h - band * BAND_ROWS) {
                let y = first + dy as i64;
                while next < entry.len() && entry[next].1.y0 <= y {
                    occupied.push(entry[next]);
                    next += 1;
                }
                occupied.retain(|(_, e)| e.y1 >= y);
                // Procedure 2: each occupant's left and right ends on this scanline.
                let ends: Vec<(usize, i64, i64)> = occupied
                    .iter()
                    .filter_map(|&(i, _)| outlines[i].as_ref()?.columns(y).map(|(a, b)| (i, a, b)))
                    .collect();
                row.fill(None);
                scan_row(&caster, tree, &ends, |x| rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)), &near, row);
                visit(&mut out, dy, row);
            }
        },
    );
}

/// One scanline: the x-entry table of the occupants, the x-occupancy list, and
/// each occupied pixel's surface from the tree cut down to the occupants.
fn scan_row(
    caster: &CsgCaster,
    tree: &CsgTree,
    ends: &[(usize, i64, i64)],
    ray_at: impl Fn(usize) -> Ray,
    near: &impl Fn(&Ray) -> f32,
    row: &mut [Option<Crossing>],
) {
    // The x-entry table: occupants by left end.
    let mut entry: Vec<(usize, i64, i64)> = ends.to_vec();
    entry.sort_by_key(|e| e.1);
    let (mut next, mut inside): (usize, Vec<(usize, i64, i64)>) = (0, Vec::new());
    let mut cut: Option<CsgTree> = None;
    let mut active = vec![false; caster.primitives()];
    let mut scratch = SpanScratch::default();
    for (x, px) in row.iter_mut().enumerate() {
        let mut changed = false;
        while next < entry.len() && entry[next].1 <= x as i64 {
            inside.push(entry[next]);
            active[entry[next].0] = true;
            next += 1;
            changed = true;
        }
        if changed {
            cut = tree.restricted(&|i| active[i]);
        }
        if let Some(tree) = &cut {
            let ray = ray_at(x);
            *px = caster.first_hit_with(tree, &ray, near(&ray), &mut scratch);
        }
        // Primitives whose right end is this pixel leave the x-occupancy list.
        let before = inside.len();
        inside.retain(|&(i, _, right)| {
            let stays = right > x as i64;
            active[i] = stays;
            stays
        });
        if inside.len() != before {
            cut = tree.restricted(&|i| active[i]);
        }
    }
}

/// Where a primitive shows on the screen: its scanlines (the y-entry table's
/// key; procedure 1) and, per scanline, its left and right ends (procedure 2).
#[derive(Debug, Clone, Copy)]
struct Outline {
    /// Rows, and the columns of its bounding box.
    rows: Extent,
    /// An ellipsoid under a perspective camera, its ends exact.
    ellipsoid: Option<EllipsoidView>,
}

/// An ellipsoid `{M·q + c : |q| ≤ 1}` seen from an eye outside it, in the unit
/// sphere's space: the eye `o`, `k = |o|² − 1 > 0`, and the camera's ray
/// vectors carried there by `M⁻¹` (a pixel's ray direction is
/// `forward + u·right + v·up`, u and v its NDC coordinates).
#[derive(Debug, Clone, Copy)]
struct EllipsoidView {
    o: Vec3,
    k: f32,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    width: f32,
    height: f32,
}

impl Outline {
    fn new(p: &Primitive, vp: Mat4, rays: &PixelRays) -> Option<Outline> {
        let (width, height) = (rays.size.x as u32, rays.size.y as u32);
        let mut rows = extent(&p.corners(), vp, width, height)?;
        let ellipsoid = (p.shape == Shape::Sphere && !rays.ortho)
            .then(|| {
                let to_unit = p.transform.inverse();
                let o = to_unit.transform_point3(rays.origin);
                let carry = |v: Vec3| to_unit.transform_vector3(v);
                let (k, size) = (o.length_squared() - 1.0, rays.size);
                (k > 1e-4).then_some(EllipsoidView {
                    o,
                    k,
                    forward: carry(rays.forward),
                    right: carry(rays.right),
                    up: carry(rays.up),
                    width: size.x,
                    height: size.y,
                })
            })
            .flatten();
        if let Some(e) = &ellipsoid {
            // Procedure 1: the scanline planes through the eye tangent to the
            // ellipsoid bound its rows.
            let (v0, v1) = e.rows()?;
            let row = |v: f64| (1.0 - v) * f64::from(e.height) * 0.5 - 0.5;
            rows.y0 = rows.y0.max((row(v1) - ROUNDING_PX).ceil() as i64);
            rows.y1 = rows.y1.min((row(v0) + ROUNDING_PX).floor() as i64);
            if rows.y0 > rows.y1 {
                return None;
            }
        }
        Some(Outline { rows, ellipsoid })
    }

    /// The columns the primitive may cover on row `y`.
    fn columns(&self, y: i64) -> Option<(i64, i64)> {
        let (x0, x1) = (self.rows.x0, self.rows.x1);
        let Some(e) = &self.ellipsoid else { return Some((x0, x1)) };
        let (u0, u1) = e.columns(1.0 - 2.0 * (y as f32 + 0.5) / e.height)?;
        let column = |u: f64| (u + 1.0) * f64::from(e.width) * 0.5 - 0.5;
        let (a, b) =
            (x0.max((column(u0) - ROUNDING_PX).ceil() as i64), x1.min((column(u1) + ROUNDING_PX).floor() as i64));
        (a <= b).then_some((a, b))
    }
}

impl EllipsoidView {
    /// Procedure 1: the `v` for which the scanline plane through the eye, spanned
    /// by `right` and `forward + v·up`, meets the unit sphere: with normal
    /// `n(v) = n0 + v·n1`, where `|n|² − (n·o)² ≥ 0`.
    fn rows(&self) -> Option<(f64, f64)> {
        let (o, right) = (self.o.as_dvec3(), self.right.as_dvec3());
        let (n0, n1) = (right.cross(self.forward.as_dvec3()), right.cross(self.up.as_dvec3()));
        let (p, q) = (n0.dot(o), n1.dot(o));
        inside_quadratic(n1.dot(n1) - q * q, n0.dot(n1) - p * q, n0.dot(n0) - p * p)
    }

    /// Procedure 2 on the scanline at NDC height `v`: the `u` for which the line
    /// through the eye along `d(u) = d0 + u·right` meets the unit sphere, where
    /// `(o·d)² − k·|d|² ≥ 0`.
    fn columns(&self, v: f32) -> Option<(f64, f64)> {
        let (o, k) = (self.o.as_dvec3(), f64::from(self.k));
        let (d0, d1) = ((self.forward + self.up * v).as_dvec3(), self.right.as_dvec3());
        let (p, q) = (o.dot(d0), o.dot(d1));
        inside_quadratic(q * q - k * d1.dot(d1), p * q - k * d0.dot(d1), p * p - k * d0.dot(d0))
    }
}

/// Where `a·s² + 2·b·s + c ≥ 0`: the interval between the roots when `a < 0`;
/// `(−∞, ∞)` (no narrowing) when the set is not one bounded interval; `None`
/// when it is empty.
fn inside_quadratic(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    if a >= 0.0 {
        return Some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let disc = b * b - a * c;
    if disc < 0.0 {
        return None;
    }
    let r = disc.sqrt();
    let (s0, s1) = ((-b + r) / a, (-b - r) / a);
    Some((s0.min(s1), s0.max(s1)))
}

/// The pixels whose centres the projection of `points` can cover; the whole
/// image if a point lies at or behind the eye; `None` if off screen.
fn extent(points: &[Vec3], vp: Mat4, width: u32, height: u32) -> Option<Extent> {
    let (w, h) = (f64::from(width), f64::from(height));
    let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
    for p in points {
        let c: Vec4 = vp * p.extend(1.0);
        if c.w <= 1e-6 {
            return Some(Extent { x0: 0, x1: i64::from(width) - 1, y0: 0, y1: i64::from(height) - 1 });
        }
        let ndc = glam::DVec2::new(f64::from(c.x / c.w), f64::from(c.y / c.w));
        let px = glam::DVec2::new((ndc.x * 0.5 + 0.5) * w, (0.5 - ndc.y * 0.5) * h);
        (lo, hi) = (lo.min(px), hi.max(px));
    }
    // Pixel x is covered when its centre x + ½ lies in [lo, hi].
    let first = |v: f64| (v - 0.5 - ROUNDING_PX).ceil() as i64;
    let last = |v: f64| (v - 0.5 + ROUNDING_PX).floor() as i64;
    let e = Extent {
        x0: first(lo.x).max(0),
        x1: last(hi.x).min(i64::from(width) - 1),
        y0: first(lo.y).max(0),
        y1: last(hi.y).min(i64::from(height) - 1),
    };
    (e.x0 <= e.x1 && e.y0 <= e.y1).then_some(e)
}
