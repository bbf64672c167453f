//! # kage — a CPU renderer for design previews
//!
//! kage implements five rendering papers (cited in `docs/papers.md`, called seeds
//! 000 to 004 in the code) as one frame pipeline. The module tree is the frame, ground floor
//! first; a module uses only the ones before it (`tests/layering.rs` holds it
//! to that):
//!
//! ```text
//! limits · error · sampling · image · camera ·       the ground floor: what one input
//! triangle · polygon · bvh                       may ask for, typed errors, sample
//!                                                patterns, the linear float image and
//!                                                sRGB, the view and its rays, a ray
//!                                                against a triangle, a polygon face
//!                                                cut into triangles, the BVH
//!   ▼
//! csg            CSG solids (seed 003): model, OpenSCAD reader, ray casting by intervals
//!   ▼
//! scene          what is drawn: objects, lights, materials, settings; files and loaders
//!   ▼
//! visibility     the item buffer: polygons (seed 004 §3(1)) and solids' scanline walk
//!   ▼
//! shadows        the shadow term per light: maps, the SLB (seed 000), two-map soft
//!                shadows (seed 001), PCSS
//!   ▼
//! shading        seed 002's passes: eq. 1 per light, summed; fog, translucency
//!   ▼
//! raytrace       reflections and refraction from the item buffer; the reference
//!   ▼
//! resolve        the edge pass (seed 004) and jittered passes (seed 002 §4)
//!   ▼
//! frame          Renderer: one call per stage, buffers kept between frames
//!   ▼
//! output · compare                               images written and read; measured
//! ```
//!
//! [`render`] runs the whole chain; each stage is usable on its own, so tests
//! can check coverage without shading and shading without files.
//!
//! The front door — what the `kage` command, its viewer and the benchmarks use —
//! is re-exported here: [`render`] and [`Renderer`] with [`RenderOptions`], the
//! [`Frame`] they give with its [`FrameStats`], the ray-traced oracle
//! [`render_reference`] with [`ReferenceOptions`], the shading components
//! ([`Component`], [`ComponentSet`]), [`thread_pool`], and [`Scene`] (built by
//! [`scene::file`], [`scene::model`] or [`scene::demo`]).
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
pub mod idle;
pub mod image;
pub mod limits;
pub mod output;
pub mod polygon;
pub mod raytrace;
pub mod resolve;
pub mod sampling;
pub mod scene;
pub mod shading;
pub mod shadows;
pub mod triangle;
pub mod visibility;

pub use error::{Error, SourceLocation};
pub use frame::{render, thread_pool, Frame, FrameStats, RenderOptions, Renderer};
pub use limits::{Limit, Limits};
pub use raytrace::reference::{render_reference, render_reference_until, ReferenceOptions};
pub use scene::Scene;
pub use shading::{Component, ComponentSet};
