//! Strokes into coverage: each stroke a round-capped line of the lines'
//! width, each pixel covered by the share a box filter of one pixel sees of
//! it (from the distance of the pixel's centre to the stroke's axis:
//! `½·width + ½ − distance`, clamped to `0 ..= min(width, 1)`); where strokes
//! overlap a pixel keeps the largest.

use glam::DVec2;
use rayon::prelude::*;

use super::Stroke;
use crate::image::PixelRect;

/// A dash pattern: `on` pixels drawn, then `off` pixels skipped, along the
/// line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Dashes {
    on: f64,
    off: f64,
}

impl Dashes {
    /// The dashes of hidden lines `width` pixels wide: four widths drawn,
    /// three skipped (at least 4 and 3 pixels).
    pub(super) fn of(width: f32) -> Dashes {
        let w = f64::from(width);
        Dashes { on: (4.0 * w).max(4.0), off: (3.0 * w).max(3.0) }
    }

    /// `stroke`'s dashes: the parts of it the pattern draws, the pattern
    /// counted from the line's start.
    fn split(&self, stroke: &Stroke) -> Vec<Stroke> {
        let length = (stroke.b - stroke.a).length();
        let period = self.on + self.off;
        let mut out = Vec::new();
        if length <= 0.0 {
            return out;
        }
        let dir = (stroke.b - stroke.a) / length;
        // The first dash that reaches into the stroke.
        let mut begin = (stroke.start / period).floor() * period - stroke.start;
        while begin < length {
            let (s, e) = (begin.max(0.0), (begin + self.on).min(length));
            if e > s {
                out.push(Stroke { a: stroke.a + dir * s, b: stroke.a + dir * e, start: stroke.start + s });
            }
            begin += period;
        }
        out
    }
}

/// The pixels `held` that `strokes` `width` pixels wide (dashed by `dashes`
/// if given) cover, with their coverage: pixel indices row-major from
/// `held`'s top left, ascending, each once.
pub(super) fn coverage(strokes: &[Stroke], held: PixelRect, width: f32, dashes: Option<Dashes>) -> Vec<(u32, f32)> {
    let dashed: Vec<Stroke>;
    let strokes = match dashes {
        Some(d) => {
            dashed = strokes.par_iter().flat_map_iter(|s| d.split(s)).collect();
            &dashed[..]
        }
        None => strokes,
    };
    let mut spots: Vec<(u32, f32)> = strokes
        .par_chunks(256)
        .map(|chunk| {
            let mut spots = Vec::with_capacity(chunk.len() * 16);
            chunk.iter().for_each(|s| stroke_spots(s, held, width, &mut spots));
            spots
        })
        .collect::<Vec<_>>()
        .concat();
    largest_each(&mut spots);
    spots
}

/// Leaves `spots` (pixel, coverage in 0..=1) sorted by pixel, each pixel once
/// with its largest coverage: sorted as one number each (pixel above, the
/// coverage's bits turned around below: a non-negative float's bits order
/// as its value), which sorts several times faster than comparing pairs.
pub(super) fn largest_each(spots: &mut Vec<(u32, f32)>) {
    let mut keys: Vec<u64> =
        spots.par_iter().map(|&(i, c)| (u64::from(i) << 32) | u64::from(u32::MAX - c.max(0.0).to_bits())).collect();
    keys.par_sort_unstable();
    keys.dedup_by_key(|k| *k >> 32);
    spots.clear();
    spots.extend(keys.iter().map(|&k| ((k >> 32) as u32, f32::from_bits(u32::MAX - (k as u32)))));
}

/// The pixels `stroke` covers among those `held`, with their coverage.
fn stroke_spots(stroke: &Stroke, held: PixelRect, width: f32, out: &mut Vec<(u32, f32)>) {
    let half = f64::from(width) * 0.5;
    let reach = half + 0.5;
    let (lo, hi) = (stroke.a.min(stroke.b) - reach, stroke.a.max(stroke.b) + reach);
    let clamp_x = |v: f64| v.clamp(f64::from(held.x0), f64::from(held.x1)) as u32;
    let clamp_y = |v: f64| v.clamp(f64::from(held.y0), f64::from(held.y1)) as u32;
    let (x0, x1) = (clamp_x(lo.x.floor()), clamp_x(hi.x.ceil()));
    let (y0, y1) = (clamp_y(lo.y.floor()), clamp_y(hi.y.ceil()));
    let most = f64::from(width.min(1.0));
    let row = held.width();
    for y in y0..y1 {
        for x in x0..x1 {
            let centre = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
            let c = (reach - distance_to_segment(centre, stroke.a, stroke.b)).clamp(0.0, most);
            if c > 0.0 {
                out.push(((y - held.y0) * row + (x - held.x0), c as f32));
            }
        }
    }
}

/// The distance from `p` to the segment `a`–`b`.
fn distance_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let along = ab.length_squared();
    let t = if along > 0.0 { ((p - a).dot(ab) / along).clamp(0.0, 1.0) } else { 0.0 };
    (p - (a + ab * t)).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(w: u32, h: u32) -> PixelRect {
        PixelRect { x0: 0, y0: 0, x1: w, y1: h }
    }

    fn dense(spots: &[(u32, f32)], n: usize) -> Vec<f32> {
        let mut out = vec![0.0; n];
        spots.iter().for_each(|&(i, c)| out[i as usize] = c);
        out
    }

    #[test]
    fn a_straight_line_covers_its_width_in_every_column() {
        // A line two pixels wide along y = 10.3 covers about two pixels in
        // each column away from its ends: the sum of the coverage is its area.
        let s = Stroke { a: DVec2::new(5.0, 10.3), b: DVec2::new(35.0, 10.3), start: 0.0 };
        let c = dense(&coverage(&[s], rect(40, 20), 2.0, None), 800);
        for x in 10..30 {
            let column: f32 = (0..20).map(|y| c[y * 40 + x]).sum();
            assert!((column - 2.0).abs() < 0.05, "column {x}: {column}");
        }
        assert!(c[40 * 10 + 20] == 1.0, "the pixel on the line's axis is covered");
        assert!(
            c.iter().enumerate().all(|(i, &v)| v == 0.0 || (i % 40 >= 3 && i % 40 <= 37)),
            "nothing beyond the caps"
        );
    }

    #[test]
    fn dashes_follow_the_pattern_along_the_line() {
        let d = Dashes { on: 4.0, off: 3.0 };
        let s = Stroke { a: DVec2::ZERO, b: DVec2::new(20.0, 0.0), start: 2.0 };
        let parts: Vec<(f64, f64)> = d.split(&s).iter().map(|p| (p.a.x, p.b.x)).collect();
        // The pattern counted from the line's start, 2 before this stroke:
        // drawn 0–4, 7–11, 14–18, 21–25 in the line's length.
        assert_eq!(parts, vec![(0.0, 2.0), (5.0, 9.0), (12.0, 16.0), (19.0, 20.0)]);
    }

    #[test]
    fn overlapping_strokes_keep_the_larger_coverage() {
        let a = Stroke { a: DVec2::new(2.0, 5.5), b: DVec2::new(10.0, 5.5), start: 0.0 };
        let b = Stroke { a: DVec2::new(10.0, 5.5), b: DVec2::new(18.0, 5.5), start: 0.0 };
        let both = coverage(&[a, b, a], rect(20, 10), 1.5, None);
        let one = coverage(&[Stroke { a: a.a, b: b.b, start: 0.0 }], rect(20, 10), 1.5, None);
        assert!(both.windows(2).all(|w| w[0].0 < w[1].0), "each pixel once, in order");
        assert_eq!(both, one, "a polyline's joints and repeated strokes are not drawn darker");
    }
}
