//! Resolve: what turns the shaded passes into the finished frame — the edge
//! pass of seed 004 ([`edges`]), which antialiases outlines after the aliased
//! frame, or jittered passes averaged ([`jitter`], seed 002 §4). (Exposure and
//! the sRGB curve are applied when an 8-bit image is written:
//! [`crate::image::LinearImage::to_srgb8`].)

pub mod edges;
pub mod jitter;
