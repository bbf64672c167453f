//! A pixel's light visibility from two hard shadows (seed 001 §3): shadowed
//! in both is umbra (V = 0), in neither lit (V = 1), in one penumbra, where
//! V = D1 / (D1 + D2) with D1 the screen distance to the nearest umbra pixel
//! and D2 to the nearest lit one — 0 beside the umbra, 1 beside the light.
//! (The paper's eq. 3.4 writes C = D2 / (D1 + D2) and calls C → 0 black,
//! which would make a pixel next to the umbra white: its own text asks for
//! D1 / (D1 + D2).)
//!
//! Two ways to the distances. [`visibility_searched`] is the paper's: a
//! search outwards from every N-th pixel in x and y, the pixels between
//! interpolated bilinearly (§3.3.3; its eqs. 3.6 and 3.7 swap the weights of
//! the two neighbours, so a linear ramp would not come back: ordinary
//! bilinear weights here). [`visibility_exact`] is kage's: two exact
//! distance transforms ([`super::edt`]) give D1 and D2 for every pixel at
//! once, in time linear in the pixels, and may be kept from crossing depth
//! discontinuities. A penumbra pixel that reaches no umbra (the two hard
//! shadows of a thin occluder need not overlap) or no lit pixel takes a value
//! its caller gives: the share of the hard shadows' points that reach it.

use rayon::prelude::*;

use super::edt::{cuts_between, Columns, Envelope, CUT_RIGHT, UNREACHED};

/// What the two hard shadows say of a pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Zone {
    /// Reached by both hard lights.
    Lit,
    /// Shadowed from one of them.
    Penumbra,
    /// Shadowed from both.
    Umbra,
}

/// V from the distances to the centres of the nearest umbra and lit pixels
/// (either may be infinite: not reached), measured to those zones' borders,
/// half a pixel nearer: (D1 − ½)/(D1 + D2 − 1). Across a straight penumbra
/// n pixels wide the k-th pixel then gets (k − ½)/n, the ramp from the
/// umbra's border to the light's sampled at its centre (D1/(D1 + D2) would
/// stretch the ramp by a pixel).
#[inline]
fn from_distances(d1: f32, d2: f32) -> Option<f32> {
    (d1.is_finite() && d2.is_finite() && d1 + d2 > 1.0).then(|| ((d1 - 0.5) / (d1 + d2 - 1.0)).clamp(0.0, 1.0))
}

/// Light visibility of every pixel of a `width` × `height` image of
/// `zones` (row by row) by exact distance transforms, never measuring a
/// distance between neighbours that `apart` says lie apart (`(x, y)` and
/// the pixel right of or below it); a penumbra pixel that reaches no umbra
/// or no lit pixel takes `unreached(i)` (`i` its index).
///
/// # Panics
///
/// If `zones` does not hold `width` × `height` values.
#[must_use]
pub fn visibility_exact(
    zones: &[Zone],
    width: usize,
    height: usize,
    apart: impl Fn((usize, usize), (usize, usize)) -> bool + Copy + Sync,
    unreached: impl Fn(usize) -> f32 + Sync,
) -> Vec<f32> {
    assert_eq!(zones.len(), width * height, "zones of {width} × {height}");
    visibility_across_cuts(zones, &cuts_between(width, height, apart), width, height, unreached)
}

/// [`visibility_exact`] with the places distances are not carried across
/// given as each pixel's cut bits ([`super::edt::CUT_RIGHT`],
/// [`super::edt::CUT_DOWN`]). The distances along a row are found only in
/// rows that hold a penumbra pixel: the others are umbra and lit alone.
///
/// # Panics
///
/// If `zones` or `cuts` do not hold `width` × `height` values.
#[must_use]
pub fn visibility_across_cuts(
    zones: &[Zone],
    cuts: &[u8],
    width: usize,
    height: usize,
    unreached: impl Fn(usize) -> f32 + Sync,
) -> Vec<f32> {
    assert_eq!(zones.len(), width * height, "zones of {width} × {height}");
    let (to_umbra, to_lit) = rayon::join(
        || Columns::new(|i| zones[i] == Zone::Umbra, cuts, width, height),
        || Columns::new(|i| zones[i] == Zone::Lit, cuts, width, height),
    );
    let mut out = vec![0.0; width * height];
    let scratch = || (Envelope::with_capacity(width), vec![0.0f32; width], vec![0.0f32; width]);
    out.par_chunks_mut(width.max(1)).enumerate().for_each_init(scratch, |(envelope, umbra, lit), (y, row)| {
        let zones = &zones[y * width..(y + 1) * width];
        let plain = |z: Zone| if z == Zone::Umbra { 0.0 } else { 1.0 };
        if !zones.contains(&Zone::Penumbra) {
            row.iter_mut().zip(zones).for_each(|(v, &z)| *v = plain(z));
            return;
        }
        let cut = |x: usize| cuts[y * width + x] & CUT_RIGHT != 0;
        for (columns, line) in [(&to_umbra, &mut *umbra), (&to_lit, &mut *lit)] {
            columns.squared_row(y, line);
            envelope.transform_runs(line, cut);
        }
        let root = |d: f32| if d == UNREACHED { f32::INFINITY } else { d.sqrt() };
        for (x, (v, &z)) in row.iter_mut().zip(zones).enumerate() {
            *v = match z {
                Zone::Penumbra => {
                    from_distances(root(umbra[x]), root(lit[x])).unwrap_or_else(|| unreached(y * width + x))
                }
                z => plain(z),
            };
        }
    });
    out
}

/// Light visibility by the paper's search: at every `n`-th pixel in x and y
/// (and the last row and column), the nearest umbra and lit pixels found by
/// looking in square rings outwards up to `reach` pixels; every other pixel
/// interpolated bilinearly from the four samples round it, where it is
/// penumbra (umbra and lit pixels keep 0 and 1). Rows of samples, and then
/// of pixels, run in parallel. A sample that reaches no
/// umbra or no lit pixel takes `unreached(i)` (`i` its pixel's index).
///
/// # Panics
///
/// If `zones` does not hold `width` × `height` values or `n` is 0.
#[must_use]
pub fn visibility_searched(
    zones: &[Zone],
    width: usize,
    height: usize,
    n: usize,
    reach: usize,
    unreached: impl Fn(usize) -> f32 + Sync,
) -> Vec<f32> {
    assert_eq!(zones.len(), width * height, "zones of {width} × {height}");
    assert!(n > 0, "a sample every n ≥ 1 pixels");
    let zone = |x: usize, y: usize| zones[y * width + x];
    let sample = |x: usize, y: usize| match zone(x, y) {
        Zone::Lit => 1.0,
        Zone::Umbra => 0.0,
        Zone::Penumbra => {
            let (d1, d2) = nearest(zones, width, height, (x, y), reach);
            from_distances(d1, d2).unwrap_or_else(|| unreached(y * width + x))
        }
    };
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let (gx, gy) = (sampled(width, n), sampled(height, n));
    // The samples' rows, then the image's rows, in parallel.
    let samples: Vec<f32> = gy.par_iter().flat_map_iter(|&y| gx.iter().map(move |&x| sample(x, y))).collect();
    let mut out = vec![0.0; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, v) in row.iter_mut().enumerate() {
            *v = match zone(x, y) {
                Zone::Lit => 1.0,
                Zone::Umbra => 0.0,
                Zone::Penumbra => bilinear(&samples, (&gx, &gy), (x, y)),
            };
        }
    });
    out
}

/// Every `n`-th of `len` (> 0) positions, and the last.
fn sampled(len: usize, n: usize) -> Vec<usize> {
    let mut at: Vec<usize> = (0..len).step_by(n).collect();
    if at.last() != Some(&(len - 1)) {
        at.push(len - 1);
    }
    at
}

/// The value at pixel `(x, y)` interpolated bilinearly from `samples` taken
/// at columns `gx` and rows `gy` (increasing, the first 0 and the last the
/// image's last): each of the four samples round the pixel weighted by the
/// pixel's nearness to it along each axis.
#[must_use]
pub fn bilinear(samples: &[f32], (gx, gy): (&[usize], &[usize]), (x, y): (usize, usize)) -> f32 {
    let cell = |g: &[usize], v: usize| {
        let i = g.partition_point(|&s| s <= v).saturating_sub(1).min(g.len().saturating_sub(2));
        let (a, b) = (g[i], g[(i + 1).min(g.len() - 1)]);
        let t = if b > a { (v - a) as f32 / (b - a) as f32 } else { 0.0 };
        (i, (i + 1).min(g.len() - 1), t)
    };
    let ((i0, i1, s), (j0, j1, t)) = (cell(gx, x), cell(gy, y));
    let at = |i: usize, j: usize| samples[j * gx.len() + i];
    (at(i0, j0) * (1.0 - s) + at(i1, j0) * s) * (1.0 - t) + (at(i0, j1) * (1.0 - s) + at(i1, j1) * s) * t
}

/// Distances from `(x, y)` to the nearest umbra and nearest lit pixel within
/// `reach` (infinite where none is), looking in square rings outwards: a
/// ring at Chebyshev distance r holds Euclidean distances r to r·√2, so the
/// search stops once r passes the nearest found.
fn nearest(zones: &[Zone], width: usize, height: usize, (x, y): (usize, usize), reach: usize) -> (f32, f32) {
    let (mut umbra, mut lit) = (f32::INFINITY, f32::INFINITY);
    for r in 1..=reach as i64 {
        if r as f32 > umbra.max(lit) {
            break;
        }
        let (cx, cy) = (x as i64, y as i64);
        let ring = (-r..=r).flat_map(|d| [(cx + d, cy - r), (cx + d, cy + r), (cx - r, cy + d), (cx + r, cy + d)]);
        for (u, v) in ring {
            if u < 0 || v < 0 || u >= width as i64 || v >= height as i64 {
                continue;
            }
            let d = (((u - cx).pow(2) + (v - cy).pow(2)) as f32).sqrt();
            match zones[v as usize * width + u as usize] {
                Zone::Umbra => umbra = umbra.min(d),
                Zone::Lit => lit = lit.min(d),
                Zone::Penumbra => {}
            }
        }
    }
    (umbra, lit)
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};

    use super::*;

    /// Umbra left of `a`, penumbra to `b`, lit beyond, in a `w` × `h` image.
    fn straight(w: usize, h: usize, a: usize, b: usize) -> Vec<Zone> {
        (0..w * h)
            .map(|i| match i % w {
                x if x < a => Zone::Umbra,
                x if x <= b => Zone::Penumbra,
                _ => Zone::Lit,
            })
            .collect()
    }

    /// V is 0 on the umbra, 1 on the lit side, rises strictly across a
    /// straight penumbra, and is D1 / (D1 + D2) there — by the transform and
    /// by the paper's search at every pixel.
    #[test]
    fn visibility_is_0_in_the_umbra_1_in_the_light_and_rises_across_the_penumbra() {
        let (w, h, a, b) = (60, 9, 20, 40);
        let zones = straight(w, h, a, b);
        let exact = visibility_exact(&zones, w, h, |_, _| false, |_| 0.5);
        let searched = visibility_searched(&zones, w, h, 1, 64, |_| 0.5);
        for v in [&exact, &searched] {
            for y in 0..h {
                let row = &v[y * w..(y + 1) * w];
                assert!(row[..a].iter().all(|&v| v == 0.0) && row[b + 1..].iter().all(|&v| v == 1.0));
                assert!(row[a..=b].windows(2).all(|p| p[0] < p[1]), "row {y}: {row:?}");
                let x = 30;
                let (d1, d2) = ((x - (a - 1)) as f32, ((b + 1) - x) as f32);
                assert!((row[x] - d1 / (d1 + d2)).abs() < 1e-6, "{} at x = {x}", row[x]);
            }
        }
    }

    /// Bilinear weights reconstruct a linear ramp exactly from samples every
    /// n pixels (swapped weights, as the paper prints them, would not).
    #[test]
    fn bilinear_interpolation_reconstructs_a_linear_ramp() {
        let (w, h) = (37, 23);
        for n in [1, 3, 5, 10] {
            let (gx, gy) = (sampled(w, n), sampled(h, n));
            let f = |x: usize, y: usize| 0.25 + 0.013 * x as f32 - 0.021 * y as f32;
            let samples: Vec<f32> = gy.iter().flat_map(|&y| gx.iter().map(move |&x| f(x, y))).collect();
            for y in 0..h {
                for x in 0..w {
                    let v = bilinear(&samples, (&gx, &gy), (x, y));
                    assert!((v - f(x, y)).abs() < 1e-5, "n = {n}, ({x}, {y}): {v} against {}", f(x, y));
                }
            }
        }
    }

    /// The paper's search at every pixel finds the same distances as the
    /// transforms, on random zones.
    #[test]
    fn the_search_at_every_pixel_agrees_with_the_transforms() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        for _ in 0..30 {
            let (w, h) = (rng.gen_range(2..30), rng.gen_range(2..30));
            let zones: Vec<Zone> = (0..w * h)
                .map(|_| [Zone::Lit, Zone::Penumbra, Zone::Penumbra, Zone::Umbra][rng.gen_range(0..4)])
                .collect();
            let exact = visibility_exact(&zones, w, h, |_, _| false, |_| 0.5);
            let searched = visibility_searched(&zones, w, h, 1, 64, |_| 0.5);
            for (i, (a, b)) in exact.iter().zip(&searched).enumerate() {
                assert!((a - b).abs() < 1e-5, "pixel {i}: transform {a}, search {b}");
            }
        }
    }

    /// A depth discontinuity keeps the distances apart: a penumbra on a floor
    /// behind a plate does not measure to the plate's umbra, so the floor's
    /// pixels next to the plate take their visibility from the floor alone.
    #[test]
    fn distances_do_not_cross_a_depth_discontinuity() {
        let (w, h) = (30, 10);
        // Columns 0..10: a plate in front, all umbra; 10..: the floor,
        // penumbra to column 20, lit beyond.
        let zones: Vec<Zone> = (0..w * h)
            .map(|i| match i % w {
                x if x < 10 => Zone::Umbra,
                x if x <= 20 => Zone::Penumbra,
                _ => Zone::Lit,
            })
            .collect();
        let plate_edge = |a: (usize, usize), b: (usize, usize)| a.0 == 9 && b.0 == 10;
        let aware = visibility_exact(&zones, w, h, plate_edge, |_| 0.5);
        let naive = visibility_exact(&zones, w, h, |_, _| false, |_| 0.5);
        assert!(naive[12] < 0.3, "without the cut the plate's umbra darkens the floor: {}", naive[12]);
        assert_eq!(aware[12], 0.5, "with it, no umbra on the floor: half lit");
    }
}
