//! Screen tiles classified lit, umbra or mixed from the hard maps' depth
//! bounds: a tile whose points lie nearer the light than everything its
//! texels hold in every map is lit, one whose points lie behind everything
//! there in every map is umbra, any other is mixed and would take the
//! per-pixel test.
//!
//! The test is conservative: a tile called lit or umbra has every point so
//! by the per-pixel lookup (`tiles_called_lit_or_umbra_are_so_at_every_pixel`
//! in `tests/soft_shadows.rs` holds it to that on frames of the soft-shadow
//! example and the demo). With 8 × 8-texel blocks it decides 659 of the 840
//! tiles of the soft-shadow example at 640 × 360 (749 are lit or umbra at
//! every pixel) and 500 of the demo's 760 (636): the bias keeps a surface's
//! own texels from shadowing it across most of a tile.
//!
//! Here a tile's texels and depth limits come from its points' own
//! projections, the work of a lookup: it measures what the bounds decide.
//! The two-map term classifies every pixel eight lanes at a time instead;
//! to save lookups the bounds must come from the tile's corners in world
//! space (eight projections a map instead of 256) and a decided tile must
//! still send its pixels facing away from the light to the umbra.

use glam::Vec3;
use rayon::prelude::*;
use wide::f32x8;

use crate::scene::ShadowSettings;
use crate::shadows::DepthMap;

/// What a tile's points are in every hard map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TileClass {
    /// Lit in every map.
    Lit,
    /// Shadowed in every map.
    Umbra,
    /// Undecided by the bounds.
    Mixed,
}

/// Texels along a side of the blocks [`DepthBounds`] keeps.
pub const BLOCK: usize = 8;

/// A map's nearest and farthest depth over square blocks of texels.
#[derive(Debug, Clone)]
pub struct DepthBounds {
    blocks: u32,
    /// Per block: the smallest and largest reversed depth (the farthest and
    /// the nearest surface).
    lo: Vec<f32>,
    hi: Vec<f32>,
}

impl DepthBounds {
    /// The bounds of `map` over blocks of [`BLOCK`] × [`BLOCK`] texels:
    /// eight texels of a row at a time as one vector, folded down the
    /// block's rows, one row of blocks per task.
    #[must_use]
    pub fn of(map: &DepthMap) -> DepthBounds {
        let res = map.resolution() as usize;
        let blocks = res.div_ceil(BLOCK);
        let (mut lo, mut hi) = (vec![f32::INFINITY; blocks * blocks], vec![0f32; blocks * blocks]);
        let rows = map.depths().par_chunks(res * BLOCK);
        rows.zip(lo.par_chunks_mut(blocks).zip(hi.par_chunks_mut(blocks))).for_each(|(texels, (lo, hi))| {
            let (mut near, mut far) = (vec![f32x8::ZERO; blocks], vec![f32x8::splat(f32::INFINITY); blocks]);
            for row in texels.chunks(res) {
                let runs = row.chunks_exact(BLOCK);
                let rest = runs.remainder();
                for ((run, near), far) in runs.zip(near.iter_mut()).zip(far.iter_mut()) {
                    let run = f32x8::new(run.try_into().expect("eight texels"));
                    (*near, *far) = (near.max(run), far.min(run));
                }
                // A row not a whole number of blocks: its last texels one by one.
                if let (false, Some(near), Some(far)) = (rest.is_empty(), near.last_mut(), far.last_mut()) {
                    let mut padded = [rest[0]; BLOCK];
                    padded[..rest.len()].copy_from_slice(rest);
                    let run = f32x8::new(padded);
                    (*near, *far) = (near.max(run), far.min(run));
                }
            }
            for (b, (near, far)) in near.iter().zip(&far).enumerate() {
                hi[b] = near.to_array().into_iter().fold(0.0, f32::max);
                lo[b] = far.to_array().into_iter().fold(f32::INFINITY, f32::min);
            }
        });
        DepthBounds { blocks: blocks as u32, lo, hi }
    }

    /// The smallest and largest reversed depth over texels `x0..=x1` ×
    /// `y0..=y1` (a superset: the blocks holding them).
    #[must_use]
    pub fn range(&self, (x0, y0): (u32, u32), (x1, y1): (u32, u32)) -> (f32, f32) {
        let (mut lo, mut hi) = (f32::INFINITY, 0f32);
        let block = BLOCK as u32;
        for by in y0 / block..=(y1 / block).min(self.blocks - 1) {
            for bx in x0 / block..=(x1 / block).min(self.blocks - 1) {
                let b = (by * self.blocks + bx) as usize;
                (lo, hi) = (lo.min(self.lo[b]), hi.max(self.hi[b]));
            }
        }
        (lo, hi)
    }
}

/// The class of a tile whose points (position, N·L) are `points`, in the
/// hard maps `maps` read with `settings` (one tap: lit where the texel's
/// reversed depth is at most the point's limit).
#[must_use]
pub fn classify_tile(
    maps: &[(&DepthMap, &DepthBounds)],
    points: &[(Vec3, f32)],
    settings: &ShadowSettings,
) -> TileClass {
    let (mut lit, mut umbra) = (true, true);
    for (map, bounds) in maps {
        let last = map.resolution().saturating_sub(1) as f32;
        let (mut lo, mut hi) = ((u32::MAX, u32::MAX), (0, 0));
        let (mut z_lo, mut z_hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for &(p, cos) in points {
            // Outside the map (or at the light): lit.
            let Some(at) = map.locate(p, cos, settings, 1.0) else {
                umbra = false;
                continue;
            };
            let (x, y) = (at.u.floor().clamp(0.0, last) as u32, at.v.floor().clamp(0.0, last) as u32);
            (lo, hi) = ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)));
            (z_lo, z_hi) = (z_lo.min(at.z_limit), z_hi.max(at.z_limit));
        }
        if z_lo > z_hi {
            continue; // every point outside this map
        }
        let (nearest_lo, nearest_hi) = bounds.range(lo, hi);
        // Lit: no texel nearer than any point's limit.
        lit &= nearest_hi <= z_lo;
        // Umbra: every texel nearer than every point's limit.
        umbra &= nearest_lo > z_hi;
        if !lit && !umbra {
            return TileClass::Mixed;
        }
    }
    match (lit, umbra) {
        (true, false) => TileClass::Lit,
        (false, true) => TileClass::Umbra,
        // No points, or every point outside every map: nothing shadows them.
        (true, true) => TileClass::Lit,
        (false, false) => TileClass::Mixed,
    }
}

/// The class of every point within the box `lo`..`hi` in the hard maps
/// `maps` read with `settings` (one tap), from the box's corners: no point
/// is projected. Points outside a map are lit in it.
#[must_use]
pub fn classify_box(maps: &[(&DepthMap, &DepthBounds)], lo: Vec3, hi: Vec3, settings: &ShadowSettings) -> TileClass {
    let (mut lit, mut umbra) = (true, true);
    for (map, depth) in maps {
        let Some(b) = map.box_bounds(lo, hi, settings) else { return TileClass::Mixed };
        let (nearest_lo, nearest_hi) = depth.range(b.texels.0, b.texels.1);
        lit &= nearest_hi <= b.limit_lo;
        umbra &= b.inside && b.limit_hi.is_some_and(|hi| nearest_lo > hi);
        if !lit && !umbra {
            return TileClass::Mixed;
        }
    }
    match (lit, umbra) {
        (true, false) => TileClass::Lit,
        (false, true) => TileClass::Umbra,
        _ => TileClass::Mixed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shadows::ShadowTerm;

    /// Every block's bounds are its texels' least and greatest depth, for a
    /// map whose side is not a whole number of blocks.
    #[test]
    fn block_bounds_are_their_texels_extremes() {
        let mut scene = crate::scene::demo::demo_scene().expect("the demo loads");
        let light = &mut scene.lights[0];
        (light.shadow.resolution, light.shadow.by_need) = (100, false);
        let term = ShadowTerm::build(&scene, &scene.lights[0]);
        let (map, _) = term.one_tap_map().expect("the demo's first light has one plain map");
        assert_eq!(map.resolution(), 100);
        let bounds = DepthBounds::of(map);
        let mut nonzero = 0;
        for by in 0..13u32 {
            for bx in 0..13u32 {
                let texels =
                    (by * 8..(by * 8 + 8).min(100)).flat_map(|y| (bx * 8..(bx * 8 + 8).min(100)).map(move |x| (x, y)));
                let depths: Vec<f32> = texels.map(|(x, y)| map.texel_depth(x, y)).collect();
                let (lo, hi) = bounds.range((bx * 8, by * 8), (bx * 8, by * 8));
                assert_eq!(lo, depths.iter().copied().fold(f32::INFINITY, f32::min), "block ({bx}, {by})");
                assert_eq!(hi, depths.iter().copied().fold(0.0, f32::max), "block ({bx}, {by})");
                nonzero += usize::from(hi > 0.0);
            }
        }
        assert!(nonzero > 10, "the map holds the demo's casters: {nonzero} blocks");
    }
}
