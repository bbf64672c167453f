//! One frame, start to finish: visibility pass → shading passes → traced term,
//! repeated and averaged for jittered antialiasing (seed 002 §4) → resolve.
//!
//! A [`Renderer`] keeps its buffers between frames, as an interactive preview
//! re-renders the same size again and again; [`render`] is the one-shot form.

use std::time::{Duration, Instant};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::image::LinearImage;
use crate::raytrace::{traced, TraceCache};
use crate::resolve::edges as solid_edges;
use crate::resolve::edges::{self, EdgeCache, EdgeOptions};
use crate::scene::{Antialias, Scene};
use crate::shading::{self, fog, translucency, Component, ComponentSet, SubpixelShading, Target};
use crate::shadows::MapPool;
use crate::visibility::{self, RasterStats, VisibilityBuffer};

/// Most worker threads a renderer accepts.
pub const MAX_THREADS: usize = 1024;

/// How to render.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderOptions {
    /// Worker threads (`None`: one per core).
    pub threads: Option<usize>,
    /// Reflection/refraction bounces traced from the item buffer (seed 002 §4).
    pub ray_depth: u32,
    /// Components also written out on their own ([`Frame::aovs`]); they sum to
    /// the final image.
    pub aovs: ComponentSet,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions { threads: None, ray_depth: 4, aovs: ComponentSet::EMPTY }
    }
}

/// Timings and counts of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Milliseconds in the visibility (polygon) passes.
    pub visibility_ms: f64,
    /// Milliseconds rendering shadow maps.
    pub shadow_ms: f64,
    /// Most bytes the shadow maps of one light held.
    pub shadow_bytes: usize,
    /// Lights whose shadow maps came from the previous frame or pass (nothing
    /// they depend on changed), summed over passes.
    pub shadow_maps_reused: usize,
    /// Shading passes run (summed over jittered passes).
    pub shading_passes: u32,
    /// Milliseconds in the shading passes (shadow maps aside; the edge pass's
    /// plan, run beside the first, included).
    pub shading_ms: f64,
    /// Milliseconds tracing reflections and refraction from the item buffer.
    pub traced_ms: f64,
    /// Pixels that spawned secondary rays, summed over passes.
    pub traced_pixels: usize,
    /// Whether this frame built a BVH for its traced term (false when it had none
    /// or reused the last frame's: same meshes, same transforms).
    pub bvh_built: bool,
    /// Milliseconds in the edge pass (seed 004; 0 unless antialiased by edges):
    /// its plan runs beside the first shading pass, so that part of it is wall
    /// time shared with the shading, not added to the frame's.
    pub edge_ms: f64,
    /// Pixels the edge pass blended.
    pub edge_blends: usize,
    /// Translucent fragments blended (summed over passes).
    pub translucent_fragments: usize,
    /// Visibility passes rendered (more than one when antialiased by jitter).
    pub passes: u32,
    /// What the rasterizer did.
    pub raster: RasterStats,
    /// Bytes held by the frame's buffers (visibility buffer, image, the
    /// accumulation buffer of jittered passes and the largest light's shadow
    /// maps).
    pub buffer_bytes: usize,
}

/// A rendered frame and the buffer it was shaded from.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Linear RGB result.
    pub image: LinearImage,
    /// Depth and item id per pixel (of the last pass, when jittered).
    pub visibility: VisibilityBuffer,
    /// The requested components, each on its own (seed 002 Fig. 4).
    pub aovs: Vec<(Component, LinearImage)>,
    /// Timings and counts.
    pub stats: FrameStats,
}

/// Renders frames, reusing its buffers from one frame to the next.
#[derive(Debug)]
pub struct Renderer {
    pool: Option<rayon::ThreadPool>,
    options: RenderOptions,
    frame: Frame,
    scratch: Scratch,
}

/// Buffers a frame needs besides its own, kept between frames.
#[derive(Debug, Default)]
struct Scratch {
    /// Sum of the jittered passes.
    accum: LinearImage,
    /// One jittered pass's components (when AOVs are requested).
    aovs: Vec<LinearImage>,
    /// Shadow-map buffers, reused from light to light and frame to frame.
    maps: MapPool,
    /// The BVH of the traced term, rebuilt only when the geometry changes.
    trace: TraceCache,
    /// The meshes' edges for the edge pass (seed 004), kept while the meshes live.
    edges: EdgeCache,
    /// The edge pass's sub-pixel samples and what the passes added there.
    subpixel: SubpixelShading,
}

impl Renderer {
    /// A renderer with empty buffers.
    pub fn new(options: &RenderOptions) -> Result<Renderer> {
        let pool = thread_pool(options.threads)?;
        let frame = Frame {
            image: LinearImage::new(0, 0),
            visibility: VisibilityBuffer::new(0, 0),
            stats: FrameStats::default(),
            aovs: Vec::new(),
        };
        Ok(Renderer { pool, frame, options: *options, scratch: Scratch::default() })
    }

    /// Renders `scene` (validated first) and returns the frame.
    pub fn render(&mut self, scene: &Scene) -> Result<&Frame> {
        scene.validate()?;
        let (frame, scratch) = (&mut self.frame, &mut self.scratch);
        let options = &self.options;
        match &self.pool {
            None => render_into(scene, frame, scratch, options),
            Some(pool) => pool.install(|| render_into(scene, frame, scratch, options)),
        }
        Ok(&self.frame)
    }

    /// Gives up the last frame.
    #[must_use]
    pub fn into_frame(self) -> Frame {
        self.frame
    }
}

/// A pool of `threads` workers (`None`: rayon's global pool, one per core);
/// refuses more than [`MAX_THREADS`].
pub fn thread_pool(threads: Option<usize>) -> Result<Option<rayon::ThreadPool>> {
    let Some(n) = threads else { return Ok(None) };
    if n > MAX_THREADS {
        return Err(Error::Scene(format!("{n} threads requested; at most {MAX_THREADS}")));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n.max(1))
        .build()
        .map(Some)
        .map_err(|e| Error::Scene(format!("cannot start {n} threads: {e}")))
}

/// Renders `scene` once.
pub fn render(scene: &Scene, options: &RenderOptions) -> Result<Frame> {
    let mut r = Renderer::new(options)?;
    r.render(scene)?;
    Ok(r.into_frame())
}

fn render_into(scene: &Scene, frame: &mut Frame, scratch: &mut Scratch, options: &RenderOptions) {
    let offsets = scene.antialias.offsets();
    frame.stats = FrameStats::default();
    let (w, h) = (scene.width, scene.height);
    // The component images are kept from frame to frame, like every other buffer.
    let components: Vec<Component> = options.aovs.iter().collect();
    frame.aovs.resize_with(components.len(), || (Component::Ambient, LinearImage::default()));
    for ((slot, image), &c) in frame.aovs.iter_mut().zip(&components) {
        *slot = c;
        image.resize(w, h);
    }
    scratch.aovs.resize_with(frame.aovs.len(), LinearImage::default);
    scratch.aovs.iter_mut().for_each(|a| a.resize(w, h));
    if offsets.len() == 1 && offsets[0] == Vec2::ZERO {
        let edge = match scene.antialias {
            Antialias::Edge(mode) => Some(EdgeOptions { mode, ..EdgeOptions::default() }),
            _ => None,
        };
        render_pass(scene, frame, scratch, options.ray_depth, edge.as_ref());
        if edge.is_some() && scene.objects.iter().any(|o| o.solid().is_some()) {
            // Solids' outlines are curves no mesh edge bounds: measured by rays.
            let t = Instant::now();
            let mut images: Vec<&mut LinearImage> =
                std::iter::once(&mut frame.image).chain(&mut scratch.aovs).collect();
            let blends = solid_edges::find_outline_blends(scene, &frame.visibility, scratch.trace.get(scene));
            images.iter_mut().for_each(|image| solid_edges::apply_outline_blends(image, &blends));
            frame.stats.edge_blends += blends.len();
            frame.stats.edge_ms += t.elapsed().as_secs_f64() * 1e3;
        }
        frame.aovs.iter_mut().zip(&mut scratch.aovs).for_each(|((_, a), s)| std::mem::swap(a, s));
    } else {
        // Seed 002 §4: each pass shifts the image by a fraction of a pixel, so its
        // item buffer samples another point of every pixel; the passes are averaged.
        scratch.accum.resize(w, h);
        scratch.accum.pixels_mut().fill(Vec3::ZERO);
        frame.aovs.iter_mut().for_each(|(_, a)| a.pixels_mut().fill(Vec3::ZERO));
        let mut pass = scene.clone();
        // Directional lights' maps are fitted to the unshifted view: the
        // passes share them (and the next frame may reuse them).
        scratch.maps.fit_to(Some(scene.camera));
        let pixel = 2.0 / Vec2::new(w as f32, h as f32);
        let k = 1.0 / offsets.len() as f32;
        for &o in &offsets {
            // Pixel offsets (y down) to NDC (y up).
            pass.camera.shift = scene.camera.shift + Vec2::new(o.x, -o.y) * pixel;
            render_pass(&pass, frame, scratch, options.ray_depth, None);
            add_scaled(&mut scratch.accum, &frame.image, k);
            frame.aovs.iter_mut().zip(&scratch.aovs).for_each(|((_, a), s)| add_scaled(a, s, k));
        }
        scratch.maps.fit_to(None);
        std::mem::swap(&mut frame.image, &mut scratch.accum);
    }
    frame.stats.buffer_bytes = frame.visibility.memory_bytes()
        + std::mem::size_of_val(frame.image.pixels())
        + std::mem::size_of_val(scratch.accum.pixels())
        + (frame.aovs.len() + scratch.aovs.len()) * std::mem::size_of_val(frame.image.pixels())
        + scratch.maps.memory_bytes();
}

/// `acc += k · img`.
fn add_scaled(acc: &mut LinearImage, img: &LinearImage, k: f32) {
    acc.pixels_mut().par_iter_mut().zip(img.pixels().par_iter()).for_each(|(a, &p)| *a += p * k);
}

/// One visibility pass, its shading and its traced term into `frame.image`, and
/// the components `frame.aovs` names into `scratch.aovs` (same order), with
/// seed 004's edge pass if `edge` says so; adds its timings to the frame's
/// statistics.
fn render_pass(scene: &Scene, frame: &mut Frame, scratch: &mut Scratch, ray_depth: u32, edge: Option<&EdgeOptions>) {
    let Scratch { aovs, maps, trace, edges: edge_cache, subpixel, .. } = scratch;
    let t0 = Instant::now();
    frame.visibility.resize(scene.width, scene.height);
    frame.stats.raster = visibility::rasterize(scene, &mut frame.visibility);
    let t1 = Instant::now();
    frame.image.resize(scene.width, scene.height);
    let mut targets = vec![Target { parts: ComponentSet::ALL, image: &mut frame.image }];
    let mut traced_aov = None;
    for ((c, _), image) in frame.aovs.iter().zip(aovs.iter_mut()) {
        if *c == Component::Traced {
            traced_aov = Some(image);
        } else {
            targets.push(Target { parts: ComponentSet::only(*c), image });
        }
    }
    let vb = &frame.visibility;
    // The edges are found while the first pass shades the pixels (they need
    // only the visibility buffer), so every pass shades the sub-pixel points
    // the crossed pixels' parts need.
    let (mut plan, mut planned) = (None, Duration::ZERO);
    let prepare = |subpixel: &mut SubpixelShading| {
        let t = Instant::now();
        plan = edge.map(|o| edges::plan(scene, vb, o, edge_cache));
        let samples = plan.as_ref().map_or_else(Vec::new, |p| p.samples(scene.width));
        subpixel.reset(scene, vb, samples);
        planned = t.elapsed();
    };
    let lit = shading::shade_lit_while(scene, vb, (&mut targets, maps), subpixel, prepare);
    let t2 = Instant::now();
    let builds = trace.builds();
    frame.stats.traced_pixels += match &mut traced_aov {
        None => traced::add_traced(scene, vb, targets[0].image, ray_depth, trace),
        Some(t) => {
            t.pixels_mut().fill(Vec3::ZERO);
            let n = traced::add_traced(scene, vb, t, ray_depth, trace);
            add_scaled(targets[0].image, t, 1.0);
            n
        }
    };
    traced::trace_subpixel(scene, subpixel, ray_depth, trace);
    let t3 = Instant::now();
    frame.stats.bvh_built |= trace.builds() > builds;
    targets.extend(traced_aov.map(|image| Target { parts: ComponentSet::only(Component::Traced), image }));
    // Translucent surfaces are drawn last, over everything opaque (seed 002 §3.4).
    let layers = visibility::fragments(scene, vb);
    // Where nothing is drawn over the passes' image, each part of a crossed
    // pixel is coloured as the pixel is blended.
    let fused = scene.fog.is_none() && layers.is_empty();
    let t = Instant::now();
    match &mut plan {
        Some(plan) if fused => plan.record_and_apply(&mut targets, subpixel),
        Some(plan) => plan.record(&targets, subpixel),
        None => {}
    }
    let mut edge_time = t.elapsed();
    let fogged = scene.fog.as_ref().map(|fog| {
        let amounts = fog::fog_amounts(scene, fog, vb);
        for t in &mut targets {
            let color = if t.parts.contains(Component::Fog) { fog.color } else { Vec3::ZERO };
            fog::apply(t.image, &amounts, color);
        }
        amounts
    });
    if !layers.is_empty() {
        let lights = shading::frame_lights(scene);
        frame.stats.translucent_fragments +=
            translucency::composite(scene, layers, scene.translucency, &lights, &mut targets, maps);
    }
    if let Some(plan) = &plan {
        let t = Instant::now();
        if !fused {
            targets.iter_mut().for_each(|t| plan.apply(t.image, t.parts, fogged.as_deref()));
        }
        edge_time += t.elapsed();
        frame.stats.edge_blends = plan.len();
        frame.stats.edge_ms = (planned + edge_time).as_secs_f64() * 1e3;
    }
    frame.stats.visibility_ms += (t1 - t0).as_secs_f64() * 1e3;
    // The edge pass's plan ran beside the first pass, within this time.
    frame.stats.shading_ms += ((t2 - t1) + t3.elapsed()).as_secs_f64() * 1e3 - lit.shadow_ms;
    frame.stats.shadow_ms += lit.shadow_ms;
    frame.stats.shadow_maps_reused += lit.maps_reused;
    frame.stats.shadow_bytes = frame.stats.shadow_bytes.max(lit.shadow_bytes);
    frame.stats.shading_passes += lit.passes;
    frame.stats.traced_ms += (t3 - t2).as_secs_f64() * 1e3;
    frame.stats.passes += 1;
}
