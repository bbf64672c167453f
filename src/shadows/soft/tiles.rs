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
//! lit tiles of the soft-shadow example at 640 × 360 (749 are lit or umbra at
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

/// A map's nearest and farthest depth over square blocks of texels.
#[derive(Debug, Clone)]
pub struct DepthBounds {
    block: u32,
    blocks: u32,
    /// Per block: the smallest and largest reversed depth (the farthest and
    /// the nearest surface).
    lo: Vec<f32>,
    hi: Vec<f32>,
}

impl DepthBounds {
    /// The bounds of `map` over blocks of `block` × `block` texels.
    ///
    /// # Panics
    ///
    /// If `block` is 0.
    #[must_use]
    pub fn of(map: &DepthMap, block: u32) -> DepthBounds {
        assert!(block > 0, "a block holds texels");
        let res = map.resolution();
        let blocks = res.div_ceil(block);
        let (mut lo, mut hi) =
            (vec![f32::INFINITY; (blocks * blocks) as usize], vec![0f32; (blocks * blocks) as usize]);
        for y in 0..res {
            for x in 0..res {
                let (b, d) = (((y / block) * blocks + x / block) as usize, map.texel_depth(x, y));
                (lo[b], hi[b]) = (lo[b].min(d), hi[b].max(d));
            }
        }
        DepthBounds { block, blocks, lo, hi }
    }

    /// The smallest and largest reversed depth over texels `x0..=x1` ×
    /// `y0..=y1` (a superset: the blocks holding them).
    #[must_use]
    pub fn range(&self, (x0, y0): (u32, u32), (x1, y1): (u32, u32)) -> (f32, f32) {
        let (mut lo, mut hi) = (f32::INFINITY, 0f32);
        for by in y0 / self.block..=(y1 / self.block).min(self.blocks - 1) {
            for bx in x0 / self.block..=(x1 / self.block).min(self.blocks - 1) {
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
