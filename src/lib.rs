//! # kage — a CPU renderer for design previews
//!
//! kage implements five rendering papers (kept in `../shared/seeds/`, restated in
//! `SPEC.md`) as one frame pipeline. The module tree follows the frame's data flow:
//!
//! ```text
//! scene ──► visibility ──► shadows ──► shading ──► raytrace ──► resolve ──► image
//! (files,    (rasterizer    (shadow      (seed 002    (item-buffer   (jitter    (PNG, EXR,
//!  meshes,    into the       term per     eq. 1,       reflections,   average,   PFM)
//!  lights)    item buffer)   light)       per light)   refraction)    exposure)
//! ```
//!
//! [`frame::render`] runs the whole chain; each stage is usable on its own, so tests
//! can check coverage without shading and shading without files.
//!
//! ```
//! // Render the built-in demo scene and look at what the centre pixel sees.
//! let scene = kage::scene::demo::demo_scene()?;
//! let frame = kage::render(&scene, &kage::RenderOptions::default())?;
//! assert_eq!((frame.image.width(), frame.image.height()), (scene.width, scene.height));
//! let item = frame.visibility.item(scene.width / 2, scene.height / 2);
//! assert!(!item.is_none(), "the demo's objects fill the centre of the view");
//! # Ok::<(), kage::Error>(())
//! ```
//!
//! Conventions (handedness, depth range, pixel centres, fill rule) are fixed once in
//! `ARCHITECTURE.md`.

pub mod bvh;
pub mod camera;
pub mod compare;
pub mod csg;
pub mod error;
pub mod frame;
pub mod image;
pub mod output;
pub mod raytrace;
pub mod resolve;
pub mod sampling;
pub mod scene;
pub mod shading;
pub mod shadows;
pub mod visibility;

pub use error::{Error, SourceLocation};
pub use frame::{render, Frame, FrameStats, RenderOptions, Renderer};
pub use scene::Scene;
