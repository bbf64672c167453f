//! The silhouette-line buffer of seed 000 (Yamaguchi & Ikedo, "Shadow
//! Antialiasing with Virtual Projection Space", IPSJ 2008): exact shadow edges
//! inside each shadow-map texel.

pub mod buffer;
pub mod light;
pub mod line;
pub mod region;
pub mod term;
pub mod walk;

pub use buffer::SilhouetteLineBuffer;
pub use term::SlbMap;
