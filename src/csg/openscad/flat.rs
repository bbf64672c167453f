//! OpenSCAD's 2-D shapes: regions of the plane as Clipper keeps them (outer
//! contours counter-clockwise, holes clockwise, none crossing another), and
//! what OpenSCAD does to them — booleans, offsets, hulls, Minkowski sums,
//! transforms — through Clipper2, the library OpenSCAD's own 2-D geometry uses.
//!
//! Coordinates go through Clipper's integers at [`PRECISION`] decimal places
//! (a micrometre on a millimetre model), as OpenSCAD rounds to its own grid.

use clipper2_rust::{
    difference_d, inflate_paths_d, intersect_d, minkowski_sum_d, union_d, union_subjects_d, EndType, FillRule,
    JoinType, PathD, PathsD, Point,
};
use glam::{DAffine2, DVec2};

/// Decimal places Clipper keeps.
pub(crate) const PRECISION: i32 = 6;

/// How an offset turns a corner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Join {
    /// `offset(r = ...)`: arcs of radius |r|, of the given number of
    /// segments to a full turn.
    Round(usize),
    /// `offset(delta = ..., chamfer = false)`: sharp corners.
    Miter,
    /// `offset(delta = ..., chamfer = true)`: corners cut off.
    Chamfer,
}

/// A region of the plane: contours, outer ones counter-clockwise, holes
/// clockwise, none crossing another.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Region {
    contours: Vec<Vec<DVec2>>,
}

fn to_path(c: &[DVec2]) -> PathD {
    c.iter().map(|p| Point::new(p.x, p.y)).collect()
}

fn to_paths(cs: &[Vec<DVec2>]) -> PathsD {
    cs.iter().map(|c| to_path(c)).collect()
}

fn from_paths(paths: PathsD) -> Region {
    let contours = paths
        .into_iter()
        .map(|p| p.into_iter().map(|q| DVec2::new(q.x, q.y)).collect::<Vec<_>>())
        .filter(|c| c.len() >= 3)
        .collect();
    Region { contours }
}

/// The signed area of a closed contour (positive counter-clockwise).
#[must_use]
pub(crate) fn signed_area(c: &[DVec2]) -> f64 {
    (0..c.len()).map(|i| c[i].perp_dot(c[(i + 1) % c.len()])).sum::<f64>() * 0.5
}

impl Region {
    /// The region inside `contours` by the even-odd rule (`polygon()`'s
    /// paths: a path inside another is a hole, whichever way it runs).
    #[must_use]
    pub(crate) fn even_odd(contours: &[Vec<DVec2>]) -> Region {
        from_paths(union_subjects_d(&to_paths(contours), FillRule::EvenOdd, PRECISION))
    }

    /// The region inside `contours` by the non-zero rule (glyph outlines).
    #[must_use]
    pub(crate) fn non_zero(contours: &[Vec<DVec2>]) -> Region {
        from_paths(union_subjects_d(&to_paths(contours), FillRule::NonZero, PRECISION))
    }

    /// `square(size, center)`.
    #[must_use]
    pub(crate) fn square(size: DVec2, center: bool) -> Region {
        let o = if center { -size * 0.5 } else { DVec2::ZERO };
        let c = vec![o, o + DVec2::new(size.x, 0.0), o + size, o + DVec2::new(0.0, size.y)];
        Region { contours: vec![c] }
    }

    /// `circle(r)` with `n` segments: corner `i` at `360·i/n` degrees.
    #[must_use]
    pub(crate) fn circle(r: f64, n: usize) -> Region {
        Region { contours: vec![ring(r, n)] }
    }

    /// The contours.
    #[must_use]
    pub(crate) fn contours(&self) -> &[Vec<DVec2>] {
        &self.contours
    }

    /// Whether nothing is inside.
    #[must_use]
    pub(crate) fn is_empty(&self) -> bool {
        self.contours.is_empty()
    }

    /// Every corner.
    pub(crate) fn points(&self) -> impl Iterator<Item = DVec2> + '_ {
        self.contours.iter().flatten().copied()
    }

    /// The bounds `(min, max)`, `None` if empty.
    #[must_use]
    pub(crate) fn bounds(&self) -> Option<(DVec2, DVec2)> {
        let mut points = self.points().peekable();
        points.peek()?;
        Some(points.fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }

    /// The area inside.
    #[cfg(test)]
    #[must_use]
    pub(crate) fn area(&self) -> f64 {
        self.contours.iter().map(|c| signed_area(c)).sum()
    }

    /// The union of `regions`.
    #[must_use]
    pub(crate) fn union(regions: &[Region]) -> Region {
        let all: Vec<Vec<DVec2>> = regions.iter().flat_map(|r| r.contours.iter().cloned()).collect();
        from_paths(union_d(&to_paths(&all), &PathsD::new(), FillRule::NonZero, PRECISION))
    }

    /// What lies in every one of `regions` (none: nothing).
    #[must_use]
    pub(crate) fn intersection(regions: &[Region]) -> Region {
        let Some((first, rest)) = regions.split_first() else { return Region::default() };
        rest.iter().fold(first.clone(), |acc, r| {
            from_paths(intersect_d(&to_paths(&acc.contours), &to_paths(&r.contours), FillRule::NonZero, PRECISION))
        })
    }

    /// This region less every one of `cutters`.
    #[must_use]
    pub(crate) fn difference(&self, cutters: &[Region]) -> Region {
        let cuts: Vec<Vec<DVec2>> = cutters.iter().flat_map(|r| r.contours.iter().cloned()).collect();
        if cuts.is_empty() {
            return self.clone();
        }
        from_paths(difference_d(&to_paths(&self.contours), &to_paths(&cuts), FillRule::NonZero, PRECISION))
    }

    /// The region without its holes (`fill()`): its outer contours alone.
    #[must_use]
    pub(crate) fn filled(&self) -> Region {
        let outer: Vec<Vec<DVec2>> = self.contours.iter().filter(|c| signed_area(c) > 0.0).cloned().collect();
        Region::non_zero(&outer)
    }

    /// The region moved by `m` (a mirror turns its contours back the right
    /// way round).
    #[must_use]
    pub(crate) fn transformed(&self, m: &DAffine2) -> Region {
        let flip = m.matrix2.determinant() < 0.0;
        let contours = self
            .contours
            .iter()
            .map(|c| {
                let mut c: Vec<DVec2> = c.iter().map(|p| m.transform_point2(*p)).collect();
                if flip {
                    c.reverse();
                }
                c
            })
            .collect();
        Region { contours }
    }

    /// The region grown by `delta` (shrunk where negative), corners turned
    /// as `join` says; `offset()`.
    #[must_use]
    pub(crate) fn offset(&self, delta: f64, join: Join) -> Region {
        let (jt, tolerance) = match join {
            // Clipper's arc tolerance is the most a chord strays from its
            // arc: a whole turn of `n` chords strays |δ|·(1 − cos(π/n)).
            Join::Round(n) => (JoinType::Round, delta.abs() * (1.0 - (std::f64::consts::PI / n.max(3) as f64).cos())),
            Join::Miter => (JoinType::Miter, 0.0),
            Join::Chamfer => (JoinType::Square, 0.0),
        };
        // OpenSCAD asks for sharp corners at any angle (a miter limit of a million).
        let paths = inflate_paths_d(&to_paths(&self.contours), delta, jt, EndType::Polygon, 1e6, PRECISION, tolerance);
        from_paths(union_subjects_d(&paths, FillRule::NonZero, PRECISION))
    }

    /// Open polylines drawn `width` wide: square ends, corners mitred up to
    /// twice the half-width (Clipper's default), as OpenSCAD strokes an SVG
    /// path that is not closed.
    #[must_use]
    pub(crate) fn stroked(lines: &[Vec<DVec2>], width: f64) -> Region {
        let paths =
            inflate_paths_d(&to_paths(lines), width * 0.5, JoinType::Miter, EndType::Square, 2.0, PRECISION, 0.0);
        from_paths(union_subjects_d(&paths, FillRule::NonZero, PRECISION))
    }

    /// The Minkowski sum of `regions` in turn (each contour with each,
    /// unioned; a hole of either is filled as OpenSCAD's own 2-D sum does).
    #[must_use]
    pub(crate) fn minkowski(regions: &[Region]) -> Region {
        let Some((first, rest)) = regions.split_first() else { return Region::default() };
        rest.iter().fold(first.clone(), |acc, r| {
            let mut parts = PathsD::new();
            for a in &acc.contours {
                for b in &r.contours {
                    parts.extend(minkowski_sum_d(&to_path(a), &to_path(b), true, PRECISION));
                    // The sum of two outlines is a band round the swept
                    // shape; its inside is the sum of their insides.
                    parts.push(to_path(&a.iter().map(|p| *p + b[0]).collect::<Vec<_>>()));
                }
            }
            from_paths(union_subjects_d(&parts, FillRule::NonZero, PRECISION))
        })
    }

    /// The convex hull of `points` (counter-clockwise, collinear corners
    /// dropped); empty when they span no area.
    #[must_use]
    pub(crate) fn hull(points: impl IntoIterator<Item = DVec2>) -> Region {
        let mut p: Vec<DVec2> = points.into_iter().filter(|p| p.is_finite()).collect();
        p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        p.dedup();
        if p.len() < 3 {
            return Region::default();
        }
        // Andrew's monotone chain.
        let turn = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
        let mut hull: Vec<DVec2> = Vec::with_capacity(2 * p.len());
        for pass in [&p[..], &p.iter().rev().copied().collect::<Vec<_>>()[..]] {
            let start = hull.len();
            for &q in pass {
                while hull.len() >= start + 2 && turn(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0 {
                    hull.pop();
                }
                hull.push(q);
            }
            hull.pop();
        }
        if hull.len() < 3 || signed_area(&hull) <= 0.0 {
            return Region::default();
        }
        Region { contours: vec![hull] }
    }
}

/// `n` corners on the circle of radius `r` about the origin, the first on +x,
/// counter-clockwise.
#[must_use]
pub(crate) fn ring(r: f64, n: usize) -> Vec<DVec2> {
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            DVec2::new(r * a.cos(), r * a.sin())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn near(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-4 * b.abs().max(1.0)
    }

    #[test]
    fn booleans_measure_as_their_areas_say() {
        let a = Region::square(DVec2::new(4.0, 4.0), false);
        let b = Region::square(DVec2::new(4.0, 4.0), true);
        assert!(near(Region::union(&[a.clone(), b.clone()]).area(), 16.0 + 16.0 - 4.0));
        assert!(near(Region::intersection(&[a.clone(), b.clone()]).area(), 4.0));
        assert!(near(a.difference(std::slice::from_ref(&b)).area(), 12.0));
        // A hole: a square with a square cut from its middle has two contours.
        let ring = Region::square(DVec2::splat(10.0), true).difference(&[b]);
        assert_eq!(ring.contours().len(), 2);
        assert!(near(ring.area(), 100.0 - 16.0));
        // fill() closes the hole.
        assert!(near(ring.filled().area(), 100.0));
    }

    #[test]
    fn even_odd_paths_make_holes_whichever_way_they_run() {
        let outer = vec![DVec2::ZERO, DVec2::new(10.0, 0.0), DVec2::new(10.0, 10.0), DVec2::new(0.0, 10.0)];
        let inner: Vec<DVec2> = vec![DVec2::splat(2.0), DVec2::new(8.0, 2.0), DVec2::splat(8.0), DVec2::new(2.0, 8.0)];
        assert!(near(Region::even_odd(&[outer.clone(), inner.clone()]).area(), 64.0));
        let mut reversed = inner;
        reversed.reverse();
        assert!(near(Region::even_odd(&[outer, reversed]).area(), 64.0));
    }

    #[test]
    fn offsets_grow_round_sharp_or_chamfered() {
        let sq = Region::square(DVec2::splat(10.0), false);
        // Round: the square plus four sides and four quarter discs (of a
        // 64-gon, just inside the circle).
        let round = sq.offset(1.0, Join::Round(64)).area();
        let exact = 100.0 + 40.0 + std::f64::consts::PI;
        assert!(round < exact && round > exact - 0.01, "{round}");
        assert!(near(sq.offset(1.0, Join::Miter).area(), 144.0));
        // Chamfered corners cut at 1 from the corner (OpenSCAD's own corners
        // of this offset, read off its STL, lie at ±0.414215).
        let chamfer = sq.offset(1.0, Join::Chamfer);
        assert!(near(chamfer.area(), 144.0 - 2.0 * (2.0 - 2f64.sqrt()).powi(2)), "{}", chamfer.area());
        assert!(chamfer.points().any(|p| (p - DVec2::new(-1.0, -0.414215)).length() < 1e-5));
        assert!(near(sq.offset(-1.0, Join::Miter).area(), 64.0));
        assert!(sq.offset(-6.0, Join::Miter).is_empty());
    }

    #[test]
    fn a_hull_and_a_minkowski_sum_of_squares() {
        let h =
            Region::hull([DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(2.0, 0.0), DVec2::new(0.0, 4.0), DVec2::ONE]);
        assert_eq!(h.contours()[0].len(), 3);
        assert!(near(h.area(), 8.0));
        let m = Region::minkowski(&[Region::square(DVec2::splat(2.0), false), Region::square(DVec2::splat(1.0), true)]);
        assert!(near(m.area(), 9.0), "{}", m.area());
        assert_eq!(m.bounds(), Some((DVec2::splat(-0.5), DVec2::splat(2.5))));
    }

    #[test]
    fn a_mirror_keeps_contours_counter_clockwise() {
        let tri = Region::even_odd(&[vec![DVec2::ZERO, DVec2::new(2.0, 0.0), DVec2::new(0.0, 1.0)]]);
        let m = tri.transformed(&DAffine2::from_scale(DVec2::new(-1.0, 1.0)));
        assert!(signed_area(&m.contours()[0]) > 0.0);
        assert!(near(m.area(), 1.0));
    }
}
