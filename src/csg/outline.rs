//! Where a primitive shows on the screen (seed 003 §6's procedures 1 and 2):
//! the scanlines its projection takes in, and its left and right ends on
//! each. An ellipsoid under a perspective camera gets them exactly, from the
//! planes and lines through the eye tangent to it; every other primitive from
//! the convex hull of the projected corners of a convex solid around it (a
//! polyhedron's own corners: exact). Ends are widened by a thousandth of a
//! pixel, so rounding never drops a pixel whose ray grazes the primitive.

use glam::{DVec2, Mat4, Vec2, Vec3, Vec4};

use crate::camera::PixelRays;
use crate::csg::{BoxBound, Primitive, Shape};

/// How far (in pixels) an exact extent is widened, so that rounding never drops
/// a pixel whose ray grazes the primitive.
const ROUNDING_PX: f64 = 1e-3;

/// Pixels a primitive may cover: rows `y0..=y1`, columns `x0..=x1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Extent {
    pub(crate) x0: i64,
    pub(crate) x1: i64,
    pub(crate) y0: i64,
    pub(crate) y1: i64,
}

impl BoxBound for Extent {
    fn meet(self, o: Extent) -> Option<Extent> {
        let e = Extent { x0: self.x0.max(o.x0), x1: self.x1.min(o.x1), y0: self.y0.max(o.y0), y1: self.y1.min(o.y1) };
        (e.x0 <= e.x1 && e.y0 <= e.y1).then_some(e)
    }

    fn join(self, o: Extent) -> Extent {
        Extent { x0: self.x0.min(o.x0), x1: self.x1.max(o.x1), y0: self.y0.min(o.y0), y1: self.y1.max(o.y1) }
    }
}

/// The columns a primitive covers, per row from the first one given.
type ColumnTable = (i64, Vec<Option<(i64, i64)>>);

/// Where a primitive shows on the screen: its scanlines (the y-entry table's
/// key; procedure 1) and, per scanline, its left and right ends (procedure 2).
#[derive(Debug, Clone)]
pub(crate) struct Outline {
    /// Rows, and the columns of its bounding box.
    pub(crate) rows: Extent,
    /// An ellipsoid under a perspective camera, its ends exact.
    ellipsoid: Option<EllipsoidView>,
    /// The convex hull (pixel coordinates, in order round it) of the projected
    /// corners of a convex solid around the primitive, when all lie in front of
    /// the eye: a polyhedron's own (exact), a frustum's circumscribed prism's.
    hull: Vec<DVec2>,
    /// The least distance along the view axis of those corners: no ray meets
    /// the primitive nearer (a row line's `t` counts that distance).
    pub(crate) nearest: f32,
    /// The columns found where it shows, per row from the first one given
    /// (a closed mesh's layer, rasterized), in place of the hull's.
    table: Option<ColumnTable>,
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
    /// The outline of `p` seen through `vp` with pixel rays `rays`, or
    /// `None` where it shows nowhere.
    pub(crate) fn new(p: &Primitive, vp: Mat4, rays: &PixelRays) -> Option<Outline> {
        let (width, height) = (rays.size.x as u32, rays.size.y as u32);
        let points = outline_points(p);
        let depth = |q: &Vec3| (*q - rays.origin).dot(rays.forward) / rays.forward.length_squared();
        let nearest = points.iter().map(depth).fold(f32::INFINITY, f32::min);
        let clip: Vec<Vec4> = points.into_iter().map(|q| vp * q.extend(1.0)).collect();
        let mut rows = extent(&clip, width, height)?;
        let hull = projected_hull(&clip, rays.size.as_dvec2()).unwrap_or_default();
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
        Some(Outline { rows, ellipsoid, hull, nearest, table: None })
    }

    /// The outline where it shows on `rows`, row by row (`table`, from
    /// `rows.y0`): a closed mesh's layer, as its rasterized pixels say.
    #[must_use]
    pub(crate) fn with_rows(self, rows: Extent, table: Vec<Option<(i64, i64)>>) -> Outline {
        Outline { rows, ellipsoid: None, hull: Vec::new(), table: Some((rows.y0, table)), ..self }
    }

    /// The columns the primitive may cover on row `y`.
    pub(crate) fn columns(&self, y: i64) -> Option<(i64, i64)> {
        let (x0, x1) = (self.rows.x0, self.rows.x1);
        if let Some((first, table)) = &self.table {
            let (a, b) = (*table.get(usize::try_from(y - first).ok()?)?)?;
            let (a, b) = (a.max(x0), b.min(x1));
            return (a <= b).then_some((a, b));
        }
        let Some(e) = &self.ellipsoid else {
            if self.hull.is_empty() {
                return Some((x0, x1));
            }
            let (lo, hi) = hull_row(&self.hull, y as f64 + 0.5)?;
            let (a, b) =
                (x0.max((lo - 0.5 - ROUNDING_PX).ceil() as i64), x1.min((hi - 0.5 + ROUNDING_PX).floor() as i64));
            return (a <= b).then_some((a, b));
        };
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

/// The pixel coordinates (pixel `(x, y)` has its centre at `x + ½, y + ½`)
/// of world point `p` seen through `vp` in a `width` x `height` image, or
/// `None` at or behind the eye.
pub(crate) fn screen_point(p: Vec3, vp: Mat4, (width, height): (u32, u32)) -> Option<Vec2> {
    pixel_of(vp * p.extend(1.0), DVec2::new(f64::from(width), f64::from(height))).map(DVec2::as_vec2)
}

/// The pixel coordinates in a `size` image of a point whose clip-space
/// position is `c`, or `None` at or behind the eye.
fn pixel_of(c: Vec4, size: DVec2) -> Option<DVec2> {
    (c.w > 1e-6).then(|| {
        let ndc = DVec2::new(f64::from(c.x / c.w), f64::from(c.y / c.w));
        DVec2::new((ndc.x * 0.5 + 0.5) * size.x, (0.5 - ndc.y * 0.5) * size.y)
    })
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

/// Sides of the polygon circumscribing a frustum's circles in its outline.
const FRUSTUM_SIDES: usize = 16;

/// Points (solid space) whose convex hull contains the primitive: a
/// polyhedron's corners; a frustum's circumscribed prism (its 16-gons' corners
/// lie 1/cos(π/16) ≈ 1.02 times the radius out); a sphere's box.
fn outline_points(p: &Primitive) -> Vec<Vec3> {
    match &p.shape {
        Shape::Frustum { bottom, top } => {
            let out = 1.0 / (std::f32::consts::PI / FRUSTUM_SIDES as f32).cos();
            let ring = |r: f32, z: f32| {
                (0..FRUSTUM_SIDES).map(move |k| {
                    let a = std::f32::consts::TAU * k as f32 / FRUSTUM_SIDES as f32;
                    Vec3::new(r * out * a.cos(), r * out * a.sin(), z)
                })
            };
            ring(*bottom, 0.0).chain(ring(*top, 1.0)).map(|c| p.transform.transform_point3(c)).collect()
        }
        _ => p.corners(),
    }
}

/// The convex hull of points projected to pixel coordinates of a `size`
/// image, given their clip-space positions `clip` (Andrew's monotone chain),
/// or `None` when a point lies at or behind the eye.
fn projected_hull(clip: &[Vec4], size: DVec2) -> Option<Vec<DVec2>> {
    let mut px: Vec<DVec2> = clip.iter().map(|&c| pixel_of(c, size)).collect::<Option<_>>()?;
    px.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    px.dedup();
    if px.len() < 3 {
        return Some(px);
    }
    let turn = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(px.len() * 2);
    // The lower chain left to right, then the upper chain back.
    for pass in 0..2 {
        let start = hull.len();
        for k in 0..px.len() {
            let p = px[if pass == 0 { k } else { px.len() - 1 - k }];
            while hull.len() >= start + 2 && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop(); // the last point starts the other chain
    }
    Some(hull)
}

/// Where the horizontal line at height `y` crosses the convex polygon `hull`:
/// the smallest and largest x, or `None` if it misses.
fn hull_row(hull: &[DVec2], y: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    // Each side: a corner and the next, the last closing on the first.
    let next = hull.iter().skip(1).chain(hull.first());
    for (&a, &b) in hull.iter().zip(next) {
        if (a.y - y) * (b.y - y) > 0.0 {
            continue; // both ends on one side
        }
        let x = if a.y == b.y { [a.x, b.x] } else { [a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y); 2] };
        lo = lo.min(x[0].min(x[1]));
        hi = hi.max(x[0].max(x[1]));
    }
    (lo <= hi).then_some((lo, hi))
}

/// The pixels whose centres the projection of points (their clip-space
/// positions `clip`) can cover; the whole image if some point lies at or
/// behind the eye; `None` if off screen or all behind the eye (the points'
/// hull then lies in the half-space behind it).
fn extent(clip: &[Vec4], width: u32, height: u32) -> Option<Extent> {
    let size = DVec2::new(f64::from(width), f64::from(height));
    if clip.iter().all(|c| c.w <= 0.0) {
        return None; // wholly behind the eye (a cube-map face looking away)
    }
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for &c in clip {
        let Some(px) = pixel_of(c, size) else {
            return Some(Extent { x0: 0, x1: i64::from(width) - 1, y0: 0, y1: i64::from(height) - 1 });
        };
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
