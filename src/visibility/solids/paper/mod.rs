//! Seed 003 as the paper states it, kept beside the default walk for
//! measuring it: the pattern matrix (the solid expanded into a sum of
//! products, §5.2.1) and the reuse of a pixel's answer at the next pixel
//! (§5.2.2).

pub mod coherence;
pub mod pattern;
