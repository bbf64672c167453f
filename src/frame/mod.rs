//! One frame, start to finish, one call per stage:
//!
//! ```text
//! visibility ─► shadows and shading ─► traced term ─► edge pass: record ─► fog ─► translucency ─► edge pass: apply
//!  (item buffer)  (seed 002 §3; the edge     (seed 002 §4)                    (§3.5)   (§3.4)        (seed 004; solids'
//!                  pass planned beside                                                               outlines by rays)
//!                  the first pass)
//! ```
//!
//! repeated and averaged for jittered antialiasing (seed 002 §4,
//! [`crate::resolve::jitter`]). A [`Renderer`] keeps its buffers between frames,
//! as an interactive preview re-renders the same size again and again; [`render`]
//! is the one-shot form.

mod budget;

pub use budget::{MemoryNeeded, BYTES_PER_PIXEL, BYTES_PER_TRIANGLE};

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::{Vec2, Vec3};

use crate::error::{Error, Result};
use crate::idle::{IdleClock, IdleTime};
use crate::image::{LinearImage, PixelRect};
use crate::raytrace::traced::Refine;
use crate::raytrace::{occlusion, traced, TraceCache};
use crate::resolve::edges::{EdgeOptions, EdgePass};
use crate::resolve::jitter;
use crate::scene::{Antialias, Scene};
use crate::shading::{
    self, fog, translucency, Component, ComponentSet, OpenShares, PassStats, SubpixelShading, Target,
};
use crate::shadows::methods::technique;
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
    /// Keep the lights' shadow maps from one frame to the next while nothing
    /// they depend on changes (the default: a viewer whose camera moves renders
    /// no spot or point light's map again). Off, every frame renders every map,
    /// as a renderer that keeps nothing between frames does.
    pub keep_shadow_maps: bool,
    /// Also write each light's shadow term on its own ([`Frame::shadows`]).
    pub shadow_images: bool,
    /// Trace reflections and refraction at one pixel of each 2 × 2 block and
    /// interpolate the others ([`crate::raytrace::traced::Refine::Sparse`]):
    /// about a quarter of the traced term's rays, for the frames of a moving
    /// camera. Ignored by edge-antialiased frames, which refine instead.
    pub sparse_traced: bool,
    /// Only these pixels of the frame need be right (`None`: all of them): a
    /// tile of a larger render. Every pixel inside equals the whole frame's
    /// bit for bit. The frame's buffers and images hold the pixels drawn for
    /// it alone ([`region_drawn`]: the region and a guard band, [`Frame::rect`]),
    /// so a tile costs memory in proportion to its area; [`Frame::crop`]
    /// cuts the region out.
    pub region: Option<PixelRect>,
    /// Measure, per stage, the time its workers had no work
    /// ([`FrameStats::idle`], [`crate::idle`]): a few reads of the kernel's
    /// per-thread statistics around each stage (tens of microseconds each),
    /// so off by default.
    pub measure_idle: bool,
}

/// Pixels drawn around a [`RenderOptions::region`]: more than any stage that
/// looks at neighbours reaches (the edge pass's blends and its outlines' ends,
/// the traced term's refinement, the silhouette-line buffer's footprints reach
/// a few pixels).
pub const REGION_GUARD_PX: u32 = 16;

/// The pixels a frame limited to `region` draws: the region grown by
/// [`REGION_GUARD_PX`], its columns widened to the shading's segment borders
/// ([`shading::SEGMENT`]); or the whole frame when a light's shadow method
/// computes its term per pixel of the frame
/// ([`crate::shadows::Technique::per_pixel`]: the
/// two-map soft shadow, whose distances reach across the image).
#[must_use]
pub fn region_drawn(scene: &Scene, region: PixelRect) -> PixelRect {
    let (w, h) = (scene.width, scene.height);
    if scene.lights.iter().any(|l| technique(l.shadow.method).per_pixel()) {
        return PixelRect::full(w, h);
    }
    let grown = region.grown(REGION_GUARD_PX, w, h);
    let segment = shading::SEGMENT as u32;
    PixelRect {
        x0: grown.x0 / segment * segment,
        x1: grown.x1.div_ceil(segment).saturating_mul(segment).min(w),
        ..grown
    }
}

/// The pixels a frame of `scene` draws: those [`region_drawn`] says for a
/// `region`, else all of them.
fn drawn(scene: &Scene, region: Option<PixelRect>) -> PixelRect {
    region.map_or(PixelRect::full(scene.width, scene.height), |r| region_drawn(scene, r))
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            threads: None,
            ray_depth: 4,
            aovs: ComponentSet::EMPTY,
            keep_shadow_maps: true,
            shadow_images: false,
            sparse_traced: false,
            region: None,
            measure_idle: false,
        }
    }
}

/// Timings and counts of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Milliseconds in the visibility (polygon and solid) passes.
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
    /// Milliseconds in the shading passes, fog and translucency (shadow maps
    /// aside; the edge pass's plan, run beside the first pass, included).
    pub shading_ms: f64,
    /// Milliseconds tracing reflections and refraction from the item buffer.
    pub traced_ms: f64,
    /// Milliseconds finding ambient occlusion (0 without it).
    pub occlusion_ms: f64,
    /// Milliseconds drawing feature lines (0 without them).
    pub lines_ms: f64,
    /// Pixels feature lines were drawn on, summed over passes.
    pub line_pixels: usize,
    /// Pixels that spawned secondary rays, summed over passes.
    pub traced_pixels: usize,
    /// Traced pixels traced again at sub-pixel points where what they show
    /// has an edge (edge-antialiased frames: [`crate::raytrace::traced::Refine`]).
    pub traced_refined: usize,
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
    /// Of [`FrameStats::buffer_bytes`], the buffers of one entry a pixel
    /// held (all but the shadow maps): in proportion to the pixels drawn
    /// ([`Frame::rect`]).
    pub pixel_bytes: usize,
    /// Per stage, its wall time and the time its workers had no work
    /// (measured only with [`RenderOptions::measure_idle`]).
    pub idle: StageIdle,
    /// Whether [`FrameStats::idle`] is measured.
    measuring: bool,
}

/// Each stage's wall time and the time its workers had no work
/// ([`crate::idle`]), summed over the frame's passes.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageIdle {
    /// The visibility passes.
    pub visibility: IdleTime,
    /// The shadow stage: maps and per-pixel terms.
    pub shadows: IdleTime,
    /// Shading, fog and translucency, the shadow stage aside.
    pub shading: IdleTime,
    /// Rays from the item buffer: reflections and refraction, ambient
    /// occlusion.
    pub traced: IdleTime,
    /// The edge pass's recording and blending.
    pub edges: IdleTime,
}

impl StageIdle {
    /// The whole frame: every stage's sum.
    #[must_use]
    pub fn frame(&self) -> IdleTime {
        [self.visibility, self.shadows, self.shading, self.traced, self.edges]
            .into_iter()
            .fold(IdleTime::default(), IdleTime::plus)
    }
}

/// The stages a frame's time is told by ([`FrameStats`]).
#[derive(Debug, Clone, Copy)]
enum Stage {
    Visibility,
    Shading,
    Traced,
    Occlusion,
    Edges,
    Lines,
}

impl FrameStats {
    /// Runs `work`, adding the time it takes to `stage`'s.
    fn timed<T>(&mut self, stage: Stage, work: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let clock = self.measuring.then(IdleClock::start);
        let out = work();
        self.add(stage, start.elapsed());
        if let Some(clock) = clock {
            let idle = match stage {
                Stage::Visibility => &mut self.idle.visibility,
                Stage::Shading => &mut self.idle.shading,
                Stage::Traced | Stage::Occlusion => &mut self.idle.traced,
                Stage::Edges | Stage::Lines => &mut self.idle.edges,
            };
            *idle = idle.plus(clock.stop());
        }
        out
    }

    /// Adds `time` to `stage`'s milliseconds.
    fn add(&mut self, stage: Stage, time: Duration) {
        let ms = time.as_secs_f64() * 1e3;
        match stage {
            Stage::Visibility => self.visibility_ms += ms,
            Stage::Shading => self.shading_ms += ms,
            Stage::Traced => self.traced_ms += ms,
            Stage::Occlusion => self.occlusion_ms += ms,
            Stage::Edges => self.edge_ms += ms,
            Stage::Lines => self.lines_ms += ms,
        }
    }

    /// Counts a pass's shading: its shadow maps' time moves from the
    /// shading's to their own.
    fn add_lit(&mut self, lit: &PassStats) {
        self.idle.shading = self.idle.shading.minus(lit.shadow_idle);
        self.idle.shadows = self.idle.shadows.plus(lit.shadow_idle);
        self.shading_ms -= lit.shadow_ms;
        self.shadow_ms += lit.shadow_ms;
        self.shadow_maps_reused += lit.maps_reused;
        self.shadow_bytes = self.shadow_bytes.max(lit.shadow_bytes);
        self.shading_passes += lit.passes;
    }
}

/// A rendered frame and the buffer it was shaded from. Its images hold the
/// pixels [`Frame::rect`] names: the whole image but for a tile of a frame
/// ([`RenderOptions::region`]), whose images start at the rectangle's top left
/// pixel.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Linear RGB result.
    pub image: LinearImage,
    /// Depth and item id per pixel (of the last pass, when jittered).
    pub visibility: VisibilityBuffer,
    /// The requested components, each on its own (seed 002 Fig. 4).
    pub aovs: Vec<(Component, LinearImage)>,
    /// When [`RenderOptions::shadow_images`] asks for them, each light's
    /// shadow term at the surface each pixel shows, in the scene's order of
    /// lights (grey: 1 lit, 0 in shadow or facing away from the light; 1
    /// where no object is seen). The mean of the passes, when jittered.
    pub shadows: Vec<LinearImage>,
    /// With the scene's ambient occlusion, the open share of each pixel's
    /// hemisphere (grey: 1 open, 0 closed; 1 where no object is seen), the
    /// mean of the passes when jittered; empty (0 × 0) without.
    pub occlusion: LinearImage,
    /// Timings and counts.
    pub stats: FrameStats,
}

impl Frame {
    /// The pixels of the whole image the frame's images and buffers hold
    /// (their pixel (0, 0) is this rectangle's top left one).
    #[must_use]
    pub fn rect(&self) -> PixelRect {
        self.visibility.rect()
    }

    /// The pixels `region` (whole-image coordinates) of the frame's image.
    ///
    /// # Panics
    ///
    /// If `region` does not lie inside [`Frame::rect`].
    #[must_use]
    pub fn crop(&self, region: PixelRect) -> LinearImage {
        self.image.crop(region.relative_to(self.rect()))
    }

    /// Each pixel's shading normal (world space, unit; zero where no object
    /// is seen), at the pixel's centre, from the visibility buffer of the
    /// frame's last pass — `scene` is the scene it was rendered from; the
    /// pixels of [`Frame::rect`], row by row.
    #[must_use]
    pub fn normals(&self, scene: &Scene) -> Vec<Vec3> {
        let surfaces = crate::shading::screen_surfaces(scene, &self.visibility);
        surfaces.all().iter().map(|s| s.map_or(Vec3::ZERO, |s| s.normal)).collect()
    }
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
    /// One pass's components (when AOVs are requested), in `Frame::aovs`' order.
    aovs: Vec<LinearImage>,
    /// One pass's shadow terms (when requested), in `Frame::shadows`' order.
    shadows: Vec<LinearImage>,
    /// One pass's ambient component, for ambient occlusion to darken when no
    /// ambient image is requested.
    ambient: LinearImage,
    /// One pass's open shares (ambient occlusion).
    occlusion: LinearImage,
    /// Shadow-map buffers, reused from light to light and frame to frame.
    maps: MapPool,
    /// The BVH of the traced term, rebuilt only when the geometry changes.
    trace: TraceCache,
    /// The edge pass (seed 004), with the meshes' edges kept while they live.
    edges: EdgePass,
    /// The edge pass's sub-pixel samples and what the passes added there.
    subpixel: SubpixelShading,
    /// Translucent fragments ready to blend, their memory kept.
    layers: translucency::Layers,
}

impl Renderer {
    /// A renderer with empty buffers.
    ///
    /// # Errors
    ///
    /// [`Error::Threads`] when `options.threads` is more than [`MAX_THREADS`]
    /// or the threads cannot be started.
    pub fn new(options: &RenderOptions) -> Result<Renderer> {
        let pool = thread_pool(options.threads)?;
        let frame = Frame {
            image: LinearImage::new(0, 0),
            visibility: VisibilityBuffer::new(0, 0),
            stats: FrameStats::default(),
            aovs: Vec::new(),
            shadows: Vec::new(),
            occlusion: LinearImage::new(0, 0),
        };
        Ok(Renderer { pool, frame, options: *options, scratch: Scratch::default() })
    }

    /// Renders the next frames as `options` say, keeping every buffer and
    /// cache (a viewer's quick frames and refined ones differ in options,
    /// not in scene).
    ///
    /// # Errors
    ///
    /// As [`Renderer::new`], when the thread count changes.
    pub fn set_options(&mut self, options: &RenderOptions) -> Result<()> {
        if options.threads != self.options.threads {
            self.pool = thread_pool(options.threads)?;
        }
        self.options = *options;
        Ok(())
    }

    /// Renders `scene` (validated first) and returns the frame.
    ///
    /// # Errors
    ///
    /// What [`Scene::validate`] finds wrong with the scene, and
    /// [`Error::Limit`] when a frame of it would ask for more than its
    /// [`Scene::limits`] allow.
    pub fn render(&mut self, scene: &Scene) -> Result<&Frame> {
        self.render_reporting(scene, &|_, _| {})
    }

    /// As [`Renderer::render`], calling `progress(done, total)` after each
    /// pass of the frame (a jittered frame has one per sub-pixel sample, any
    /// other frame one).
    ///
    /// # Errors
    ///
    /// As [`Renderer::render`].
    pub fn render_reporting(&mut self, scene: &Scene, progress: &(dyn Fn(u32, u32) + Sync)) -> Result<&Frame> {
        self.render_watched(scene, progress, Stop(None))
    }

    /// As [`Renderer::render`], giving the frame up as soon as `stop` is
    /// raised (by another thread: a viewer whose user moved on): checked
    /// before each stage of each pass (visibility, shading with its shadow
    /// maps, the traced term, fog and translucency with the edge pass), so
    /// the call returns within one stage of the raise. The buffers are left
    /// ready for the next frame.
    ///
    /// # Errors
    ///
    /// [`Error::Stopped`] when `stop` was raised before the frame was done;
    /// otherwise as [`Renderer::render`].
    pub fn render_or_stop(&mut self, scene: &Scene, stop: &AtomicBool) -> Result<&Frame> {
        self.render_watched(scene, &|_, _| {}, Stop(Some(stop)))
    }

    fn render_watched(&mut self, scene: &Scene, progress: &(dyn Fn(u32, u32) + Sync), stop: Stop) -> Result<&Frame> {
        scene.validate()?;
        if let Some(region) = self.options.region {
            if region.is_empty() || !region.fits(scene.width, scene.height) {
                let region = (region.x0, region.y0, region.x1, region.y1);
                return Err(Error::Region { region, width: scene.width, height: scene.height });
            }
        }
        budget::check(scene, drawn(scene, self.options.region))?;
        let (frame, scratch) = (&mut self.frame, &mut self.scratch);
        let options = &self.options;
        match &self.pool {
            None => render_into(scene, frame, scratch, options, progress, stop),
            Some(pool) => pool.install(|| render_into(scene, frame, scratch, options, progress, stop)),
        }?;
        Ok(&self.frame)
    }

    /// Gives up the last frame.
    #[must_use]
    pub fn into_frame(self) -> Frame {
        self.frame
    }
}

/// A pool of `threads` workers (`None`: rayon's global pool, one per core).
///
/// # Errors
///
/// [`Error::Threads`] for more than [`MAX_THREADS`] threads, or when the
/// system cannot start them.
pub fn thread_pool(threads: Option<usize>) -> Result<Option<rayon::ThreadPool>> {
    let Some(n) = threads else { return Ok(None) };
    let refused = |reason: String| Error::Threads { requested: n, reason };
    if n > MAX_THREADS {
        return Err(refused(format!("at most {MAX_THREADS} can be used")));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n.max(1))
        .build()
        .map(Some)
        .map_err(|e| refused(format!("the system could not start them: {e}")))
}

/// Renders `scene` once.
///
/// # Errors
///
/// As [`Renderer::new`] and [`Renderer::render`].
pub fn render(scene: &Scene, options: &RenderOptions) -> Result<Frame> {
    let mut r = Renderer::new(options)?;
    r.render(scene)?;
    Ok(r.into_frame())
}

/// A flag a caller may raise to give a frame up between its stages.
#[derive(Debug, Clone, Copy)]
struct Stop<'a>(Option<&'a AtomicBool>);

impl Stop<'_> {
    /// [`Error::Stopped`] once the flag is raised.
    fn check(self) -> Result<()> {
        match self.0 {
            Some(flag) if flag.load(Ordering::Relaxed) => Err(Error::Stopped),
            _ => Ok(()),
        }
    }
}

fn render_into(
    scene: &Scene,
    frame: &mut Frame,
    scratch: &mut Scratch,
    options: &RenderOptions,
    progress: &(dyn Fn(u32, u32) + Sync),
    stop: Stop,
) -> Result<()> {
    frame.stats = FrameStats { measuring: options.measure_idle, ..FrameStats::default() };
    scratch.maps.measure_idle(options.measure_idle);
    if !options.keep_shadow_maps {
        scratch.maps.forget();
    }
    fit_component_images(scene, drawn(scene, options.region), options, frame, scratch);
    let offsets = scene.antialias.offsets();
    if offsets.len() == 1 && offsets[0] == Vec2::ZERO {
        let edges = match scene.antialias {
            Antialias::Edge(mode) => Some(EdgeOptions { mode, ..EdgeOptions::default() }),
            _ => None,
        };
        render_pass(scene, frame, scratch, options, edges.as_ref(), stop)?;
        frame.aovs.iter_mut().zip(&mut scratch.aovs).for_each(|((_, a), s)| std::mem::swap(a, s));
        std::mem::swap(&mut frame.shadows, &mut scratch.shadows);
        std::mem::swap(&mut frame.occlusion, &mut scratch.occlusion);
        progress(1, 1);
    } else {
        render_jittered(scene, &offsets, frame, scratch, options, progress, stop)?;
    }
    frame.stats.pixel_bytes = frame.visibility.memory_bytes()
        + std::mem::size_of_val(frame.image.pixels())
        + std::mem::size_of_val(scratch.accum.pixels())
        + (frame.aovs.len() + scratch.aovs.len() + frame.shadows.len() + scratch.shadows.len())
            * std::mem::size_of_val(frame.image.pixels());
    frame.stats.buffer_bytes = frame.stats.pixel_bytes + scratch.maps.memory_bytes();
    Ok(())
}

/// Makes the frame's component images (and one pass's, in `scratch`) the
/// components `wanted` names, the size of the pixels `held`; the images are
/// kept from frame to frame, like every other buffer.
fn fit_component_images(
    scene: &Scene,
    held: PixelRect,
    options: &RenderOptions,
    frame: &mut Frame,
    scratch: &mut Scratch,
) {
    let (w, h) = (held.width(), held.height());
    let components: Vec<Component> = options.aovs.iter().collect();
    frame.aovs.resize_with(components.len(), || (Component::Ambient, LinearImage::default()));
    for ((slot, image), &c) in frame.aovs.iter_mut().zip(&components) {
        *slot = c;
        image.resize(w, h);
    }
    scratch.aovs.resize_with(frame.aovs.len(), LinearImage::default);
    scratch.aovs.iter_mut().for_each(|a| a.resize(w, h));
    let lights = if options.shadow_images { scene.lights.len() } else { 0 };
    frame.shadows.resize_with(lights, LinearImage::default);
    frame.shadows.iter_mut().for_each(|a| a.resize(w, h));
    let (ow, oh) = if scene.ambient_occlusion.is_some() { (w, h) } else { (0, 0) };
    frame.occlusion.resize(ow, oh);
    scratch.occlusion.resize(ow, oh);
}

/// Seed 002 §4's accumulation buffer: one pass per sub-pixel `offsets`, each
/// shifting the image so its item buffer samples another point of every
/// pixel, averaged into the frame's image and component images.
fn render_jittered(
    scene: &Scene,
    offsets: &[Vec2],
    frame: &mut Frame,
    scratch: &mut Scratch,
    options: &RenderOptions,
    progress: &(dyn Fn(u32, u32) + Sync),
    stop: Stop,
) -> Result<()> {
    let held = drawn(scene, options.region);
    scratch.accum.resize(held.width(), held.height());
    scratch.accum.pixels_mut().fill(Vec3::ZERO);
    frame.aovs.iter_mut().for_each(|(_, a)| a.pixels_mut().fill(Vec3::ZERO));
    frame.shadows.iter_mut().for_each(|a| a.pixels_mut().fill(Vec3::ZERO));
    frame.occlusion.pixels_mut().fill(Vec3::ZERO);
    // Directional lights' maps are fitted to the unshifted view: the passes
    // share them (and the next frame may reuse them).
    scratch.maps.fit_to(Some(scene.camera));
    let weight = 1.0 / offsets.len() as f32;
    let mut pass = scene.clone();
    let mut passes = || {
        for (done, &offset) in (1..).zip(offsets) {
            pass.camera = scene.camera.shifted(offset, (scene.width, scene.height));
            if let (Some(ao), Some(base)) = (&mut pass.ambient_occlusion, &scene.ambient_occlusion) {
                // Each pass casts new rays of each point's sequence.
                ao.pass = base.pass.saturating_mul(offsets.len() as u32).saturating_add(done - 1);
            }
            render_pass(&pass, frame, scratch, options, None, stop)?;
            jitter::accumulate(&mut scratch.accum, &frame.image, weight);
            frame.aovs.iter_mut().zip(&scratch.aovs).for_each(|((_, a), s)| jitter::accumulate(a, s, weight));
            frame.shadows.iter_mut().zip(&scratch.shadows).for_each(|(a, s)| jitter::accumulate(a, s, weight));
            jitter::accumulate(&mut frame.occlusion, &scratch.occlusion, weight);
            progress(done, offsets.len() as u32);
        }
        Ok(())
    };
    let done = passes();
    scratch.maps.fit_to(None);
    std::mem::swap(&mut frame.image, &mut scratch.accum);
    done
}

/// One visibility pass and everything shaded from it into `frame.image`, and
/// the components `frame.aovs` names into `scratch.aovs` (same order) and the
/// shadow terms into `scratch.shadows` when `options` asks for them, with the
/// edge pass if `edges` asks for one; adds its timings to the frame's
/// statistics. Given up before a stage once `stop` is raised.
fn render_pass(
    scene: &Scene,
    frame: &mut Frame,
    scratch: &mut Scratch,
    options: &RenderOptions,
    edges: Option<&EdgeOptions>,
    stop: Stop,
) -> Result<()> {
    stop.check()?;
    let ray_depth = options.ray_depth;
    let Frame { image, visibility, aovs, stats, .. } = frame;
    let Scratch {
        aovs: component_images,
        maps,
        trace,
        edges: edge_pass,
        subpixel,
        shadows,
        ambient,
        occlusion,
        layers: kept,
        ..
    } = scratch;
    visibility.resize_to(scene.width, scene.height, Some(drawn(scene, options.region)));
    stats.raster = stats.timed(Stage::Visibility, || visibility::rasterize(scene, visibility));
    stop.check()?;
    let vb = &*visibility;
    let held = visibility.rect();
    image.resize(held.width(), held.height());
    // The quick form of ambient occlusion is found before the shading, which
    // scales the ambient term by it; the traced form darkens the pass's
    // ambient after it.
    let screen_space = scene.ambient_occlusion.is_some_and(|a| a.screen_space);
    if screen_space {
        stats.timed(Stage::Occlusion, || shading::screen_occlusion::open_shares(scene, vb, occlusion));
    }
    let open = screen_space
        .then(|| OpenShares::new(occlusion.pixels(), held.width() as usize, (held.x0 as usize, held.y0 as usize)));
    let darkened = (scene.ambient_occlusion.is_some() && !screen_space).then_some(ambient);
    let mut images = PassImages::new(image, aovs, component_images, darkened);
    let targets = &mut images.targets;
    let beside = |s: &mut SubpixelShading| {
        let start = Instant::now();
        edge_pass.plan(scene, vb, edges, s);
        start.elapsed()
    };
    let (lit, planned) = stats.timed(Stage::Shading, || shade(scene, vb, targets, maps, subpixel, open, beside));
    stats.add_lit(&lit);
    stats.add(Stage::Edges, planned);
    if options.shadow_images {
        shading::shadow_images::shadow_term_images(scene, vb, maps, shadows);
    }
    stop.check()?;
    let builds = trace.builds();
    if screen_space {
        stats.timed(Stage::Occlusion, || shading::screen_occlusion::darken_samples(vb, occlusion, subpixel));
    } else if scene.ambient_occlusion.is_some() {
        let open = occlusion;
        stats.timed(Stage::Occlusion, || occlusion_term(scene, vb, &mut images, subpixel, trace, open));
    }
    let refine = match (edges, options.sparse_traced) {
        (Some(_), _) => Refine::Contrast,
        (None, true) => Refine::Sparse,
        (None, false) => Refine::Never,
    };
    let (traced, refined) =
        stats.timed(Stage::Traced, || traced_term(scene, vb, &mut images, subpixel, ray_depth, refine, trace));
    (stats.traced_pixels, stats.traced_refined) = (stats.traced_pixels + traced, stats.traced_refined + refined);
    let targets = &mut images.targets;
    stats.bvh_built |= trace.builds() > builds;
    stop.check()?;
    // Translucent surfaces are drawn last, over everything opaque (seed 002 §3.4).
    let layers = visibility::fragments(scene, vb);
    let nothing_over = scene.fog.is_none() && layers.is_empty();
    stats.timed(Stage::Edges, || edge_pass.record(targets, subpixel, nothing_over));
    let fog = stats.timed(Stage::Shading, || fog::fog_targets(scene, vb, targets));
    let (blended, transmittance) =
        stats.timed(Stage::Shading, || translucency::composite(scene, vb, layers, targets, maps, kept));
    stats.translucent_fragments += blended;
    let seen = seen_through(fog.as_deref(), transmittance.as_deref());
    stats.timed(Stage::Edges, || edge_pass.apply(scene, vb, targets, seen.as_deref(), trace));
    stats.edge_blends = edge_pass.blends();
    if scene.lines.is_some() {
        let image = &mut *images.targets[0].image;
        stats.line_pixels += stats.timed(Stage::Lines, || edge_pass.draw_lines(scene, vb, image, trace));
    }
    stats.passes += 1;
    Ok(())
}

/// Per pixel, the share of its opaque surface's colour the image still shows
/// through fog (`1 − fog`) and translucent surfaces (their transmittance):
/// what an edge's move, found on the opaque surfaces, is scaled by. `None`
/// when it is 1 everywhere.
fn seen_through(fog: Option<&[f32]>, transmittance: Option<&[f32]>) -> Option<Vec<f32>> {
    match (fog, transmittance) {
        (None, None) => None,
        (Some(f), None) => Some(f.iter().map(|f| 1.0 - f).collect()),
        (None, Some(t)) => Some(t.to_vec()),
        (Some(f), Some(t)) => Some(f.iter().zip(t).map(|(f, t)| (1.0 - f) * t).collect()),
    }
}

/// The shading passes ([`shading::shade_lit_beside`]) with `beside` run beside
/// the first; returns their statistics and what `beside` returned.
fn shade<T: Send>(
    scene: &Scene,
    vb: &VisibilityBuffer,
    targets: &mut [Target],
    maps: &mut MapPool,
    subpixel: &mut SubpixelShading,
    open: Option<OpenShares>,
    beside: impl FnOnce(&mut SubpixelShading) -> T + Send,
) -> (PassStats, T) {
    let mut out = None;
    let lit = shading::shade_lit_beside(scene, vb, targets, maps, subpixel, open, |s| out = Some(beside(s)));
    (lit, out.expect("the passes run what goes beside them"))
}

/// The images one pass writes.
struct PassImages<'a> {
    /// The frame's image (every component) first, then the image of each
    /// requested component, then (with ambient occlusion and no ambient image
    /// requested) the pass's own ambient image.
    targets: Vec<Target<'a>>,
    /// Whether the last target is the pass's own ambient image.
    own_ambient: bool,
    /// The traced component's image, when it is requested: written by the
    /// traced term alone, it joins `targets` then.
    traced: Option<&'a mut LinearImage>,
}

impl<'a> PassImages<'a> {
    /// `image` and the `components`' own `images` (same order), and
    /// `ambient` (cleared to `image`'s size) when given and no ambient image
    /// is requested: what ambient occlusion darkens.
    fn new(
        image: &'a mut LinearImage,
        components: &[(Component, LinearImage)],
        images: &'a mut [LinearImage],
        ambient: Option<&'a mut LinearImage>,
    ) -> Self {
        let (w, h) = (image.width(), image.height());
        let mut targets = vec![Target { parts: ComponentSet::ALL, image }];
        let mut traced = None;
        for ((c, _), image) in components.iter().zip(images) {
            match c {
                Component::Traced => traced = Some(image),
                c => targets.push(Target { parts: ComponentSet::only(*c), image }),
            }
        }
        let requested = components.iter().any(|(c, _)| *c == Component::Ambient);
        let own_ambient = ambient.is_some() && !requested;
        if let Some(image) = ambient.filter(|_| own_ambient) {
            image.resize(w, h);
            image.pixels_mut().fill(Vec3::ZERO);
            targets.push(Target { parts: ComponentSet::only(Component::Ambient), image });
        }
        PassImages { targets, traced, own_ambient }
    }
}

/// Ambient occlusion ([`crate::raytrace::occlusion`]): the pass's ambient
/// darkened in its image and its ambient image, each pixel's open share into
/// `open`; the pass's own ambient image then leaves the targets.
fn occlusion_term(
    scene: &Scene,
    vb: &VisibilityBuffer,
    images: &mut PassImages,
    subpixel: &mut SubpixelShading,
    trace: &mut TraceCache,
    open: &mut LinearImage,
) {
    let ambient = ComponentSet::only(Component::Ambient);
    let Some(k) = images.targets.iter().position(|t| t.parts == ambient) else { return };
    let (image, rest) = images.targets.split_at_mut(1);
    let (image, ambient) = (&mut *image[0].image, &mut *rest[k - 1].image);
    occlusion::darken_ambient(scene, vb, trace.get(scene), image, ambient, subpixel, open);
    if images.own_ambient {
        images.targets.remove(k);
        images.own_ambient = false;
    }
}

/// Seed 002 §4's traced term, at the pixels (into the frame's image, through
/// the traced component's own image when it is requested, which then joins the
/// targets) and at the edge pass's sub-pixel samples, the pixels refined as
/// `refine` says; returns the pixels traced and refined.
fn traced_term(
    scene: &Scene,
    vb: &VisibilityBuffer,
    images: &mut PassImages,
    subpixel: &mut SubpixelShading,
    ray_depth: u32,
    refine: Refine,
    trace: &mut TraceCache,
) -> (usize, usize) {
    let pixels = match images.traced.take() {
        None => traced::add_traced(scene, vb, images.targets[0].image, ray_depth, trace, refine),
        Some(own) => {
            own.pixels_mut().fill(Vec3::ZERO);
            let n = traced::add_traced(scene, vb, own, ray_depth, trace, refine);
            jitter::accumulate(images.targets[0].image, own, 1.0);
            images.targets.push(Target { parts: ComponentSet::only(Component::Traced), image: own });
            n
        }
    };
    traced::trace_subpixel(scene, subpixel, ray_depth, trace);
    pixels
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

    use super::{Renderer, Stop};
    use crate::error::Error;
    use crate::scene::{demo::demo_scene, Antialias};
    use crate::RenderOptions;

    fn small_demo(antialias: Antialias) -> crate::Scene {
        let mut scene = demo_scene().expect("the demo loads");
        (scene.width, scene.height, scene.antialias) = (96, 64, antialias);
        scene
    }

    /// A raised flag gives the frame up before its first stage.
    #[test]
    fn a_raised_stop_gives_the_frame_up() {
        let mut renderer = Renderer::new(&RenderOptions::default()).unwrap();
        let stop = AtomicBool::new(true);
        let out = renderer.render_or_stop(&small_demo(Antialias::None), &stop).map(|_| ());
        assert!(matches!(out, Err(Error::Stopped)), "{out:?}");
    }

    /// Raised during the fourth of sixteen jittered passes, the frame stops
    /// there; the renderer's next frame equals a fresh renderer's.
    #[test]
    fn a_stop_during_jittered_passes_ends_them_and_leaves_the_renderer_whole() {
        let scene = small_demo(Antialias::Jitter(16));
        let mut renderer = Renderer::new(&RenderOptions::default()).unwrap();
        let (stop, passes) = (AtomicBool::new(false), AtomicU32::new(0));
        let progress = |done: u32, _| {
            passes.store(done, Ordering::Relaxed);
            if done == 3 {
                stop.store(true, Ordering::Relaxed);
            }
        };
        let out = renderer.render_watched(&scene, &progress, Stop(Some(&stop))).map(|_| ());
        assert!(matches!(out, Err(Error::Stopped)), "{out:?}");
        assert_eq!(passes.load(Ordering::Relaxed), 3, "no pass after the raise");
        let again = renderer.render(&scene).unwrap().image.clone();
        let fresh = crate::render(&scene, &RenderOptions::default()).unwrap().image;
        assert_eq!(again.pixels(), fresh.pixels());
    }
}
