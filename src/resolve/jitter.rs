//! Antialiasing by jittered sub-pixel passes: the accumulation buffer of seed 002 §4.
//!
//! The paper antialiases its traced reflections by rendering several item buffers,
//! each with the image shifted by a fraction of a pixel, tracing each and averaging
//! (Fig. 8): every pass samples a different point of each pixel, so small and
//! needle-like polygons are sampled in proportion to their area. kage jitters the
//! whole frame — visibility, shading passes and traced term — so the average is the
//! classic accumulation-buffer antialiasing of everything at once.

use glam::Vec2;

use crate::sampling::radical_inverse;

/// How a frame is antialiased.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Antialias {
    /// One sample at each pixel centre.
    #[default]
    None,
    /// `n` frames with sub-pixel jitter, averaged (n = 1 is one centred frame).
    Jitter(u32),
    /// One frame, then seed 004's edge pass ([`super::edges`]).
    Edge(super::edges::EdgeMode),
}

/// Most jittered passes one frame may take.
pub const MAX_JITTER_SAMPLES: u32 = 1024;

impl Antialias {
    /// Sub-pixel offsets of the passes, in pixels within (−0.5, 0.5)²: one centred
    /// pass, or the first `n` points of the Halton (2, 3) sequence, which fill the
    /// pixel evenly for every prefix length.
    #[must_use]
    pub fn offsets(self) -> Vec<Vec2> {
        match self {
            Antialias::None | Antialias::Edge(_) | Antialias::Jitter(0 | 1) => vec![Vec2::ZERO],
            Antialias::Jitter(n) => (1..=n.min(MAX_JITTER_SAMPLES))
                .map(|i| Vec2::new(radical_inverse(i, 2), radical_inverse(i, 3)) - 0.5)
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_stay_inside_the_pixel_and_average_near_its_centre() {
        assert_eq!(Antialias::None.offsets(), vec![Vec2::ZERO]);
        for n in [2, 4, 16, 64] {
            let o = Antialias::Jitter(n).offsets();
            assert_eq!(o.len(), n as usize);
            assert!(o.iter().all(|p| p.abs().max_element() < 0.5));
            let mean = o.iter().sum::<Vec2>() / n as f32;
            assert!(mean.abs().max_element() < 1.0 / n as f32 + 0.02, "n {n}: mean {mean}");
        }
    }

    #[test]
    fn offsets_fill_each_quarter_of_the_pixel_evenly() {
        for n in [16, 64, 256] {
            let o = Antialias::Jitter(n).offsets();
            for q in 0..4 {
                let inside = o.iter().filter(|p| (p.x >= 0.0) == (q & 1 == 1) && (p.y >= 0.0) == (q & 2 == 2)).count();
                assert!(inside.abs_diff(n as usize / 4) <= (n as usize / 64).max(1), "n {n}, quarter {q}: {inside}");
            }
        }
    }
}
