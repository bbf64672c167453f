//! Exact Euclidean distance transform in linear time (Felzenszwalb &
//! Huttenlocher, "Distance Transforms of Sampled Functions", 2012): for every
//! pixel of a mask, the squared distance to the nearest set pixel.
//!
//! Seed 001 finds, for each penumbra pixel, the screen distances to the
//! nearest umbra pixel and the nearest lit pixel by searching around it
//! (every N-th pixel, the rest interpolated). Two transforms give both
//! distances for every pixel at once, exactly, in O(pixels): one pass down
//! each column, then one along each row, each the lower envelope of the
//! parabolas (x − q)² + f(q) rooted at the samples q.
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
    if width == 0 || height == 0 {
        return Vec::new();
    }
    // Down each column (transposed, so each column is one slice and the
    // columns run in parallel): the squared distance to the nearest set
    // pixel of the same column.
    let mut columns = vec![UNREACHED; width * height];
    columns.par_chunks_mut(height).enumerate().for_each_init(
        || Envelope::with_capacity(height),
        |scratch, (x, column)| {
            column.iter_mut().enumerate().for_each(|(y, v)| *v = if mask[y * width + x] { 0.0 } else { UNREACHED });
            scratch.transform_runs(column, |y| apart((x, y), (x, y + 1)));
        },
    );
    // Along each row, over the columns' distances.
    let mut rows = vec![UNREACHED; width * height];
    rows.par_chunks_mut(width).enumerate().for_each_init(
        || Envelope::with_capacity(width),
        |scratch, (y, row)| {
            row.iter_mut().enumerate().for_each(|(x, v)| *v = columns[x * height + y]);
            scratch.transform_runs(row, |x| apart((x, y), (x + 1, y)));
        },
    );
    rows
}

/// The lower envelope's working arrays, kept from line to line.
struct Envelope {
    /// The roots of the parabolas on the envelope.
    roots: Vec<usize>,
    /// Where each one starts to be the lowest (and one past the last).
    starts: Vec<f64>,
    /// A copy of the line being transformed.
    f: Vec<f32>,
}

impl Envelope {
    fn with_capacity(n: usize) -> Envelope {
        Envelope { roots: Vec::with_capacity(n), starts: Vec::with_capacity(n + 1), f: Vec::with_capacity(n) }
    }

    /// Transforms `line` in place, run by run: a run ends after index `i`
    /// where `cut(i)` says so.
    fn transform_runs(&mut self, line: &mut [f32], cut: impl Fn(usize) -> bool) {
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
