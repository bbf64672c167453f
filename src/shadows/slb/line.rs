//! One silhouette line in one texel, as seed 000 §3.1 (Fig. 1) stores it:
//! Fraction and Slope in k-bit fixed point, the polygon's id and the flags —
//! and its reconstruction in the eye pass (Table 5's line equations, Table 6's
//! inside/outside).
//!
//! Beyond the paper's record: where an end of the edge lies inside the texel
//! (the paper's End flag says only that one does), in k bits along the major
//! axis, so a line that stops inside a texel stops where the edge does; and the
//! depth plane of the line's polygon (the paper keeps one depth per entry and
//! names per-line depth and depth slope as the cure for the black lines of its
//! Fig. 8 at large scales, §4.5).

use super::walk::{LineType, Major, Visit};

/// A depth over one texel: `at(mx, my) = c + dx·mx + dy·my`, `(mx, my)` the
/// position inside the texel in texels from its corner; reversed depth as the
/// shadow map stores it (larger is nearer the light).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TexelDepth {
    /// Depth at the texel's corner (0, 0).
    pub c: f32,
    /// Change per texel along x.
    pub dx: f32,
    /// Change per texel along y.
    pub dy: f32,
}

impl TexelDepth {
    /// The depth at `(mx, my)` inside the texel.
    #[inline]
    #[must_use]
    pub fn at(&self, mx: f32, my: f32) -> f32 {
        self.c + self.dx * mx + self.dy * my
    }
}

/// Which way a surface faces the light, by its triangle's winding (the side
/// its vertices run counter-clockwise around).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Facing {
    /// Towards the light.
    Light,
    /// Away from it.
    Away,
    /// Not known (a solid's outline band, a receiver whose plane is not given).
    #[default]
    Unknown,
}

impl Facing {
    /// How a surface whose winding normal is `normal` faces a light that lies
    /// towards `to_light` (zero `normal`: not known).
    #[must_use]
    pub fn of(normal: glam::Vec3, to_light: glam::Vec3) -> Facing {
        let d = normal.dot(to_light);
        if normal == glam::Vec3::ZERO || !d.is_finite() {
            Facing::Unknown
        } else if d > 0.0 {
            Facing::Light
        } else {
            Facing::Away
        }
    }

    /// Whether both are known and differ: a surface of one facing cannot be
    /// the sheet a point of the other lies on.
    #[inline]
    #[must_use]
    pub fn opposes(self, other: Facing) -> bool {
        matches!((self, other), (Facing::Light, Facing::Away) | (Facing::Away, Facing::Light))
    }
}

/// A surface over an edge texel's centre, counted `count` times (a correction
/// counts −1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layer {
    /// Its depth plane over the texel.
    pub depth: TexelDepth,
    /// How many surfaces it stands for.
    pub count: i32,
    /// The object it belongs to.
    pub object: u32,
    /// Which way it faces the light.
    pub facing: Facing,
}

/// A silhouette line's record in one texel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SilhouetteLine {
    /// Major axis and x sign.
    pub line: LineType,
    /// The Cross flag (see [`Visit::cross`]).
    pub cross: bool,
    /// The L/R flag: true when the line is its polygon's left edge (the
    /// polygon lies on its +x side).
    pub left: bool,
    /// Fraction × 2^k, in 0 ..= 2^k.
    pub fraction: u32,
    /// Slope × 2^k, in 0 ..= 2^k.
    pub slope: u32,
    /// The End flag for the edge's start: where along the major axis it lies
    /// inside the texel (canonical `a`, texels from the side the walk enters
    /// by): at first in k bits, then where the line meets the other line of
    /// that vertex as both are stored, so the stored outline stays closed.
    pub start: Option<f32>,
    /// The End flag for the edge's end.
    pub end: Option<f32>,
    /// The Polygon ID: the triangle the line bounds.
    pub polygon: u32,
    /// The object the triangle belongs to (the paper keeps it per SLB entry;
    /// the compact store keeps it per line).
    pub object: u32,
    /// The depth plane of that polygon over the texel.
    pub depth: TexelDepth,
    /// Which way that polygon faces the light.
    pub facing: Facing,
    /// Whether the texel's centre lies on the polygon's side of this line as
    /// stored (quantised): the reference the eye pass counts crossings from.
    pub centre_inside: bool,
}

/// Rounds `v` ∈ [0, 1] to `bits` fractional bits.
#[must_use]
pub fn quantise(v: f64, bits: u32) -> u32 {
    let one = (1u64 << bits) as f64;
    (v.clamp(0.0, 1.0) * one).round() as u32
}

/// `v` ∈ [0, 1] rounded to `bits` fractional bits, as a number.
fn quantised(v: f64, bits: u32) -> f32 {
    quantise(v, bits) as f32 / (1u64 << bits) as f32
}

impl SilhouetteLine {
    /// The record of walk step `visit` of an edge of type `line` and `slope`,
    /// quantised to `bits`.
    #[must_use]
    pub fn new(visit: &Visit, line: LineType, slope: f64, left: bool, bits: u32) -> SilhouetteLine {
        let mut record = SilhouetteLine {
            line,
            cross: visit.cross,
            left,
            fraction: quantise(visit.fraction, bits),
            slope: quantise(slope, bits),
            start: visit.start.map(|a| quantised(a, bits)),
            end: visit.end.map(|a| quantised(a, bits)),
            polygon: 0,
            object: 0,
            depth: TexelDepth::default(),
            facing: Facing::Unknown,
            centre_inside: false,
        };
        record.centre_inside = record.strictly_inside(0.5, 0.5, bits);
        record
    }

    /// Whether `(mx, my)` lies strictly on the polygon's side of the line (a
    /// point on the line is outside): the side the eye pass counts by.
    #[inline]
    #[must_use]
    pub fn strictly_inside(&self, mx: f32, my: f32, bits: u32) -> bool {
        let off = self.offset(mx, my, bits);
        if self.inside_above() {
            off > 0.0
        } else {
            off < 0.0
        }
    }

    /// How far `(mx, my)` (texel-local, inside the texel or not) lies off
    /// the line along its minor axis, signed (positive above it in the
    /// canonical frame): an affine function of the point.
    #[inline]
    #[must_use]
    pub fn offset(&self, mx: f32, my: f32, bits: u32) -> f32 {
        let (a, b) = self.canonical(mx, my);
        b - self.b_at(a, bits)
    }

    /// The major-axis extent of the line's part in the texel, from its End
    /// flags (0 ..= 1 where it runs through).
    #[inline]
    #[must_use]
    pub fn extent(&self) -> (f32, f32) {
        (self.start.unwrap_or(0.0), self.end.unwrap_or(1.0))
    }

    /// Fraction and Slope as numbers.
    #[inline]
    fn numbers(&self, bits: u32) -> (f32, f32) {
        let s = 1.0 / (1u32 << bits) as f32;
        (self.fraction as f32 * s, self.slope as f32 * s)
    }

    /// Table 5: the line's x at height `my` inside the texel. An x-major line
    /// of Slope 0 is horizontal: its x is ±∞ above and below it, as the
    /// division gives, which Table 6 reads correctly.
    #[must_use]
    pub fn table5_x(&self, my: f32, bits: u32) -> f32 {
        let (frac, slope) = self.numbers(bits);
        match (self.line.major, self.line.x_positive, self.cross) {
            (Major::X, true, false) => (my - frac) / slope,
            (Major::X, true, true) => (my - frac) / slope + 1.0,
            (Major::X, false, false) => -(my - frac) / slope + 1.0,
            (Major::X, false, true) => -(my - frac) / slope,
            (Major::Y, true, false) => slope * my + frac,
            (Major::Y, true, true) => slope * (my - 1.0) + frac,
            (Major::Y, false, false) => -slope * my + (1.0 - frac),
            (Major::Y, false, true) => -slope * (my - 1.0) + (1.0 - frac),
        }
    }

    /// Table 6: whether `(mx, my)` lies on the polygon's side of the line
    /// (inside the shadow region it bounds).
    #[must_use]
    pub fn table6_inside(&self, mx: f32, my: f32, bits: u32) -> bool {
        let left_of_line = mx < self.table5_x(my, bits);
        left_of_line != self.left
    }

    /// `(mx, my)` in the line's canonical frame (`a` along the major axis, `b`
    /// along the minor one, both increasing along the walk).
    #[inline]
    #[must_use]
    pub fn canonical(&self, mx: f32, my: f32) -> (f32, f32) {
        match self.line.major {
            Major::X => (self.mirror(mx), my),
            Major::Y => (my, self.mirror(mx)),
        }
    }

    /// A texel-local x in the line's frame, mirrored for x-negative lines
    /// (its own inverse).
    #[inline]
    fn mirror(&self, x: f32) -> f32 {
        if self.line.x_positive {
            x
        } else {
            1.0 - x
        }
    }

    /// The inverse of [`SilhouetteLine::canonical`].
    #[inline]
    #[must_use]
    pub fn texel_point(&self, a: f32, b: f32) -> (f32, f32) {
        match self.line.major {
            Major::X => (self.mirror(a), b),
            Major::Y => (self.mirror(b), a),
        }
    }

    /// The line's minor coordinate at major coordinate `a` (canonical frame).
    #[inline]
    #[must_use]
    pub fn b_at(&self, a: f32, bits: u32) -> f32 {
        let (frac, slope) = self.numbers(bits);
        if self.cross {
            frac + slope * (a - 1.0)
        } else {
            frac + slope * a
        }
    }

    /// Whether the polygon lies where the minor coordinate is above the line
    /// (canonical frame): Left means the +x side, which is below the line for
    /// x-major x+ and y-major x− lines.
    #[inline]
    #[must_use]
    pub fn inside_above(&self) -> bool {
        self.left != ((self.line.major == Major::X) == self.line.x_positive)
    }

    /// The part of the line inside the texel, as two texel points `(mx, my)`
    /// in walk order; `None` when the reconstructed line misses the texel.
    #[must_use]
    pub fn segment(&self, bits: u32) -> Option<[(f32, f32); 2]> {
        let (_, slope) = self.numbers(bits);
        let b0 = self.b_at(0.0, bits);
        let (mut lo, mut hi) = self.extent();
        // Where the line meets b = 0 and b = 1.
        if slope > 0.0 {
            lo = lo.max(-b0 / slope);
            hi = hi.min((1.0 - b0) / slope);
        } else if !(0.0..=1.0).contains(&b0) {
            return None;
        }
        (lo <= hi).then(|| [self.texel_point(lo, self.b_at(lo, bits)), self.texel_point(hi, self.b_at(hi, bits))])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shadows::slb::walk::{Edge, WalkPoint};
    use proptest::prelude::*;

    fn lines(p: (f64, f64), q: (f64, f64), bits: u32) -> Vec<(Visit, SilhouetteLine)> {
        let e = Edge::new(WalkPoint::snap(p.0, p.1), WalkPoint::snap(q.0, q.1)).unwrap();
        let mut out = Vec::new();
        e.walk(|v| out.push((v, SilhouetteLine::new(&v, e.line, e.slope, true, bits))));
        out
    }

    /// Distance from texel point `m` of texel `(x, y)` to the exact line `p`–`q`.
    fn distance(p: (f64, f64), q: (f64, f64), x: i32, y: i32, m: (f32, f32)) -> f64 {
        let (px, py) = (x as f64 + m.0 as f64, y as f64 + m.1 as f64);
        let (dx, dy) = (q.0 - p.0, q.1 - p.1);
        ((px - p.0) * dy - (py - p.1) * dx).abs() / (dx * dx + dy * dy).sqrt()
    }

    /// Where the lines rebuilt from `bits`-bit numbers stray more than 2^-bits
    /// texel from the edge `(px, py)`–`(qx, qy)` the walk is given (its ends
    /// on the walk's grid: a short edge's snapped ends tilt it by more than
    /// 2^-16 a texel), at points a quarter texel apart along each line.
    fn reconstruction_error(px: f64, py: f64, qx: f64, qy: f64, bits: u32) -> Option<String> {
        let step = 1.0 / (1u64 << bits) as f64;
        let (p, q) = (WalkPoint::snap(px, py).texels(), WalkPoint::snap(qx, qy).texels());
        for (v, line) in lines((px, py), (qx, qy), bits) {
            for a in [0.0, 0.25, 0.5, 0.75, 1.0f32] {
                let b = line.b_at(a, bits);
                if !(0.0..=1.0).contains(&b) {
                    continue;
                }
                let d = distance(p, q, v.x, v.y, line.texel_point(a, b));
                if d > step + 1e-6 {
                    return Some(format!("{d} > {step} at texel ({}, {})", v.x, v.y));
                }
            }
        }
        None
    }

    /// A short steep edge whose snapped ends tilt it: within the step of the
    /// edge the walk is given.
    #[test]
    fn a_short_edge_reconstructs_within_one_step() {
        let e = reconstruction_error(-1.097939886375706, 2.27010754998979, -1.0970152182165955, 2.282354158991121, 16);
        assert_eq!(e, None);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// Per-line reconstruction: in every texel an edge crosses, the line
        /// rebuilt from k-bit Fraction and Slope lies within 2^-k texel of the
        /// edge, at every point of its part in the texel, for k = 4, 8, 16.
        #[test]
        fn a_reconstructed_line_is_within_one_step_of_the_edge(
            px in -3.0f64..3.0, py in -3.0f64..3.0, qx in -3.0f64..3.0, qy in -3.0f64..3.0, k in 0usize..3,
        ) {
            let bits = [4, 8, 16][k];
            prop_assume!((px - qx).abs() + (py - qy).abs() > 1e-3);
            let error = reconstruction_error(px, py, qx, qy, bits);
            prop_assert!(error.is_none(), "{:?}", error);
        }

        /// Table 5 and the canonical frame describe the same line: Table 6's
        /// inside/outside agrees with the side of `b_at` away from the line.
        #[test]
        fn table5_and_the_canonical_line_agree(
            px in -3.0f64..3.0, py in -3.0f64..3.0, qx in -3.0f64..3.0, qy in -3.0f64..3.0,
            mx in 0.0f32..1.0, my in 0.0f32..1.0, left: bool,
        ) {
            prop_assume!((px - qx).abs() + (py - qy).abs() > 1e-3);
            for (_, mut line) in lines((px, py), (qx, qy), 16) {
                line.left = left;
                let (a, b) = line.canonical(mx, my);
                let off = b - line.b_at(a, 16);
                if off.abs() < 1e-3 || line.slope == 0 {
                    continue;
                }
                prop_assert_eq!(line.table6_inside(mx, my, 16), (off > 0.0) == line.inside_above());
            }
        }
    }

    /// Table 6 on a vertical left edge: inside is its +x side.
    #[test]
    fn a_left_edge_has_its_polygon_on_the_right() {
        let l = lines((0.5, 0.0), (0.5, 1.0), 8)[0].1;
        assert!(l.table6_inside(0.75, 0.5, 8));
        assert!(!l.table6_inside(0.25, 0.5, 8));
    }
}
