//! The silhouette-line buffer of seed 000 (Yamaguchi & Ikedo, "Shadow
//! Antialiasing with Virtual Projection Space", IPSJ 2008): exact shadow edges
//! inside each shadow-map texel.
//!
//! One file per stage: `light` (the casters' triangles as the light sees
//! them), `solid` (a CSG solid's outline, traced by rays, as triangles),
//! `walk` (the supercover walk of an edge through the texels), `line` (one
//! line's record and its reconstruction), `buffer` (the light pass: records,
//! shared- and hidden-line removal, the compact store), `neighbourhood` (what
//! the texels round each texel hold, deciding most points of the eye pass at
//! one look), `region` (the eye pass inside one edge texel) and `term` (the
//! light's shadow term).

pub mod buffer;
pub mod light;
pub mod line;
pub mod neighbourhood;
pub mod region;
pub mod solid;
pub mod term;
pub mod walk;

pub use buffer::SilhouetteLineBuffer;
pub use term::SlbMap;
