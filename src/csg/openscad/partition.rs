//! A region of the plane cut into convex pieces, so that what is extruded or
//! revolved from it is a union of seed 003's convex primitives.
//!
//! The region (holes included) is triangulated by Manifold's ear clipper,
//! then triangles are merged across their shared sides while the merged piece
//! stays convex (Hertel and Mehlhorn: removing every diagonal that leaves both
//! its ends convex gives at most four times the fewest pieces possible).
//! Pieces are counter-clockwise and share whole sides with their
//! neighbours, so their union is the region to the bit.

use std::collections::HashMap;

use glam::DVec2;
use manifold_rust::linalg::Vec2 as MVec2;
use manifold_rust::polygon::triangulate;

use super::flat::Region;

/// The sine of the largest angle a corner may turn the wrong way by and
/// still count as convex: collinear corners from rounding.
const STRAIGHT: f64 = 1e-9;

/// The region's convex pieces, each counter-clockwise (corners as points).
#[must_use]
pub(crate) fn convex_pieces(region: &Region) -> Vec<Vec<DVec2>> {
    let points: Vec<DVec2> = region.points().collect();
    let polygons: Vec<Vec<MVec2>> =
        region.contours().iter().map(|c| c.iter().map(|p| MVec2::new(p.x, p.y)).collect()).collect();
    let triangles: Vec<Vec<usize>> = triangulate(&polygons, -1.0, true)
        .into_iter()
        .map(|t| vec![t.x as usize, t.y as usize, t.z as usize])
        .filter(|t| cross(points[t[0]], points[t[1]], points[t[2]]) > 0.0)
        .collect();
    merge(triangles, &points)
}

/// `(b − a) × (c − b)`: positive where `a → b → c` turns left.
fn cross(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - b)
}

/// Hertel–Mehlhorn: merges pieces (corner indices, counter-clockwise) across
/// shared sides while both ends of the side stay convex.
fn merge(mut pieces: Vec<Vec<usize>>, points: &[DVec2]) -> Vec<Vec<DVec2>> {
    let mut alive = vec![true; pieces.len()];
    // Each directed side (a, b) → the piece that has it.
    let mut owner: HashMap<(usize, usize), usize> = HashMap::new();
    for (k, p) in pieces.iter().enumerate() {
        for i in 0..p.len() {
            owner.insert((p[i], p[(i + 1) % p.len()]), k);
        }
    }
    let mut changed = true;
    while changed {
        changed = false;
        for k in 0..pieces.len() {
            if !alive[k] {
                continue;
            }
            let mut i = 0;
            while i < pieces[k].len() {
                let p = &pieces[k];
                let (a, b) = (p[i], p[(i + 1) % p.len()]);
                let Some(&other) = owner.get(&(b, a)) else {
                    i += 1;
                    continue;
                };
                if other == k || !alive[other] {
                    i += 1;
                    continue;
                }
                let Some(joined) = join(&pieces[k], &pieces[other], a, b) else {
                    i += 1;
                    continue;
                };
                if !convex_at(&joined, points, a) || !convex_at(&joined, points, b) {
                    i += 1;
                    continue;
                }
                for j in 0..joined.len() {
                    owner.insert((joined[j], joined[(j + 1) % joined.len()]), k);
                }
                owner.remove(&(a, b));
                owner.remove(&(b, a));
                pieces[k] = joined;
                pieces[other].clear();
                alive[other] = false;
                changed = true;
                i = 0;
            }
        }
    }
    pieces
        .into_iter()
        .zip(alive)
        .filter(|(p, alive)| *alive && p.len() >= 3)
        .map(|(p, _)| p.into_iter().map(|i| points[i]).collect())
        .collect()
}

/// Piece `p` (which has side `a → b`) joined with `q` (which has `b → a`):
/// `p`'s corners from `b` round to `a`, then `q`'s between `a` and `b`.
fn join(p: &[usize], q: &[usize], a: usize, b: usize) -> Option<Vec<usize>> {
    let ib = p.iter().position(|&v| v == b)?;
    let ia = q.iter().position(|&v| v == a)?;
    let mut out: Vec<usize> = (0..p.len()).map(|k| p[(ib + k) % p.len()]).collect();
    // `out` runs b ... a; `q` runs b → a, then on round to b: its corners
    // after a and before b close the piece.
    out.extend((1..q.len() - 1).map(|k| q[(ia + k) % q.len()]));
    // Repeated corners would mean the two touch elsewhere too.
    let mut seen = out.clone();
    seen.sort_unstable();
    seen.dedup();
    (seen.len() == out.len()).then_some(out)
}

/// Whether the corner at point index `v` of `piece` turns left (or runs
/// straight, within [`STRAIGHT`]).
fn convex_at(piece: &[usize], points: &[DVec2], v: usize) -> bool {
    let Some(i) = piece.iter().position(|&x| x == v) else { return false };
    let n = piece.len();
    let (a, b, c) = (points[piece[(i + n - 1) % n]], points[v], points[piece[(i + 1) % n]]);
    cross(a, b, c) >= -STRAIGHT * (b - a).length() * (c - b).length()
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::super::flat::signed_area;
    use super::*;

    /// Whether `p` lies inside the convex counter-clockwise `piece`
    /// (strictly, by `eps`).
    fn strictly_inside(piece: &[DVec2], p: DVec2, eps: f64) -> bool {
        (0..piece.len()).all(|i| (piece[(i + 1) % piece.len()] - piece[i]).perp_dot(p - piece[i]) > eps)
    }

    /// Whether `p` lies inside the region by the even-odd rule of its contours.
    fn in_region(region: &Region, p: DVec2) -> bool {
        let mut inside = false;
        for c in region.contours() {
            for i in 0..c.len() {
                let (a, b) = (c[i], c[(i + 1) % c.len()]);
                if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                    inside = !inside;
                }
            }
        }
        inside
    }

    fn check(region: &Region) {
        let pieces = convex_pieces(region);
        let total: f64 = pieces.iter().map(|p| signed_area(p)).sum();
        assert!((total - region.area()).abs() < 1e-6 * region.area().max(1.0), "{total} vs {}", region.area());
        for p in &pieces {
            let n = p.len();
            for i in 0..n {
                assert!(cross(p[(i + n - 1) % n], p[i], p[(i + 1) % n]) >= -1e-6, "not convex: {p:?}");
            }
        }
        // Every point of a grid is in the region exactly when a piece
        // holds it (points near a side are skipped).
        let (lo, hi) = region.bounds().unwrap();
        for i in 0..40 {
            for j in 0..40 {
                let q = lo + (hi - lo) * DVec2::new((i as f64 + 0.37) / 40.0, (j as f64 + 0.61) / 40.0);
                let holders = pieces.iter().filter(|p| strictly_inside(p, q, 1e-7)).count();
                let near_side = pieces.iter().any(|p| !strictly_inside(p, q, 1e-7) && strictly_inside(p, q, -1e-3));
                if !near_side {
                    assert_eq!(holders, usize::from(in_region(region, q)), "at {q}");
                }
            }
        }
    }

    #[test]
    fn a_square_with_a_hole_and_an_l_are_cut_into_convex_pieces() {
        check(&Region::square(DVec2::splat(10.0), true).difference(&[Region::square(DVec2::splat(4.0), true)]));
        let l = Region::even_odd(&[vec![
            DVec2::ZERO,
            DVec2::new(6.0, 0.0),
            DVec2::new(6.0, 2.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(2.0, 6.0),
            DVec2::new(0.0, 6.0),
        ]]);
        check(&l);
        assert_eq!(convex_pieces(&l).len(), 2);
        // A convex region is one piece.
        assert_eq!(convex_pieces(&Region::circle(3.0, 30)).len(), 1);
    }

    proptest! {
        /// Random star polygons (not convex, not simple where rays cross)
        /// less a random disc: the pieces tile the region.
        #[test]
        fn pieces_tile_random_regions(radii in prop::collection::vec(1.0f64..5.0, 5..24), hole in 0.0f64..1.5) {
            let n = radii.len();
            let star: Vec<DVec2> = radii
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    let a = std::f64::consts::TAU * i as f64 / n as f64;
                    DVec2::new(a.cos(), a.sin()) * *r
                })
                .collect();
            let region = Region::even_odd(&[star]).difference(&[Region::circle(hole, 12)]);
            if !region.is_empty() {
                check(&region);
            }
        }
    }
}
