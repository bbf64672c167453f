//! Scan conversion of one triangle, seed 004 §3(1): the left and right edges are
//! walked by a DDA with a y step of one scanline, and the pixels between them are
//! emitted as a span.
//!
//! The DDA is exact. Vertices sit on a fixed-point grid of 1/[`ONE`] pixel; for the
//! scanline whose centre is `y = j + ½`, an edge from `a` to `b` (`a.y < b.y`) crosses
//! it at the rational `x(j) = a.x + (y − a.y)·(b.x − a.x)/(b.y − a.y)`. The walker
//! keeps `ceil((x(j) − ½) / 1px)`, the first pixel whose centre is at or right of the
//! edge, as an integer quotient and remainder, so no rounding ever happens.
//!
//! Fill rule (top-left): a pixel belongs to a triangle when its centre is inside, or
//! on a left edge, or on a top edge; centres on right or bottom edges belong to the
//! neighbour. Both triangles sharing an edge walk it in the same direction (towards
//! +y) with the same integers, so one gets the pixels left of it and the other the
//! rest: shared edges are neither cracked nor drawn twice.

use std::ops::Range;

/// Fractional bits of screen coordinates.
pub const SUBPIXEL_BITS: u32 = 12;
/// One pixel in fixed-point units.
pub const ONE: i64 = 1 << SUBPIXEL_BITS;
const HALF: i64 = ONE / 2;

/// A screen position in fixed point: pixels × [`ONE`], y down, row 0 at the top.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FixedPoint {
    /// Column coordinate × `ONE`.
    pub x: i64,
    /// Row coordinate × `ONE`.
    pub y: i64,
}

/// Receives the spans a scan converter produces.
pub trait SpanSink {
    /// Pixels `x0 .. x1` of row `y` are covered (`x0 < x1`; may extend past the image).
    fn span(&mut self, y: i64, x0: i64, x1: i64);
}

impl<F: FnMut(i64, i64, i64)> SpanSink for F {
    fn span(&mut self, y: i64, x0: i64, x1: i64) {
        self(y, x0, x1)
    }
}

/// `ceil(n / d)` for `d > 0`.
fn ceil_div(n: i64, d: i64) -> i64 {
    -(-n).div_euclid(d)
}

/// Index of the first pixel (or row) whose centre lies at or after fixed-point `v`.
#[must_use]
pub fn first_centre_from(v: i64) -> i64 {
    ceil_div(v - HALF, ONE)
}

/// Exact integer DDA along one edge, one scanline per step.
#[derive(Debug, Clone, Copy)]
struct EdgeDda {
    /// First pixel at or right of the edge on the current row.
    x: i64,
    /// `x·d − numerator`, in `0..d`.
    rem: i64,
    step_x: i64,
    step_rem: i64,
    d: i64,
}

impl EdgeDda {
    /// The walker for edge `a → b` (`a.y < b.y`), positioned on row `row`.
    fn new(a: FixedPoint, b: FixedPoint, row: i64) -> EdgeDda {
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let d = ONE * dy;
        let n = (a.x - HALF) * dy + (row * ONE + HALF - a.y) * dx;
        let x = ceil_div(n, d);
        let s = ONE * dx;
        EdgeDda { x, rem: x * d - n, step_x: s.div_euclid(d), step_rem: s.rem_euclid(d), d }
    }

    /// Moves to the next row.
    fn step(&mut self) {
        self.x += self.step_x;
        self.rem -= self.step_rem;
        if self.rem < 0 {
            self.x += 1;
            self.rem += self.d;
        }
    }
}

/// Twice the signed area of triangle `v` in fixed-point units²: negative when the
/// vertices run counter-clockwise as seen on screen (the front faces of a
/// counter-clockwise mesh), positive when clockwise, zero when degenerate.
#[must_use]
pub fn signed_area2(v: &[FixedPoint; 3]) -> i64 {
    (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[2].x - v[0].x) * (v[1].y - v[0].y)
}

/// Rows of pixel centres the triangle covers, before clipping to the image.
#[must_use]
pub fn row_range(v: &[FixedPoint; 3]) -> Range<i64> {
    let lo = v.iter().map(|p| p.y).min().unwrap_or(0);
    let hi = v.iter().map(|p| p.y).max().unwrap_or(0);
    first_centre_from(lo)..first_centre_from(hi)
}

/// Columns of pixel centres the triangle's bounding box covers.
#[must_use]
pub fn column_range(v: &[FixedPoint; 3]) -> Range<i64> {
    let lo = v.iter().map(|p| p.x).min().unwrap_or(0);
    let hi = v.iter().map(|p| p.x).max().unwrap_or(0);
    first_centre_from(lo)..first_centre_from(hi)
}

/// Emits the spans of triangle `v` on the rows in `rows` (any vertex order).
pub fn scan_triangle(v: &[FixedPoint; 3], rows: Range<i64>, sink: &mut impl SpanSink) {
    let mut s = *v;
    s.sort_unstable_by_key(|p| (p.y, p.x));
    let [a, b, c] = s;
    // Sign of (c − a) × (b − a): negative when b lies right of the long edge a → c.
    let cross = (c.x - a.x) * (b.y - a.y) - (b.x - a.x) * (c.y - a.y);
    if cross == 0 {
        return;
    }
    let (top, mid, bottom) = (first_centre_from(a.y), first_centre_from(b.y), first_centre_from(c.y));
    let (start, end) = (top.max(rows.start), bottom.min(rows.end));
    if start >= end {
        return;
    }
    let mut long = EdgeDda::new(a, c, start);
    let short_is_left = cross > 0;
    let mut walk = |short_from: FixedPoint, short_to: FixedPoint, r0: i64, r1: i64, long: &mut EdgeDda| {
        if r0 >= r1 {
            return;
        }
        let mut short = EdgeDda::new(short_from, short_to, r0);
        for row in r0..r1 {
            let (l, r) = if short_is_left { (short.x, long.x) } else { (long.x, short.x) };
            if l < r {
                sink.span(row, l, r);
            }
            short.step();
            long.step();
        }
    };
    walk(a, b, start, mid.min(end), &mut long);
    walk(b, c, mid.max(start), end, &mut long);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fp(x: f64, y: f64) -> FixedPoint {
        FixedPoint { x: (x * ONE as f64).round() as i64, y: (y * ONE as f64).round() as i64 }
    }

    fn covered(v: &[FixedPoint; 3]) -> Vec<(i64, i64)> {
        let mut out = Vec::new();
        scan_triangle(v, -100..100, &mut |y, x0, x1| out.extend((x0..x1).map(|x| (x, y))));
        out.sort_unstable();
        out
    }

    #[test]
    fn matches_edge_function_oracle_on_small_triangles() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 33) % 2000) as f64 / 100.0 - 10.0
        };
        for _ in 0..300 {
            let v = [fp(rnd(), rnd()), fp(rnd(), rnd()), fp(rnd(), rnd())];
            if signed_area2(&v) == 0 {
                continue;
            }
            let got = covered(&v);
            let mut want = Vec::new();
            for y in -12..12 {
                for x in -12..12 {
                    if inside_tl(&v, x, y) {
                        want.push((x, y));
                    }
                }
            }
            want.sort_unstable();
            assert_eq!(got, want, "{v:?}");
        }
    }

    /// Independent oracle: the edge-function test with the top-left tie rule, in
    /// exact integer arithmetic, for a triangle in either winding.
    fn inside_tl(v: &[FixedPoint; 3], x: i64, y: i64) -> bool {
        let p = FixedPoint { x: x * ONE + HALF, y: y * ONE + HALF };
        // Orient clockwise as seen on screen (positive area): the interior has e > 0,
        // left edges run upwards and top edges run towards +x.
        let v = if signed_area2(v) < 0 { [v[0], v[2], v[1]] } else { *v };
        (0..3).all(|i| {
            let (a, b) = (v[i], v[(i + 1) % 3]);
            let e = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
            let left = b.y < a.y;
            let top = b.y == a.y && b.x > a.x;
            e > 0 || (e == 0 && (left || top))
        })
    }

    #[test]
    fn pixel_centre_ties() {
        // Square split along its diagonal: each pixel exactly once.
        let (p0, p1, p2, p3) = (fp(0.5, 0.5), fp(4.5, 0.5), fp(4.5, 4.5), fp(0.5, 4.5));
        let mut all = covered(&[p0, p1, p2]);
        all.extend(covered(&[p0, p2, p3]));
        all.sort_unstable();
        let want: Vec<_> = (0..4).flat_map(|y| (0..4).map(move |x| (x, y))).collect::<Vec<_>>();
        let mut want = want;
        want.sort_unstable();
        assert_eq!(all, want);
    }
}
