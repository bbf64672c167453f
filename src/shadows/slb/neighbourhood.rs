//! What the 3 × 3 texels round each texel of a silhouette-line buffer hold,
//! so that most points of the eye pass are decided by one look — the
//! depth test first, the lines only where it cannot decide (the conservative
//! pre-pass of irregular and alias-free shadow maps: Aila & Laine 2004,
//! Tokuyoshi & Mizokuchi 2018).
//!
//! A point whose pixel's footprint reaches at most one texel from its own
//! lies within these 3 × 3 texels, and so do all its footprint's points:
//! - where no silhouette line and no step of a CSG solid lies in them, the
//!   map decides it as a plain map lookup would (the lines cannot change it);
//! - where every surface over them (the map's depths, every line's and
//!   layer's depth plane at the texel's corners) lies no nearer the light than
//!   the receiver's smallest limit, nothing can hide it: lit.
//!
//! Only the rest take the exact line test. On the 1920×1080 demo with its
//! 1024² buffers, these two looks decide most points, which leaves the
//! line test to those beside a visible shadow edge (`kage-bench slb`).

use rayon::prelude::*;

use super::buffer::{ranked, ranks, SilhouetteLineBuffer};
use super::line::TexelDepth;
use crate::shadows::map::DepthMap;
use crate::visibility::Workers;

/// Per texel, what its 3 × 3 neighbourhood holds.
#[derive(Debug, Clone, Default)]
pub struct Neighbourhood {
    /// One bit per texel: a silhouette line or a solid's step lies in the
    /// neighbourhood (a busy texel).
    busy: Vec<u64>,
    /// Busy texels before each word of `busy`.
    rank: Vec<u32>,
    /// Per busy texel, in order: the nearest (largest reversed) depth of any
    /// surface over its neighbourhood.
    nearest: Vec<f32>,
}

impl Neighbourhood {
    /// The neighbourhoods of every texel of `map`, whose lines `slb` holds
    /// and whose solids' steps `steps` marks (one bit per texel; empty:
    /// none). Only the busy texels' depths are kept: a few times the edge
    /// texels, so the build costs the lines', not the map's, size.
    #[must_use]
    pub fn build(map: &DepthMap, slb: &SilhouetteLineBuffer, steps: &[u64], workers: Workers) -> Neighbourhood {
        let n = map.resolution() as usize;
        let mut busy = vec![0u64; (n * n).div_ceil(64)];
        let mut mark = |t: usize| {
            let (x, y) = (t % n, t / n);
            for j in y.saturating_sub(1)..(y + 2).min(n) {
                for i in x.saturating_sub(1)..(x + 2).min(n) {
                    let k = j * n + i;
                    busy[k / 64] |= 1 << (k % 64);
                }
            }
        };
        for (w, &word) in slb.edge_words().iter().enumerate() {
            set_bits(word).for_each(|b| mark(w * 64 + b));
        }
        for (w, &word) in steps.iter().enumerate() {
            set_bits(word).for_each(|b| mark(w * 64 + b));
        }
        let rank = ranks(&busy);
        // A texel's own nearest surface: the map's, or over an edge texel
        // every line's and layer's plane at the texel's corners.
        let own = |x: usize, y: usize| {
            let z = map.texel_depth(x as u32, y as u32);
            slb.entry(x as u32, y as u32).map_or(z, |entry| {
                let planes = entry.lines.iter().map(|l| l.depth).chain(entry.layers.iter().map(|l| l.depth));
                planes.map(|d| corner_max(&d)).fold(z, f32::max)
            })
        };
        let around = |t: usize| {
            let (x, y) = (t % n, t / n);
            let rows = y.saturating_sub(1)..(y + 2).min(n);
            rows.flat_map(|j| (x.saturating_sub(1)..(x + 2).min(n)).map(move |i| (i, j)))
                .map(|(i, j)| own(i, j))
                .fold(0.0, f32::max)
        };
        let word = |(w, &word): (usize, &u64)| set_bits(word).map(move |b| around(w * 64 + b));
        let nearest = match workers {
            Workers::All => busy.par_iter().enumerate().flat_map_iter(word).collect(),
            Workers::One => busy.iter().enumerate().flat_map(word).collect(),
        };
        Neighbourhood { busy, rank, nearest }
    }

    /// Whether a line or a solid's step lies within a texel of texel `t`
    /// (its index, row by row).
    #[inline]
    #[must_use]
    pub fn busy(&self, t: usize) -> bool {
        self.busy.get(t / 64).is_some_and(|w| w >> (t % 64) & 1 == 1)
    }

    /// The nearest reversed depth of any surface within a texel of texel
    /// `t`, a busy texel (others: infinite).
    #[inline]
    #[must_use]
    pub fn nearest(&self, t: usize) -> f32 {
        ranked(&self.busy, &self.rank, t).map_or(f32::INFINITY, |i| self.nearest[i])
    }

    /// Bytes held.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.busy.len() * 8 + self.rank.len() * 4 + self.nearest.len() * 4
    }
}

/// The set bits of `word`, lowest first.
fn set_bits(word: u64) -> impl Iterator<Item = usize> {
    let mut rest = word;
    std::iter::from_fn(move || {
        (rest != 0).then(|| {
            let b = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            b
        })
    })
}

/// The largest value of a depth plane over its texel (at one of its corners).
fn corner_max(d: &TexelDepth) -> f32 {
    d.c + d.dx.max(0.0) + d.dy.max(0.0)
}
