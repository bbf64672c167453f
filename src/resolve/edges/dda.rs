//! Seed 004's DDA (Kato & Kameyama, §3 (2)): one walker along a projected edge
//! for x-major and y-major edges alike, and the exact geometry of the pixels it
//! crosses — the share of a pixel's square beyond the edge's line and that
//! part's centroid.
//!
//! The walker steps column by column along the major axis (rows, for a y-major
//! edge: the axes are swapped on the way in and out, so there is one walker,
//! not four copies), and in each column through the one or two pixels the
//! edge's line crosses. A column's share below the line is the mean over the
//! column of the clamped height of the line within the pixel row
//! (`clamped_mean`, exact: the integrand is piecewise linear); the paper's Wu
//! weights are the distances of the two straddling centres from the line.

use glam::{DVec3, Vec2};

use crate::scene::EdgeFilter;

/// The DDA of pass 2, one walker for both axes: steps column by column along the
/// major axis through the column centres the segment spans, and in each column
/// through the (one or two) pixels the edge's line crosses. For each it calls
/// `visit(c, o, alpha, point, far)`: the crossed pixel `c`, its neighbour `o`
/// across the edge, the share of `c`'s area on `o`'s side of the line (exact),
/// the edge's point at the column centre (screen x, y and depth) and the
/// centroid of `c`'s part on `o`'s side, from `c`'s centre. Pixels are (x, y);
/// pairs reaching outside the image are skipped.
pub(super) fn walk(
    a: DVec3,
    b: DVec3,
    mut visit: impl FnMut((u32, u32), (u32, u32), f32, DVec3, PartBeyond),
    size: (u32, u32),
    filter: EdgeFilter,
) {
    let swap = (b.y - a.y).abs() > (b.x - a.x).abs();
    // (major, minor, depth) of each end, ordered along the major axis.
    let axes = |p: DVec3| if swap { (p.y, p.x, p.z) } else { (p.x, p.y, p.z) };
    let (mut s, mut e) = (axes(a), axes(b));
    if s.0 > e.0 {
        std::mem::swap(&mut s, &mut e);
    }
    let length = e.0 - s.0;
    let (major_size, minor_size) = if swap { (size.1, size.0) } else { (size.0, size.1) };
    if length < 1e-9 {
        return;
    }
    let per_length = 1.0 / length;
    let at = |major: f64| {
        let t = (major - s.0) * per_length;
        (s.1 + t * (e.1 - s.1), s.2 + t * (e.2 - s.2))
    };
    let to_xy = |major: u32, minor: i64| if swap { (minor as u32, major) } else { (major, minor as u32) };
    let inside = |k: i64| k >= 0 && k < i64::from(minor_size);
    // Columns whose centre i + ½ lies in [start, end): the edges of a chain share
    // no column, and each column is taken whole, with the edge's line extended
    // across it.
    let first = (s.0 - 0.5).ceil().max(0.0) as i64;
    let last = (((e.0 - 0.5).ceil()) as i64 - 1).min(i64::from(major_size) - 1);
    for i in first..=last {
        let (x0, x1) = (i as f64, (i + 1) as f64);
        let ((y0, _), (y1, _)) = (at(x0), at(x1));
        let (yc, z) = at(i as f64 + 0.5);
        let centre = i as f64 + 0.5;
        let point = if swap { DVec3::new(yc, centre, z) } else { DVec3::new(centre, yc, z) };
        let mut emit = |r: i64, o: i64, alpha: f64| {
            if alpha > 1e-6 && inside(r) && inside(o) {
                // The part towards o (smaller minor coordinate if o = r − 1).
                let far = PartBeyond { v0: y0 - r as f64, v1: y1 - r as f64, below: o > r, swap };
                visit(to_xy(i as u32, r), to_xy(i as u32, o), alpha as f32, point, far);
            }
        };
        match filter {
            EdgeFilter::Coverage => {
                for r in y0.min(y1).floor() as i64..=y0.max(y1).floor() as i64 {
                    // Share of pixel row r below the edge, over [x0, x1].
                    let below = (x1 - x0) * clamped_mean(r as f64 + 1.0 - y0, y0 - y1);
                    let above = (x1 - x0) - below;
                    if r as f64 + 0.5 > yc {
                        emit(r, r - 1, above);
                    } else {
                        emit(r, r + 1, below);
                    }
                }
            }
            EdgeFilter::Paper => {
                // P above and Q below the edge point, D_P its distance from P's centre:
                // I_P = Filter(D_Q) = 1 − D_P, I_Q = Filter(D_P) = D_P (linear light,
                // so the filter is already gamma-correct).
                let m = yc - 0.5;
                let p = m.floor() as i64;
                let d_p = m - m.floor();
                emit(p, p + 1, 1.0 - d_p);
                emit(p + 1, p, d_p);
            }
        }
    }
}

/// The part of a crossed pixel beyond an edge, as the walker meets it: its
/// centroid is worked out only for the blends the depth test keeps.
#[derive(Debug, Clone, Copy)]
pub(super) struct PartBeyond {
    /// The edge's line across the pixel's column (rows for a y-major edge),
    /// from the pixel's minor-axis origin, at its two sides.
    v0: f64,
    v1: f64,
    /// Whether the part lies towards greater minor coordinates.
    below: bool,
    /// Whether the edge is y-major (the axes swapped).
    swap: bool,
}

impl PartBeyond {
    /// The part's centroid from the pixel's centre (pixels, x right, y down).
    pub(super) fn centroid(self) -> Vec2 {
        let (u, v) = part_centroid(self.v0, self.v1, self.below);
        if self.swap {
            Vec2::new(v as f32, u as f32)
        } else {
            Vec2::new(u as f32, v as f32)
        }
    }
}

/// The centroid, from the square's centre, of the part of the unit square
/// (u, v) ∈ [0, 1]² beyond the line from (0, `v0`) to (1, `v1`): where v is
/// greater than the line's if `beyond_below`, else where it is smaller (the
/// square's centre if that part is empty).
fn part_centroid(v0: f64, v1: f64, beyond_below: bool) -> (f64, f64) {
    let k = v1 - v0;
    if (0.0..=1.0).contains(&v0) && (0.0..=1.0).contains(&v1) {
        // The line crosses the square from side to side: the part above it
        // is the trapezoid 0 ≤ v ≤ v0 + k·u, whose moments are polynomials
        // (the part below is the square less it).
        let area = v0 + 0.5 * k;
        let (mu, mv) = (0.5 * v0 + k / 3.0, 0.5 * (v0 * v0 + v0 * k + k * k / 3.0));
        let (area, mu, mv) = if beyond_below { (1.0 - area, 0.5 - mu, 0.5 - mv) } else { (area, mu, mv) };
        if area < 1e-12 {
            return (0.0, 0.0);
        }
        return (mu / area - 0.5, mv / area - 0.5);
    }
    let sign = if beyond_below { 1.0 } else { -1.0 };
    square_part(|(u, v)| sign * (v - (v0 + k * u))).1
}

/// The part of the unit square (u, v) ∈ [0, 1]² where the affine function
/// `side` is ≥ 0: its area and its centroid from the square's centre (the
/// centre if the part is empty).
pub(super) fn square_part(side: impl Fn((f64, f64)) -> f64) -> (f64, (f64, f64)) {
    // The square clipped to side ≥ 0 (Sutherland–Hodgman, one plane).
    let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    let sides = square.map(&side);
    // A line cuts a square's boundary at most twice: at most five corners.
    let (mut corners, mut n) = ([(0.0, 0.0); 5], 0);
    for (k, &p) in square.iter().enumerate() {
        let q = square[(k + 1) % 4];
        let (sp, sq) = (sides[k], sides[(k + 1) % 4]);
        if sp >= 0.0 {
            corners[n] = p;
            n += 1;
        }
        if (sp >= 0.0) != (sq >= 0.0) {
            let t = sp / (sp - sq);
            corners[n] = (p.0 + (q.0 - p.0) * t, p.1 + (q.1 - p.1) * t);
            n += 1;
        }
    }
    let part = &corners[..n];
    // Area and centroid of the polygon (shoelace).
    let (mut area, mut cu, mut cv) = (0.0, 0.0, 0.0);
    for (k, &(pu, pv)) in part.iter().enumerate() {
        let (qu, qv) = part[(k + 1) % n];
        let cross = pu * qv - qu * pv;
        area += cross;
        cu += (pu + qu) * cross;
        cv += (pv + qv) * cross;
    }
    if area.abs() < 1e-12 {
        return (0.0, (0.0, 0.0));
    }
    (area * 0.5, (cu / (3.0 * area) - 0.5, cv / (3.0 * area) - 0.5))
}

/// ∫₀¹ clamp(a + k·t, 0, 1) dt, exactly: the integrand is linear between the
/// points where it meets 0 and 1.
fn clamped_mean(a: f64, k: f64) -> f64 {
    if (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&(a + k)) {
        return a + 0.5 * k; // no clamping: most columns cross one row
    }
    if k.abs() <= 1e-12 {
        return a.clamp(0.0, 1.0);
    }
    // Where a + k·t meets 0 and 1, within [0, 1] and in order.
    let (t0, t1) = ((-a / k).clamp(0.0, 1.0), ((1.0 - a) / k).clamp(0.0, 1.0));
    let cuts = [0.0, t0.min(t1), t0.max(t1), 1.0];
    cuts.windows(2).map(|w| (w[1] - w[0]) * (a + k * (w[0] + w[1]) * 0.5).clamp(0.0, 1.0)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_walker_gives_each_crossed_pixel_its_exact_share_across_the_edge() {
        // y = 0.7·x + 2.2 from x = 0.4 to 10.3: x-major, crossing two rows in most
        // columns.
        let (a, b) = (DVec3::new(0.4, 2.48, 0.5), DVec3::new(10.3, 9.41, 0.5));
        let line = |x: f64| 0.7 * x + 2.2;
        let mut seen = Vec::new();
        walk(
            a,
            b,
            |c, o, alpha, _, far: PartBeyond| seen.push((c, o, alpha, far.centroid())),
            (20, 20),
            EdgeFilter::Coverage,
        );
        let swapped = {
            let mut v = Vec::new();
            let t = |p: DVec3| DVec3::new(p.y, p.x, p.z);
            let mut visit = |c: (u32, u32), o: (u32, u32), alpha, _, far: PartBeyond| {
                let far = far.centroid();
                v.push(((c.1, c.0), (o.1, o.0), alpha, Vec2::new(far.y, far.x)));
            };
            walk(t(b), t(a), &mut visit, (20, 20), EdgeFilter::Coverage);
            v
        };
        assert_eq!(seen, swapped, "y-major is x-major with the axes swapped");
        assert!(seen.len() > 12, "{} blends", seen.len());
        for ((cx, cy), (ox, oy), alpha, far) in seen {
            assert_eq!(cx, ox);
            assert_eq!(oy.abs_diff(cy), 1);
            // Numerically: the share of pixel (cx, cy) on the other side of the
            // line from its centre, and that part's centroid.
            let centre_below = f64::from(cy) + 0.5 > line(f64::from(cx) + 0.5);
            let n = 1000;
            let part: Vec<(f64, f64)> = (0..n * n)
                .map(|k| (((k % n) as f64 + 0.5) / n as f64, ((k / n) as f64 + 0.5) / n as f64))
                .filter(|&(x, y)| (f64::from(cy) + y > line(f64::from(cx) + x)) != centre_below)
                .collect();
            let share = part.len() as f64 / (n * n) as f64;
            assert!((f64::from(alpha) - share).abs() < 2e-3, "pixel ({cx}, {cy}): alpha {alpha} vs {share}");
            let mean = |f: fn(&(f64, f64)) -> f64| part.iter().map(f).sum::<f64>() / part.len() as f64 - 0.5;
            let centroid = Vec2::new(mean(|p| p.0) as f32, mean(|p| p.1) as f32);
            assert!(far.distance(centroid) < 2e-3, "pixel ({cx}, {cy}): part's centroid {far} vs {centroid}");
            assert_eq!(oy > cy, !centre_below, "o lies across the edge");
        }
    }

    #[test]
    fn clamped_mean_integrates_exactly() {
        for (a, k) in [(0.3, 0.0), (-0.2, 1.5), (1.4, -2.0), (0.5, 0.25), (2.0, 1.0), (-1.0, -0.5)] {
            let n = 100_000;
            let numeric: f64 =
                (0..n).map(|i| (a + k * (i as f64 + 0.5) / n as f64).clamp(0.0, 1.0)).sum::<f64>() / n as f64;
            assert!((clamped_mean(a, k) - numeric).abs() < 1e-6, "a {a} k {k}");
        }
    }
}
