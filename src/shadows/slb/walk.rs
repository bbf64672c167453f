//! The outline walk of seed 000 §3.3.1 (Tables 2 and 3, Fig. 5): every texel a
//! polygon edge passes through, none skipped and none added — unlike Bresenham's
//! line, which picks the texels nearest the line (the paper's Fig. 3).
//!
//! An edge is always walked towards +y. Its *type* is its major axis and the
//! sign of its x step; the four types are one walk in canonical coordinates
//! `(a, b)` — `a` along the major axis, `b` along the minor one, both mirrored to
//! increase — so that `db/da` is the paper's Slope ∈ [0, 1]. In a texel the walk
//! holds the paper's state: the *Cross flag* (0: the edge entered through a
//! grid line across the major axis, 1: through one along it) and the *Fraction*
//! (the `b` coordinate of the entry point for Cross 0, of the exit point on the
//! next `a` grid line for Cross 1). Fraction + Slope against 1 picks the exit
//! (Table 2): past 1 the edge leaves through the major-axis side, at 1 through
//! the corner, below 1 through the minor-axis side.
//!
//! The arithmetic is exact: endpoints sit on a grid of 2^-[`WALK_BITS`] texel,
//! and a Fraction is kept as the integer numerator of a rational whose
//! denominator is fixed per edge, so a corner is a corner and an edge along a
//! grid line is recognised as one. A texel is visited when the edge meets its
//! open interior: an edge through a corner does not visit the two texels that
//! only touch it there, and an edge lying on a grid line visits none (every
//! point of the texels beside it is on one side of it, which the shadow map's
//! own sample already tells).

/// Fractional bits of the texel coordinates the walk takes: finer than the
/// 16 bits the silhouette-line buffer stores at most, so snapping an endpoint
/// costs 2^-21 texel.
pub const WALK_BITS: u32 = 20;

/// One texel in walk units.
const UNIT: i64 = 1 << WALK_BITS;

/// The axis along which an edge moves farther (the paper's Major).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Major {
    /// |dx| > |dy|.
    X,
    /// |dy| ≥ |dx|.
    Y,
}

/// An edge's type: its major axis and whether x grows along it (the paper's
/// Xsign; edges are walked towards +y, a horizontal one towards +x).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LineType {
    /// The major axis.
    pub major: Major,
    /// x grows (or stays) along the walk.
    pub x_positive: bool,
}

/// Which side of a texel an edge leaves it through (Table 2's columns).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exit {
    /// Through a grid line along the major axis (`b` + 1).
    MajorAxis,
    /// Through the corner.
    Corner,
    /// Through a grid line across the major axis (`a` + 1).
    MinorAxis,
}

impl LineType {
    /// Table 2: the exit point number (0–4) of `exit` for this type; moving
    /// through exit k changes the texel by 0: (−1, +1), 1: (−1, 0), 2: (+1, 0),
    /// 3: (+1, +1), 4: (0, +1).
    #[must_use]
    pub fn exit_point(self, exit: Exit) -> u8 {
        match (self.major, self.x_positive, exit) {
            (Major::X, _, Exit::MajorAxis) | (Major::Y, _, Exit::MinorAxis) => 4,
            (_, true, Exit::Corner) => 3,
            (_, false, Exit::Corner) => 0,
            (Major::X, true, Exit::MinorAxis) | (Major::Y, true, Exit::MajorAxis) => 2,
            (Major::X, false, Exit::MinorAxis) | (Major::Y, false, Exit::MajorAxis) => 1,
        }
    }
}

/// The texel step of Table 2's exit point `k` (x, y).
#[must_use]
pub fn exit_step(k: u8) -> (i32, i32) {
    match k {
        0 => (-1, 1),
        1 => (-1, 0),
        2 => (1, 0),
        3 => (1, 1),
        _ => (0, 1),
    }
}

/// A point in walk units: texel coordinates × 2^[`WALK_BITS`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct WalkPoint {
    /// x × 2^WALK_BITS.
    pub x: i64,
    /// y × 2^WALK_BITS.
    pub y: i64,
}

impl WalkPoint {
    /// The nearest walk point to texel coordinates `(x, y)`.
    #[must_use]
    pub fn snap(x: f64, y: f64) -> WalkPoint {
        let s = UNIT as f64;
        WalkPoint { x: (x * s).round() as i64, y: (y * s).round() as i64 }
    }

    /// Texel coordinates.
    #[must_use]
    pub fn texels(self) -> (f64, f64) {
        (self.x as f64 / UNIT as f64, self.y as f64 / UNIT as f64)
    }
}

/// One texel of a walk: what the paper stores per texel before quantising.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Visit {
    /// Texel column.
    pub x: i32,
    /// Texel row.
    pub y: i32,
    /// The Cross flag: the edge entered through a grid line along its major
    /// axis (true) or across it (false).
    pub cross: bool,
    /// The Fraction, exactly (as a double): for Cross 0 the minor coordinate of
    /// the entry point, for Cross 1 that of the exit point on the next grid
    /// line across the major axis, in texels from the texel's side (mirrored
    /// for x-negative edges, as Table 5 reads it).
    pub fraction: f64,
    /// The edge's start lies inside this texel (not on its border): where along
    /// the major axis, in texels from the texel's entry side.
    pub start: Option<f64>,
    /// The edge's end lies inside this texel: where along the major axis.
    pub end: Option<f64>,
    /// Table 2's exit point (0–4) the edge leaves this texel through, `None`
    /// in the last texel.
    pub exit: Option<u8>,
}

/// An edge ready to walk: its type, Slope and canonical coordinates.
#[derive(Debug, Clone, Copy)]
pub struct Edge {
    /// Major axis and x sign.
    pub line: LineType,
    /// |minor step / major step| ∈ [0, 1], exactly as a double.
    pub slope: f64,
    a0: i64,
    b0: i64,
    a1: i64,
    b1: i64,
}

impl Edge {
    /// The edge between `p` and `q`, oriented towards +y (a horizontal one
    /// towards +x); `None` for a point.
    #[must_use]
    pub fn new(p: WalkPoint, q: WalkPoint) -> Option<Edge> {
        let (p, q) = if (p.y, p.x) <= (q.y, q.x) { (p, q) } else { (q, p) };
        let (dx, dy) = (q.x - p.x, q.y - p.y);
        if dx == 0 && dy == 0 {
            return None;
        }
        let x_positive = dx >= 0;
        let s = if x_positive { 1 } else { -1 };
        let (major, a0, b0, a1, b1) =
            if dx.abs() > dy { (Major::X, s * p.x, p.y, s * q.x, q.y) } else { (Major::Y, p.y, s * p.x, q.y, s * q.x) };
        let slope = (b1 - b0) as f64 / (a1 - a0) as f64;
        Some(Edge { line: LineType { major, x_positive }, slope, a0, b0, a1, b1 })
    }

    /// Whether the edge was given the other way round (its walk runs from its
    /// second point to its first).
    #[must_use]
    pub fn reversed(p: WalkPoint, q: WalkPoint) -> bool {
        (p.y, p.x) > (q.y, q.x)
    }

    /// The texel (x, y) of canonical texel (a, b).
    fn texel(&self, ta: i64, tb: i64) -> (i32, i32) {
        let mirror = |t: i64| if self.line.x_positive { t } else { -1 - t };
        match self.line.major {
            Major::X => (mirror(ta) as i32, tb as i32),
            Major::Y => (mirror(tb) as i32, ta as i32),
        }
    }

    /// Visits every texel the edge passes through, in order along it.
    pub fn walk(&self, mut visit: impl FnMut(Visit)) {
        let (da, db) = (self.a1 - self.a0, self.b1 - self.b0);
        if db == 0 && self.b0.rem_euclid(UNIT) == 0 {
            return; // along a grid line: no texel's interior
        }
        let (da, db) = (i128::from(da), i128::from(db));
        let unit = i128::from(UNIT);
        // b·da at a, exactly: B(a) = b0·da + (a − a0)·db.
        let b_at = |a: i64| i128::from(self.b0) * da + (i128::from(a) - i128::from(self.a0)) * db;
        // One texel of b in B units.
        let one = unit * da;
        let (mut ta, mut tb) = (self.a0.div_euclid(UNIT), self.b0.div_euclid(UNIT));
        // Table 3: extended backwards to the texel's entry grid line across the
        // major axis, does the edge reach it within the texel (fr ≥ 0)?
        let fr = b_at(ta * UNIT) - i128::from(tb) * one;
        let (mut cross, mut frac) = if fr >= 0 { (false, fr) } else { (true, fr + unit * db) };
        let minor_in = |v: i64| v.rem_euclid(UNIT) != 0;
        let inside = |a: i64, b: i64, ta: i64, tb: i64| {
            minor_in(a) && minor_in(b) && a.div_euclid(UNIT) == ta && b.div_euclid(UNIT) == tb
        };
        let along = |a: i64, ta: i64| (a - ta * UNIT) as f64 / UNIT as f64;
        let mut first = true;
        loop {
            // The minor coordinate where the edge meets the next grid line
            // across the major axis, relative to this texel.
            let exit_b = if cross { frac } else { frac + unit * db };
            let exit = match exit_b.cmp(&one) {
                std::cmp::Ordering::Greater => Exit::MajorAxis,
                std::cmp::Ordering::Equal => Exit::Corner,
                std::cmp::Ordering::Less => Exit::MinorAxis,
            };
            let last = match exit {
                Exit::MajorAxis => self.b1 <= (tb + 1) * UNIT,
                Exit::Corner | Exit::MinorAxis => self.a1 <= (ta + 1) * UNIT,
            };
            let (x, y) = self.texel(ta, tb);
            let start = (first && inside(self.a0, self.b0, ta, tb)).then(|| along(self.a0, ta));
            let end = (last && inside(self.a1, self.b1, ta, tb)).then(|| along(self.a1, ta));
            visit(Visit {
                x,
                y,
                cross,
                fraction: frac as f64 / one as f64,
                start,
                end,
                exit: (!last).then(|| self.line.exit_point(exit)),
            });
            if last {
                return;
            }
            first = false;
            match exit {
                Exit::MajorAxis => (tb, cross, frac) = (tb + 1, true, exit_b - one),
                Exit::Corner => (ta, tb, cross, frac) = (ta + 1, tb + 1, false, 0),
                Exit::MinorAxis => (ta, cross, frac) = (ta + 1, false, exit_b),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Texels whose open square the closed segment `p`–`q` meets, by exact
    /// parametric clipping — an oracle that shares nothing with the walk.
    fn oracle(p: WalkPoint, q: WalkPoint) -> Vec<(i32, i32)> {
        let (dx, dy) = (i128::from(q.x - p.x), i128::from(q.y - p.y));
        let mut out = Vec::new();
        let lo = |a: i64, b: i64| a.min(b).div_euclid(UNIT) - 1;
        let hi = |a: i64, b: i64| a.max(b).div_euclid(UNIT) + 1;
        for ty in lo(p.y, q.y)..=hi(p.y, q.y) {
            for tx in lo(p.x, q.x)..=hi(p.x, q.x) {
                // t ranges as fractions (num, den) with den > 0: open intervals.
                let range = |o: i64, d: i128, t: i64| -> Option<((i128, i128), (i128, i128))> {
                    let (l, h) = (i128::from(t * UNIT - o), i128::from((t + 1) * UNIT - o));
                    match d.signum() {
                        0 => (l < 0 && h > 0).then_some(((-1, 1), (2, 1))),
                        1 => Some(((l, d), (h, d))),
                        _ => Some(((h, d), (l, d))),
                    }
                };
                let (Some(rx), Some(ry)) = (range(p.x, dx, tx), range(p.y, dy, ty)) else { continue };
                let norm = |(n, d): (i128, i128)| if d < 0 { (-n, -d) } else { (n, d) };
                let less = |a: (i128, i128), b: (i128, i128)| {
                    let (a, b) = (norm(a), norm(b));
                    a.0 * b.1 < b.0 * a.1
                };
                let lo_t = if less(norm(rx.0), norm(ry.0)) { norm(ry.0) } else { norm(rx.0) };
                let hi_t = if less(norm(rx.1), norm(ry.1)) { norm(rx.1) } else { norm(ry.1) };
                if less(lo_t, hi_t) && less(lo_t, (1, 1)) && less((0, 1), hi_t) {
                    out.push((tx as i32, ty as i32));
                }
            }
        }
        out.sort_unstable();
        out
    }

    fn walked(p: WalkPoint, q: WalkPoint) -> Vec<Visit> {
        let mut v = Vec::new();
        if let Some(e) = Edge::new(p, q) {
            e.walk(|s| v.push(s));
        }
        v
    }

    fn check(p: WalkPoint, q: WalkPoint) {
        if p == q {
            return; // a point is no edge
        }
        let visits = walked(p, q);
        let mut got: Vec<(i32, i32)> = visits.iter().map(|v| (v.x, v.y)).collect();
        // Consecutive visits step by the exit point each names.
        for pair in visits.windows(2) {
            let (dx, dy) = exit_step(pair[0].exit.expect("an exit before the last texel"));
            assert_eq!((pair[0].x + dx, pair[0].y + dy), (pair[1].x, pair[1].y), "{p:?} {q:?}");
        }
        got.sort_unstable();
        let n = got.len();
        got.dedup();
        assert_eq!(n, got.len(), "a texel visited twice: {p:?} {q:?}");
        assert_eq!(got, oracle(p, q), "{p:?} → {q:?}");
    }

    /// A coordinate: often on a grid line or a texel's centre, else anywhere.
    fn coordinate() -> impl Strategy<Value = i64> {
        prop_oneof![
            (-6i64..6).prop_map(|t| t * UNIT),
            (-6i64..6).prop_map(|t| t * UNIT + UNIT / 2),
            (-6 * UNIT..6 * UNIT),
            (-2 * UNIT..2 * UNIT).prop_map(|v| v / 1024 * 1024),
        ]
    }

    fn point() -> impl Strategy<Value = WalkPoint> {
        (coordinate(), coordinate()).prop_map(|(x, y)| WalkPoint { x, y })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]

        /// Random segments, many through texel corners and along texel
        /// edges, of all four types, visit exactly the texels they cross.
        #[test]
        fn the_walk_visits_exactly_the_texels_an_edge_crosses(p in point(), q in point()) {
            check(p, q);
        }

        /// Lines at exactly 45° and along the axes through corners: the
        /// corner exits of Table 2.
        #[test]
        fn diagonals_and_axis_lines_through_corners(x in -4i64..4, y in -4i64..4, n in 1i64..5, k in 0usize..8) {
            let (dx, dy) = [(1, 1), (-1, 1), (1, -1), (-1, -1), (1, 0), (0, 1), (2, 1), (1, 2)][k];
            let p = WalkPoint { x: x * UNIT, y: y * UNIT };
            let q = WalkPoint { x: p.x + dx * n * UNIT, y: p.y + dy * n * UNIT };
            check(p, q);
        }
    }

    /// Table 3 and the Fraction: in each visited texel, the Fraction places
    /// the edge where it really is (the exact crossing of the texel's side).
    #[test]
    fn fractions_are_the_exact_crossings() {
        let (p, q) = (WalkPoint::snap(0.3, 0.2), WalkPoint::snap(3.7, 1.9));
        let e = Edge::new(p, q).unwrap();
        let slope = 1.7 / 3.4;
        assert!((e.slope - slope).abs() < 1e-6);
        for v in walked(p, q) {
            // x-major, x+: Cross 0 ⇒ the edge is at y + Fraction on the left side x;
            // Cross 1 ⇒ at y + Fraction on the right side x + 1.
            let side = if v.cross { v.x + 1 } else { v.x } as f64;
            let y = 0.2 + (side - 0.3) * slope;
            assert!((y - (v.y as f64 + v.fraction)).abs() < 1e-5, "{v:?}");
        }
    }

    /// The first and last texels of an edge inside the map carry where its
    /// ends lie; an end on a grid line is no end inside a texel.
    #[test]
    fn ends_inside_texels_are_marked() {
        let v = walked(WalkPoint::snap(0.5, 0.25), WalkPoint::snap(2.5, 1.0));
        assert_eq!(v.first().unwrap().start, Some(0.5));
        assert!(v.iter().all(|s| s.end.is_none()), "the end lies on a grid line");
        let v = walked(WalkPoint::snap(0.5, 0.5), WalkPoint::snap(0.25, 0.75));
        assert_eq!(v.len(), 1);
        assert_eq!((v[0].start, v[0].end), (Some(0.5), Some(0.75)), "y-major x−: a along y");
    }
}
