//! Soft shadows from two hard shadows (seed 001, Tsutsumi): a pixel shadowed
//! in the hard shadows of two points on either side of the light is umbra,
//! in one of them penumbra, and a penumbra pixel's visibility comes from its
//! screen distances to the nearest umbra and the nearest lit pixel
//! ([`penumbra`]: by the paper's search every N pixels, or by an exact
//! distance transform, [`edt`], for every pixel at once).

pub mod edt;
pub mod penumbra;
