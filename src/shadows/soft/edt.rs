//! Exact Euclidean distance transform in linear time (Felzenszwalb &
//! Huttenlocher, "Distance Transforms of Sampled Functions", 2012): for every
//! pixel of a mask, the squared distance to the nearest set pixel.
//!
//! Seed 001 finds, for each penumbra pixel, the screen distances to the
//! nearest umbra pixel and the nearest lit pixel by searching around it
//! (every N-th pixel, the rest interpolated). Two transforms give both
//! distances for every pixel at once, exactly, in O(pixels): first each
//! pixel's distance to the nearest set pixel of its column (two sweeps over
//! the rows, down and up, many columns at a time: [`Columns`]), then along
//! each row the lower envelope of the parabolas (x − q)² + g(q)² rooted at
//! the columns' distances g.
//!
//! The transform may be told where it must not carry a distance across
//! (`apart`): between two neighbouring pixels of one row or column whose
//! surfaces lie at very different depths. Each row and column is then cut
//! into runs at those places and each run transformed on its own, so a
//! distance reaches a pixel only along a path (down a column, then along a
//! row) that crosses no cut.

use rayon::prelude::*;

/// A squared distance no pixel reaches: the mask holds no set pixel on any
/// path that crosses no cut.
pub const UNREACHED: f32 = f32::INFINITY;

/// Squared Euclidean distance, in pixels, from each pixel of a `width` ×
/// `height` image (row by row) to the nearest pixel `mask` sets (0 on set
/// pixels; [`UNREACHED`] everywhere when none is set).
///
/// # Panics
///
/// If `mask` does not hold `width` × `height` values.
#[must_use]
pub fn squared_distances(mask: &[bool], width: usize, height: usize) -> Vec<f32> {
    squared_distances_apart(mask, width, height, |_, _| false)
}

/// [`squared_distances`], never carried between two neighbouring pixels
/// `apart(a, b)` says are apart (`a`, `b` as `(x, y)`, `b` one pixel right of
/// or below `a`): each column, then each row, is transformed run by run
/// between those cuts.
///
/// # Panics
///
/// If `mask` does not hold `width` × `height` values.
#[must_use]
pub fn squared_distances_apart(
    mask: &[bool],
    width: usize,
    height: usize,
    apart: impl Fn((usize, usize), (usize, usize)) -> bool + Sync,
) -> Vec<f32> {
    assert_eq!(mask.len(), width * height, "a mask of {width} × {height}");
    let cuts = cuts_between(width, height, apart);
    let columns = Columns::new(|i| mask[i], &cuts, width, height);
    let mut out = vec![UNREACHED; width * height];
    out.par_chunks_mut(width.max(1)).enumerate().for_each_init(
        || Envelope::with_capacity(width),
        |scratch, (y, row)| {
            columns.squared_row(y, row);
            scratch.transform_runs(row, |x| cuts[y * width + x] & CUT_RIGHT != 0);
        },
    );
    out
}

/// A pixel's cut bit: it lies apart from the pixel right of it.
pub const CUT_RIGHT: u8 = 1;
/// A pixel's cut bit: it lies apart from the pixel below it.
pub const CUT_DOWN: u8 = 2;

/// A pixel's cut bits: apart from the pixel `right` of it, from the one
/// `below` it.
#[must_use]
pub fn cut_bits(right: bool, below: bool) -> u8 {
    (u8::from(right) * CUT_RIGHT) | (u8::from(below) * CUT_DOWN)
}

/// Each pixel's cut bits ([`CUT_RIGHT`], [`CUT_DOWN`]) of a `width` ×
/// `height` image, as `apart` says of it and its neighbours.
#[must_use]
pub fn cuts_between(
    width: usize,
    height: usize,
    apart: impl Fn((usize, usize), (usize, usize)) -> bool + Sync,
) -> Vec<u8> {
    let mut cuts = vec![0u8; width * height];
    cuts.par_chunks_mut(width.max(1)).enumerate().for_each(|(y, row)| {
        for (x, c) in row.iter_mut().enumerate() {
            let right = x + 1 < width && apart((x, y), (x + 1, y));
            let down = y + 1 < height && apart((x, y), (x, y + 1));
            *c = cut_bits(right, down);
        }
    });
    cuts
}

/// Columns swept together: a strip's distances lie together in memory, so
/// that the sweeps down and up the image read whole cache lines.
const STRIP: usize = 64;

/// Distance in pixels no set pixel reaches along a column.
const FAR: u16 = u16::MAX;

/// The first pass of the transform: for every pixel, the distance down or
/// up its column to the nearest set pixel that no cut ([`CUT_DOWN`])
/// separates from it — two sweeps along the image's rows, top to bottom and
/// back, many columns at once, instead of one column at a time across the
/// rows (which reads one value per cache line).
pub struct Columns {
    width: usize,
    height: usize,
    /// Strip by strip ([`STRIP`] columns), row by row within a strip.
    distances: Vec<u16>,
}

impl Columns {
    /// The column distances of the pixels `set` says are set (by index, row
    /// by row) in a `width` × `height` image with `cuts`.
    ///
    /// # Panics
    ///
    /// If `cuts` does not hold `width` × `height` values.
    #[must_use]
    pub fn new(set: impl Fn(usize) -> bool + Sync, cuts: &[u8], width: usize, height: usize) -> Columns {
        assert_eq!(cuts.len(), width * height, "cuts of {width} × {height}");
        let mut distances = vec![FAR; width.div_ceil(STRIP) * STRIP * height];
        distances.par_chunks_mut((STRIP * height).max(1)).enumerate().for_each(|(strip, d)| {
            let (x0, x1) = (strip * STRIP, (strip * STRIP + STRIP).min(width));
            for y in 0..height {
                for x in x0..x1 {
                    let (i, k) = (y * width + x, y * STRIP + x - x0);
                    d[k] = if set(i) {
                        0
                    } else if y > 0 && cuts[i - width] & CUT_DOWN == 0 {
                        d[k - STRIP].saturating_add(1)
                    } else {
                        FAR
                    };
                }
            }
            for y in (0..height.saturating_sub(1)).rev() {
                for x in x0..x1 {
                    let (i, k) = (y * width + x, y * STRIP + x - x0);
                    if cuts[i] & CUT_DOWN == 0 {
                        d[k] = d[k].min(d[k + STRIP].saturating_add(1));
                    }
                }
            }
        });
        Columns { width, height, distances }
    }

    /// Row `y`'s squared column distances into `out` ([`UNREACHED`] where
    /// none is set).
    ///
    /// # Panics
    ///
    /// If `out` is not one row long or `y` is past the last row.
    pub fn squared_row(&self, y: usize, out: &mut [f32]) {
        assert!(out.len() == self.width && y < self.height, "a row of {}", self.width);
        for (strip, chunk) in out.chunks_mut(STRIP).enumerate() {
            let at = (strip * self.height + y) * STRIP;
            let len = chunk.len();
            for (o, &d) in chunk.iter_mut().zip(&self.distances[at..at + len]) {
                *o = if d == FAR { UNREACHED } else { f32::from(d) * f32::from(d) };
            }
        }
    }
}

/// The lower envelope's working arrays, kept from line to line.
pub struct Envelope {
    /// The roots of the parabolas on the envelope.
    roots: Vec<usize>,
    /// Where each one starts to be the lowest (and one past the last).
    starts: Vec<f64>,
    /// A copy of the line being transformed.
    f: Vec<f32>,
}

impl Envelope {
    /// Working arrays for lines of up to `n` values.
    #[must_use]
    pub fn with_capacity(n: usize) -> Envelope {
        Envelope { roots: Vec::with_capacity(n), starts: Vec::with_capacity(n + 1), f: Vec::with_capacity(n) }
    }

    /// Transforms `line` in place, run by run: a run ends after index `i`
    /// where `cut(i)` says so.
    pub fn transform_runs(&mut self, line: &mut [f32], cut: impl Fn(usize) -> bool) {
        let mut start = 0;
        for i in 0..line.len() {
            if i + 1 == line.len() || cut(i) {
                self.transform(&mut line[start..=i]);
                start = i + 1;
            }
        }
    }

    /// d(p) = min over q of (p − q)² + f(q), in place (f = [`UNREACHED`]
    /// where nothing is rooted).
    fn transform(&mut self, line: &mut [f32]) {
        self.f.clear();
        self.f.extend_from_slice(line);
        self.roots.clear();
        self.starts.clear();
        // Where the parabolas rooted at q and p (p < q) cross.
        let cross = |f: &[f32], p: usize, q: usize| {
            let (fp, fq) = (f64::from(f[p]), f64::from(f[q]));
            let (p, q) = (p as f64, q as f64);
            ((fq + q * q) - (fp + p * p)) / (2.0 * (q - p))
        };
        for q in 0..self.f.len() {
            if self.f[q] == UNREACHED {
                continue;
            }
            loop {
                let Some(&p) = self.roots.last() else {
                    self.roots.push(q);
                    self.starts.push(f64::NEG_INFINITY);
                    break;
                };
                let s = cross(&self.f, p, q);
                if s <= *self.starts.last().expect("one start per root") {
                    self.roots.pop();
                    self.starts.pop();
                    continue;
                }
                self.roots.push(q);
                self.starts.push(s);
                break;
            }
        }
        if self.roots.is_empty() {
            line.fill(UNREACHED);
            return;
        }
        let mut k = 0;
        for (p, out) in line.iter_mut().enumerate() {
            while k + 1 < self.roots.len() && self.starts[k + 1] < p as f64 {
                k += 1;
            }
            let q = self.roots[k];
            let d = p as f64 - q as f64;
            *out = (d * d + f64::from(self.f[q])) as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};

    use super::*;

    /// The nearest set pixel by looking at every one.
    fn brute_force(mask: &[bool], width: usize) -> Vec<f32> {
        let set: Vec<(i64, i64)> = mask
            .iter()
            .enumerate()
            .filter(|(_, &m)| m)
            .map(|(i, _)| ((i % width) as i64, (i / width) as i64))
            .collect();
        (0..mask.len())
            .map(|i| {
                let (x, y) = ((i % width) as i64, (i / width) as i64);
                set.iter().map(|&(a, b)| ((a - x).pow(2) + (b - y).pow(2)) as f32).fold(UNREACHED, f32::min)
            })
            .collect()
    }

    /// On random masks — sparse, dense, empty, one pixel, thin shapes — every
    /// squared distance equals the brute-force nearest search's, exactly.
    #[test]
    fn the_transform_equals_a_brute_force_nearest_search() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        for case in 0..200 {
            let (w, h) = (rng.gen_range(1..40), rng.gen_range(1..40));
            let density = [0.0, 0.002, 0.02, 0.2, 0.7, 1.0][case % 6];
            let mut mask: Vec<bool> = (0..w * h).map(|_| rng.gen_bool(density)).collect();
            if case % 7 == 0 {
                // A thin diagonal line.
                mask.iter_mut().enumerate().for_each(|(i, m)| *m = i % w == (i / w) % w);
            }
            assert_eq!(squared_distances(&mask, w, h), brute_force(&mask, w), "case {case}: {w} × {h}");
        }
    }

    /// With random cuts, every squared distance is the brute-force nearest
    /// set pixel among those reached by a path down (or up) a column and
    /// then along a row that crosses no cut.
    #[test]
    fn random_cuts_keep_distances_to_uncut_paths() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        for case in 0..150 {
            let (w, h) = (rng.gen_range(1..90), rng.gen_range(1..40));
            let mask: Vec<bool> = (0..w * h).map(|_| rng.gen_bool([0.01, 0.05, 0.3][case % 3])).collect();
            let cuts: Vec<u8> = (0..w * h).map(|_| rng.gen_range(0..4u8) * u8::from(rng.gen_bool(0.2))).collect();
            let apart = |a: (usize, usize), b: (usize, usize)| {
                let bit = if b.1 > a.1 { CUT_DOWN } else { CUT_RIGHT };
                cuts[a.1 * w + a.0] & bit != 0
            };
            // Whether the column `x` from row `a` to row `b` crosses no cut, and
            // the same along row `y` from column `a` to `b`.
            let column_open = |x: usize, a: usize, b: usize| (a.min(b)..a.max(b)).all(|y| !apart((x, y), (x, y + 1)));
            let row_open = |y: usize, a: usize, b: usize| (a.min(b)..a.max(b)).all(|x| !apart((x, y), (x + 1, y)));
            let got = squared_distances_apart(&mask, w, h, apart);
            for y in 0..h {
                for x in 0..w {
                    let want = (0..w * h)
                        .filter(|&i| mask[i])
                        .map(|i| (i % w, i / w))
                        .filter(|&(q, r)| column_open(q, r, y) && row_open(y, q, x))
                        .map(|(q, r)| ((q as i64 - x as i64).pow(2) + (r as i64 - y as i64).pow(2)) as f32)
                        .fold(UNREACHED, f32::min);
                    assert_eq!(got[y * w + x], want, "case {case}: ({x}, {y}) of {w} × {h}");
                }
            }
        }
    }

    /// A cut stops the distance: a set pixel's distance reaches across an
    /// uncut image, not past a column of cuts, and what lies beyond it is
    /// measured from its own side.
    #[test]
    fn a_cut_keeps_the_distance_on_its_side() {
        let (w, h) = (9, 5);
        let mut mask = vec![false; w * h];
        mask[2 * w + 1] = true;
        let whole = squared_distances(&mask, w, h);
        assert_eq!(whole[2 * w + 8], 49.0);
        let cut = squared_distances_apart(&mask, w, h, |a, b| a.0 == 4 && b.0 == 5);
        for y in 0..h {
            for x in 0..w {
                let want = if x <= 4 { whole[y * w + x] } else { UNREACHED };
                assert_eq!(cut[y * w + x], want, "({x}, {y})");
            }
        }
        mask[2 * w + 7] = true;
        let both = squared_distances_apart(&mask, w, h, |a, b| a.0 == 4 && b.0 == 5);
        assert_eq!((both[2 * w + 4], both[2 * w + 5]), (9.0, 4.0), "each side measured from its own pixel");
    }
}
