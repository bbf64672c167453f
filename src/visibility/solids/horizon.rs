//! Occupants that lie wholly beyond the visible surface, left out of the
//! booleans (beyond seed 003, whose §5.2 combines the intervals of every
//! primitive occupying the pixel).
//!
//! A primitive's extent on the screen says nothing of its depth: a printer
//! part's holes and ribs behind its front face occupy the same pixels as the
//! face, and most of a pixel's occupants lie behind its surface (three in four
//! on a printer carriage of hundreds of primitives). The scanline walk guesses a [`Horizon`] a little beyond
//! the surface of the pixel before; occupants whose interval at the pixel
//! starts at or beyond it are read as missed, and the booleans — union
//! merges, cuts, clips — run over the rest. The answer stands when nothing
//! was left out, or when it lies short of the horizon by more than any
//! [`TIE`] move ([`Horizon::clears`]); otherwise the pixel is done again with
//! every occupant.
//!
//! Why the answer is the whole tree's. Let `T` be the horizon. A left-out
//! occupant's interval lies at or beyond `T`; the booleans
//! ([`crate::csg`]) compare its ends with others' unmoved (union,
//! intersection) or moved nearer by one [`TIE`] move (a difference's cutter,
//! from `t` to `below(t)`). So a union gains from it spans beyond `T` only;
//! an intersection with it lies beyond `T`, where read as missed it is
//! empty; a difference by it removes nothing nearer than `below(T)`. Short
//! of `below(T)` the set inside the solid — each of its ends the same end of
//! the same occupant — is the same whether the left-out occupants are read
//! or not, and so is its first end beyond the near plane, when that lies
//! there. The block spreading ([`super::block`]) then checks the answer
//! against every occupant, as for an answer found with all of them.

use crate::csg::TIE;

/// How far along a pixel's ray the booleans read occupants: those whose
/// interval starts at or beyond it are left out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Horizon(f32);

/// How far beyond the last surface found the guess lies, as a factor of its
/// distance (besides twice its rise from the pixel before). Measured on the
/// corpus: a wider horizon leaves fewer occupants out, a narrower one misses
/// the next surface more often.
const REACH: f32 = 1.002;

/// The fewest occupants for which the walk guesses a horizon: with fewer
/// there is little to leave out, and a miss costs a second pass.
const MANY: usize = 4;

impl Horizon {
    /// No occupant left out.
    pub const EVERYWHERE: Horizon = Horizon(f32::INFINITY);

    /// The walk's guess for a pixel of `occupants` after one whose surface
    /// lay at `t`, `rise` beyond the pixel's before it: a little beyond it,
    /// or everywhere (no surface yet, one at or behind the eye, or few
    /// occupants).
    #[must_use]
    pub fn guess(surface: Option<(f32, f32)>, occupants: usize) -> Horizon {
        match surface {
            Some((t, rise)) if t > 0.0 && occupants >= MANY => Horizon(t * REACH + 2.0 * rise.max(0.0)),
            _ => Self::EVERYWHERE,
        }
    }

    /// Whether an occupant whose interval starts at `enter` is left out.
    #[inline(always)]
    #[must_use]
    pub fn hides(self, enter: f32) -> bool {
        enter >= self.0
    }

    /// Whether an answer at `t`, found with occupants beyond the horizon left
    /// out, is the answer with all of them (see the module's doc): short of
    /// it by eight [`TIE`] moves.
    #[inline]
    #[must_use]
    pub fn clears(self, t: f32) -> bool {
        self.0 == f32::INFINITY || t < self.0 - 8.0 * TIE * self.0.abs().max(1.0)
    }
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;

    use proptest::prelude::*;

    use super::*;
    use crate::csg::{random_tree, ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Shape};
    use crate::csg::{CsgCaster, Hit, Interval, SpanScratch};

    const N: usize = 8;

    /// The horizon the property test reads at.
    const AT: f32 = 4.0;

    /// A span end: mostly a whole number (so that ends meet the horizon and
    /// each other), else the horizon less a few [`TIE`] moves, the margin
    /// [`Horizon::clears`] keeps included.
    fn end() -> impl Strategy<Value = f32> {
        let moves = [0.5f32, 1.0, 2.0, 7.0, 8.0, 9.0, 30.0];
        prop_oneof![
            2 => (0i32..8).prop_map(|k| k as f32),
            1 => prop::sample::select(moves.to_vec()).prop_map(|m| AT - m * TIE * AT),
        ]
    }

    /// The first crossing beyond `t_min` of `tree` over the spans `spans`
    /// (`None` a miss), the occupants `hidden` says left out, and whether
    /// one was.
    fn first(tree: &CsgTree, spans: &[Option<Interval>], hidden: impl Fn(&Interval) -> bool) -> (Option<Hit>, bool) {
        let primitives = (0..N)
            .map(|_| Primitive {
                shape: Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
                transform: glam::Affine3A::IDENTITY,
                color: None,
                source: 0..0,
            })
            .collect();
        let caster = CsgCaster::new(&CsgSolid { primitives, tree: Some(tree.clone()) });
        let hid = Cell::new(false);
        let read = |i: usize| {
            let s = spans[i]?;
            hid.set(hid.get() | hidden(&s));
            (!hidden(&s)).then_some(s)
        };
        (caster.first_hit_in_by(tree, &read, 0.5, &mut SpanScratch::default()), hid.get())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2048))]

        /// With the occupants beyond the horizon left out, an answer kept
        /// (nothing left out, or one that clears the horizon) is the one all
        /// occupants give: the same end of the same occupant.
        #[test]
        fn an_answer_that_clears_the_horizon_is_the_whole_trees(
            tree in random_tree(N, 3),
            ends in prop::collection::vec(prop::option::of((end(), end())), N),
        ) {
            let spans: Vec<Option<Interval>> = ends
                .iter()
                .enumerate()
                .map(|(i, e)| {
                    let (a, b) = (*e)?;
                    let (lo, hi) = (a.min(b), a.max(b));
                    (lo < hi).then(|| Interval { enter: Hit::new(lo, i, 0), exit: Hit::new(hi, i, 1) })
                })
                .collect();
            let horizon = Horizon(AT);
            let (all, _) = first(&tree, &spans, |_| false);
            let (short, hid) = first(&tree, &spans, |s| horizon.hides(s.enter.t));
            if !hid || short.is_some_and(|h| horizon.clears(h.t)) {
                prop_assert_eq!(short, all);
            }
        }
    }

    #[test]
    fn a_guess_lies_beyond_the_surface_and_its_rise() {
        let h = Horizon::guess(Some((100.0, 0.5)), MANY);
        assert!(!h.hides(100.0) && !h.hides(101.0) && h.hides(101.3));
        assert!(h.clears(100.9) && !h.clears(101.195));
        assert_eq!(Horizon::guess(Some((100.0, 0.5)), MANY - 1), Horizon::EVERYWHERE);
        assert_eq!(Horizon::guess(None, 100), Horizon::EVERYWHERE);
        assert_eq!(Horizon::guess(Some((-1.0, 0.0)), 100), Horizon::EVERYWHERE);
        assert!(Horizon::EVERYWHERE.clears(f32::MAX) && !Horizon::EVERYWHERE.hides(f32::MAX));
    }
}
