//! The frame's shading passes, summed as seed 002 eq. 4 says.
//!
//! The paper renders ambient, diffuse and specular per light as separate hardware
//! passes and adds them. The sum does not depend on how terms are grouped into
//! passes, so kage groups them by what they need:
//!
//! 1. one pass replaces the buffer with emission, the ambient of every light that
//!    lights all objects, and the diffuse and specular — times its shadow term — of
//!    every such light whose shadow maps fit a memory budget together: one sweep
//!    reconstructs each pixel's surface once for all of them;
//! 2. then each remaining light — selective ones (§3.3), and shadowed ones past
//!    the budget — gets its own pass: its maps are rendered, its diffuse and
//!    specular (and, if selective, its ambient, on its objects only) are added,
//!    and its maps are dropped, so memory stays bounded however many lights there
//!    are, and time grows linearly with them.
//!
//! An area light (a point or spot light with a `size` and several shadow
//! samples) is shadowed by its jittered samples' maps, each rendered with the
//! light moved to another point of its disc (§3.3), but lit once: its diffuse
//! and specular at its centre times the mean of the samples' shadow terms. The
//! paper sums a full pass per moved light instead; the two differ only by how
//! N·L and the highlight vary across the disc (small for the small lights soft
//! shadows are for), one evaluation is what the reference renderer computes
//! (its shadow rays average over the disc, its Phong term is the centre's), and
//! it costs one Phong term instead of n.

use std::time::Instant;

use crate::idle::{IdleClock, IdleTime};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::lanes::OpenShares;
use super::reflection_map::{add_reflection_map, flat_background};
use super::visible::screen_surfaces;
use super::{
    shade_pass_finding_mirrors, Blend, Component, ComponentSet, Lighting, Mirror, ShadingPass, SubpixelShading,
};
use crate::image::LinearImage;
use crate::scene::{Light, Material, Scene};
use crate::shadows::{MapPool, PixelView, ScreenSurfaces, ShadowTerm};
use crate::visibility::VisibilityBuffer;

/// What the passes of one frame cost.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PassStats {
    /// Shading passes run.
    pub passes: u32,
    /// Milliseconds spent rendering shadow maps.
    pub shadow_ms: f64,
    /// Most bytes of shadow maps held at once.
    pub shadow_bytes: usize,
    /// Lights whose shadow maps were reused from the last frame (only the
    /// camera moved, or a jittered pass of the same frame).
    pub maps_reused: usize,
    /// The shadow stage's wall time and its workers' idle time (measured
    /// only where the pool asks: [`MapPool::measure_idle`]).
    pub shadow_idle: IdleTime,
}

/// An image a frame's passes write: the final image (every component) or one
/// component on its own.
#[derive(Debug)]
pub struct Target<'a> {
    /// The components this image receives.
    pub parts: ComponentSet,
    /// Where they go (the visibility buffer's size).
    pub image: &'a mut LinearImage,
}

/// Most bytes of shadow maps held at once for the first, fused pass.
pub const FUSED_SHADOW_BUDGET: usize = 64 << 20;

/// A scene light as a frame shades it.
#[derive(Debug, Clone)]
pub struct FrameLight {
    /// The light itself: its ambient, diffuse and specular terms.
    pub light: Light,
    /// The lights its shadow maps are rendered from: its jittered samples (an
    /// area light, §3.3; [`Light::jittered`]) or itself. The mean of their
    /// shadow terms is its shadow term.
    pub samples: Vec<Light>,
}

/// The lights a frame is shaded with: the scene's, each with its shadow samples.
#[must_use]
pub fn frame_lights(scene: &Scene) -> Vec<FrameLight> {
    frame_lights_within(scene, scene.caster_bounds().unwrap_or_default())
}

/// [`frame_lights`] with the bounds of the scene's shadow casters already
/// known ([`Scene::caster_bounds`]: what the maps are fitted to, and what an
/// area light's samples face).
pub(crate) fn frame_lights_within(scene: &Scene, (lo, hi): (Vec3, Vec3)) -> Vec<FrameLight> {
    let centre = (lo + hi) * 0.5;
    scene.lights.iter().map(|l| FrameLight { light: l.clone(), samples: l.jittered(centre) }).collect()
}

/// A frame's shadow terms made ready for its lookups — the one place that
/// does it, for the passes, the shadow images and the scalar reference: each
/// term set to look up the frame's pixels through the light's view
/// ([`light_view`]), a per-pixel term computed at every pixel from the
/// surfaces the pixels show (found once, when a per-pixel term first needs
/// them). Translucent layers, which lie off those surfaces, read the terms
/// without it.
pub(crate) struct ShadowFrame<'a> {
    scene: &'a Scene,
    vb: &'a VisibilityBuffer,
    bounds: (Vec3, Vec3),
    surfaces: Option<ScreenSurfaces<'a>>,
}

impl<'a> ShadowFrame<'a> {
    /// The frame of `scene` whose visibility buffer is `vb`, its shadow
    /// casters within `bounds` ([`Scene::caster_bounds`], found once by the caller).
    pub(crate) fn within(scene: &'a Scene, vb: &'a VisibilityBuffer, bounds: (Vec3, Vec3)) -> ShadowFrame<'a> {
        ShadowFrame { scene, vb, bounds, surfaces: None }
    }

    /// The surface each pixel shows (found on the first call).
    pub(crate) fn surfaces(&mut self) -> &ScreenSurfaces<'a> {
        let (scene, vb) = (self.scene, self.vb);
        self.surfaces.get_or_insert_with(|| screen_surfaces(scene, vb))
    }

    /// Makes `term`, one of `light`'s samples' terms, ready for this frame's
    /// lookups.
    pub(crate) fn ready(&mut self, light: &FrameLight, term: &mut ShadowTerm) {
        term.set_view(light_view(self.scene, light));
        if term.per_pixel() {
            term.prepare(self.surfaces());
        }
    }

    /// The shadow terms of `light`'s samples (taken from `pool`: last frame's
    /// where they still hold), made ready, all timed into `stats`.
    fn terms(&mut self, light: &FrameLight, pool: &mut MapPool, stats: &mut PassStats) -> Vec<ShadowTerm> {
        let t = Instant::now();
        let clock = pool.measures_idle().then(IdleClock::start);
        let mut terms = pool.terms(self.scene, &light.samples, self.bounds);
        terms.iter_mut().for_each(|term| self.ready(light, term));
        stats.shadow_ms += t.elapsed().as_secs_f64() * 1e3;
        if let Some(clock) = clock {
            stats.shadow_idle = stats.shadow_idle.plus(clock.stop());
        }
        terms
    }
}

/// The view `light`'s shadow terms look up `scene`'s pixels through: its
/// pixel rays when the light has one sample, none for an area light's
/// jittered samples (they average their edges already: antialiasing each
/// would cost as much again for little).
fn light_view(scene: &Scene, light: &FrameLight) -> Option<PixelView> {
    let rays = scene.camera.pixel_rays(Vec2::new(scene.width as f32, scene.height as f32));
    (light.samples.len() == 1).then(|| PixelView::new(&rays))
}

/// Shades `vb` with every light of `scene`, shadows included, into each target:
/// each pass runs once per target, restricted to the target's components, so the
/// shadow maps of a light are rendered once for all targets. Map buffers come
/// from `pool` and go back to it. Every pass is also added at the `subpixel`
/// samples.
pub fn shade_lit(
    scene: &Scene,
    vb: &VisibilityBuffer,
    targets: &mut [Target],
    pool: &mut MapPool,
    subpixel: &mut SubpixelShading,
) -> PassStats {
    shade_lit_beside(scene, vb, targets, pool, subpixel, None, |_| {})
}

/// [`shade_lit`] with the sub-pixel samples set up by `beside` while the
/// first pass shades the pixels: work that needs only the visibility buffer
/// (the edge pass's plan) fills the gaps the pixels' shading leaves on the
/// workers, instead of running before it. The samples get every pass, the
/// first included (shaded beside the pixels too, once `beside` is done).
/// With `open`, every pass's ambient term is scaled by each pixel's open
/// share at the pixels (not at the sub-pixel samples).
pub fn shade_lit_beside(
    scene: &Scene,
    vb: &VisibilityBuffer,
    targets: &mut [Target],
    pool: &mut MapPool,
    subpixel: &mut SubpixelShading,
    open: Option<OpenShares>,
    beside: impl FnOnce(&mut SubpixelShading) + Send,
) -> PassStats {
    let mut stats = PassStats::default();
    // The casters are found once for the pool, the lights and the frame.
    let (casters, bounds) = scene.shadow_casters();
    let bounds = bounds.unwrap_or_default();
    pool.begin_frame_drawing(scene, casters);
    let mut budget = FUSED_SHADOW_BUDGET;
    let lights = frame_lights_within(scene, bounds);
    let mut frame = ShadowFrame::within(scene, vb, bounds);
    let (mut fused, mut own) = (Vec::new(), Vec::new());
    for light in &lights {
        let bytes: usize = light.samples.iter().map(|s| ShadowTerm::bytes_needed(s, bounds)).sum();
        if light.light.only.is_none() && bytes <= budget {
            budget -= bytes;
            fused.push((light, frame.terms(light, pool, &mut stats)));
        } else {
            own.push(light);
        }
    }
    stats.shadow_bytes = FUSED_SHADOW_BUDGET - budget;
    let direct = fused.iter().map(|(l, t)| (&l.light, t.as_slice())).collect();
    let ambient = lights.iter().map(|l| &l.light).filter(|l| l.only.is_none());
    let first = Lighting::pass(ambient, direct, true).with_open(open);
    let first = LitPass { lighting: &first, blend: Blend::Replace, receivers: None };
    let mut mirrors = mirror_buffer(scene, vb, targets);
    run(scene, vb, targets, subpixel, first, beside, mirrors.as_deref_mut());
    stats.passes = 1;
    // The fused terms stay for the next frame (within the same budget).
    for (light, terms) in fused {
        light.samples.iter().zip(terms).for_each(|(s, term)| pool.keep(scene, s, bounds, term));
    }
    for frame_light in own {
        let terms = frame.terms(frame_light, pool, &mut stats);
        let light = &frame_light.light;
        stats.shadow_bytes = stats.shadow_bytes.max(terms.iter().map(ShadowTerm::memory_bytes).sum());
        let receivers = light.only.as_ref().map(|only| (0..scene.objects.len()).map(|i| only.contains(&i)).collect());
        // A light that lights every object had its ambient added in the first pass.
        let ambient = light.only.is_some().then_some(light);
        let lighting = Lighting::pass(ambient, vec![(light, &terms)], false).with_open(open);
        let pass = LitPass { lighting: &lighting, blend: Blend::Add, receivers };
        run(scene, vb, targets, subpixel, pass, |_| {}, None);
        stats.passes += 1;
        terms.into_iter().for_each(|t| pool.recycle(t));
    }
    add_reflection_map(scene, vb, targets, mirrors.as_deref());
    stats.maps_reused = pool.reused();
    stats
}

/// What one lit pass adds, and how: its lighting, whether it replaces or adds,
/// and which objects receive it (`None`: all).
struct LitPass<'a> {
    lighting: &'a Lighting<'a>,
    blend: Blend,
    receivers: Option<Vec<bool>>,
}

/// Most pixels whose [`Mirror`]s the first pass hands the reflection-map pass
/// (24 bytes each: a 3840 × 2160 frame's are 200 MB); a larger frame's pass
/// finds them itself, a band of rows at a time.
const MIRROR_PIXELS: usize = 3840 * 2160;

/// A buffer for each pixel's [`Mirror`] when the frame draws a reflection
/// map (an environment, a material with a Km, a target with the reflection
/// component) in an image of at most [`MIRROR_PIXELS`].
fn mirror_buffer(scene: &Scene, vb: &VisibilityBuffer, targets: &[Target]) -> Option<Vec<Mirror>> {
    // Chosen by the whole image's size, so that a tile of a frame takes the
    // same path as the frame.
    let image = vb.width() as usize * vb.height() as usize;
    let wanted = scene.environment.is_some()
        && scene.materials.iter().any(Material::reflects_environment)
        && targets.iter().any(|t| t.parts.contains(Component::Reflection))
        && image <= MIRROR_PIXELS;
    let held = vb.rect();
    let pixels = held.width() as usize * held.height() as usize;
    wanted.then(|| {
        let mut buffer = Vec::new();
        (0..pixels).into_par_iter().map(|_| Mirror::NONE).collect_into_vec(&mut buffer);
        buffer
    })
}

/// One pass into every target and, beside it, at every sub-pixel sample, once
/// `prepare` has set them up; the first target's pass writes `mirrors`.
fn run(
    scene: &Scene,
    vb: &VisibilityBuffer,
    targets: &mut [Target],
    subpixel: &mut SubpixelShading,
    pass: LitPass,
    prepare: impl FnOnce(&mut SubpixelShading) + Send,
    mut mirrors: Option<&mut [Mirror]>,
) {
    let LitPass { lighting, blend, receivers } = pass;
    let pixels = || {
        for t in targets {
            let lighting = lighting.restricted(t.parts);
            if blend == Blend::Add && lighting.is_empty() {
                continue;
            }
            let background = if t.parts.contains(Component::Emission) { flat_background(scene) } else { Vec3::ZERO };
            let pass = ShadingPass { lighting, blend, background, receivers: receivers.clone() };
            shade_pass_finding_mirrors(scene, vb, t.image, &pass, mirrors.take());
        }
    };
    let samples = || {
        prepare(subpixel);
        subpixel.add_pass(lighting, receivers.as_deref());
    };
    rayon::join(samples, pixels);
}
