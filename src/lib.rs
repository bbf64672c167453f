//! # kage — a CPU renderer for design previews
//!
//! kage implements five rendering papers (kept in `../shared/seeds/`, restated in
//! `SPEC.md`) as one frame pipeline. The module tree follows the frame's data flow:
//!
//! ```text
//! scene ──► visibility ──► shading ──► resolve ──► image
//! (files,    (rasterizer    (seed 002     (tone,      (PNG, EXR,
//!  meshes,    into the       eq. 1 per     gamma)      PFM)
//!  lights)    item buffer)   light)
//! ```
//!
//! [`frame::render`] runs the whole chain; each stage is usable on its own, so tests
//! can check coverage without shading and shading without files.
//!
//! Conventions (handedness, depth range, pixel centres, fill rule) are fixed once in
//! `ARCHITECTURE.md`.

pub mod error;
pub mod frame;
pub mod output;
pub mod resolve;
pub mod scene;
pub mod shading;
pub mod visibility;

pub use error::{Error, SourceLocation};
pub use frame::{render, Frame, FrameStats, RenderOptions, Renderer};
pub use scene::Scene;
