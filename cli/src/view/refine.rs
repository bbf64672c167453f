//! Renders the viewer's steps: the scene as the toggles and the refinement
//! step set it (quick frames with plain maps and no edge pass, the full
//! frame, jittered passes averaged), and what the window shows of the frame
//! (the image, a component, the shadow term, depth, normals, items).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use glam::Vec3;
use kage::image::{LinearImage, ToneCurve};
use kage::scene::material::Filter;
use kage::scene::{AmbientOcclusion, Antialias, Light, Scene, ShadowMethod, ShadowSettings};
use kage::ComponentSet;
use kage::{FrameStats, RenderOptions, Renderer};
use rayon::prelude::*;

use super::state::{Display, LineStyle, Shadows, Smoothing, Step, Viewer, MAX_PASSES};

/// Jittered passes averaged before the average replaces the full frame on
/// screen (fewer look noisier than the edge pass's frame).
pub const SHOWN_FROM_PASS: u32 = 4;

/// Ambient-occlusion rays a pixel casts in each jittered pass (new ones each
/// pass): the full frame casts the scene's (16 by default), 64 passes 256.
pub const PASS_OCCLUSION_RAYS: u32 = 4;

/// What the window shows: linear colour, how to map it to the screen, and
/// the frame it came from. The rendering thread writes it in place (its
/// buffers kept from frame to frame: a new 1280 × 720 image a frame costs
/// page faults worth several milliseconds), the window copies `screen` out.
#[derive(Debug, Clone, Default)]
pub struct Shown {
    /// Linear colour, row by row.
    pub image: LinearImage,
    /// Exposure multiplier.
    pub scale: f32,
    /// Tone curve.
    pub tone: ToneCurve,
    /// The last frame's statistics.
    pub stats: FrameStats,
    /// Jittered passes in `image` (0: a single frame).
    pub passes: u32,
    /// `image` as the screen shows it: 0RGB words, 8-bit sRGB through the
    /// tone curve (made on the rendering thread, in parallel).
    pub screen: Vec<u32>,
}

/// The lock on what is shown (a thread that panicked holding it left
/// nothing half-written that matters more than the window staying up).
pub fn lock(shown: &Mutex<Shown>) -> MutexGuard<'_, Shown> {
    shown.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Renders steps and keeps the accumulation of jittered passes.
pub struct Refiner {
    renderer: Option<Renderer>,
    threads: Option<usize>,
    /// The sum of the jittered passes so far.
    sum: LinearImage,
    passes: u32,
    /// A pass's image when what is shown is not the image itself.
    pass_image: LinearImage,
    /// The exposure and tone curve of the last full frame, which the average
    /// of the passes keeps.
    look: (f32, ToneCurve),
}

impl Refiner {
    /// A refiner rendering on `threads` workers (`None`: one per core).
    #[must_use]
    pub fn new(threads: Option<usize>) -> Refiner {
        Refiner {
            renderer: None,
            threads,
            sum: LinearImage::default(),
            passes: 0,
            pass_image: LinearImage::default(),
            look: (1.0, ToneCurve::Clip),
        }
    }

    /// Renders `step` of `base` as `viewer` sets it up, giving up between
    /// stages once `stop` is raised, and writes what to show into `shown`
    /// (a jittered pass only once [`SHOWN_FROM_PASS`] are averaged); returns
    /// the frame's statistics.
    ///
    /// # Errors
    ///
    /// [`kage::Error::Stopped`] when `stop` was raised (`shown` is left as
    /// it was); when the scene cannot be rendered (too large for the limits).
    pub fn render(
        &mut self,
        base: &Scene,
        viewer: &Viewer,
        step: Step,
        stop: &AtomicBool,
        shown: &Mutex<Shown>,
    ) -> kage::error::Result<FrameStats> {
        let scene = scene_for(base, viewer, step);
        let options = RenderOptions {
            threads: self.threads,
            ray_depth: if viewer.toggles.traced { RenderOptions::default().ray_depth } else { 0 },
            aovs: match viewer.display {
                Display::Component(c) => ComponentSet::of(&[c]),
                _ => ComponentSet::EMPTY,
            },
            shadow_images: viewer.display == Display::Shadow,
            // A moving camera's reflections: a quarter of the rays.
            sparse_traced: step == Step::Quick,
            ..RenderOptions::default()
        };
        let renderer = match &mut self.renderer {
            Some(r) => {
                r.set_options(&options)?;
                r
            }
            None => self.renderer.insert(Renderer::new(&options)?),
        };
        let frame = renderer.render_or_stop(&scene, stop)?;
        let stats = frame.stats;
        let display = viewer.display;
        let Step::Pass(n) = step else {
            return publish(shown, stop, stats, 0, |image| {
                display_image(&scene, frame, display, image);
                self.look = if display == Display::Image {
                    (scene.exposure.scale(image), scene.tone)
                } else {
                    (1.0, ToneCurve::Clip)
                };
                self.look
            });
        };
        let image = if display == Display::Image {
            &frame.image
        } else {
            display_image(&scene, frame, display, &mut self.pass_image);
            &self.pass_image
        };
        if n == 1 || self.sum.width() != image.width() || self.sum.height() != image.height() {
            self.sum = LinearImage::new(image.width(), image.height());
            self.passes = 0;
        }
        self.sum.pixels_mut().par_iter_mut().zip(image.pixels().par_iter()).for_each(|(s, p)| *s += *p);
        self.passes += 1;
        if self.passes < SHOWN_FROM_PASS {
            return Ok(stats);
        }
        let (sum, look, k) = (&self.sum, self.look, 1.0 / self.passes as f32);
        publish(shown, stop, stats, self.passes, |image| {
            image.resize(sum.width(), sum.height());
            image.pixels_mut().par_iter_mut().zip(sum.pixels().par_iter()).for_each(|(o, s)| *o = *s * k);
            look
        })
    }
}

/// Writes what is shown, unless `stop` is raised: `fill` writes the linear
/// image and gives its exposure and tone curve; the screen's words, the
/// frame's `stats` and the `passes` averaged follow. Returns `stats`.
fn publish(
    shown: &Mutex<Shown>,
    stop: &AtomicBool,
    stats: FrameStats,
    passes: u32,
    fill: impl FnOnce(&mut LinearImage) -> (f32, ToneCurve),
) -> kage::error::Result<FrameStats> {
    let mut out = lock(shown);
    if stop.load(Ordering::Relaxed) {
        return Err(kage::Error::Stopped);
    }
    let Shown { image, scale, tone, stats: shown_stats, passes: shown_passes, screen } = &mut *out;
    (*scale, *tone) = fill(image);
    (*shown_stats, *shown_passes) = (stats, passes);
    image.to_0rgb_toned_into(*scale, *tone, screen);
    Ok(stats)
}

/// `base` as `viewer` and `step` set it up: the orbit's camera at the
/// window's size, the toggles' shadows, smoothing, fog, ambient occlusion
/// (none in a quick step, new rays each jittered pass); a quick step with
/// plain maps in place of costlier shadows and no edge pass; a jittered pass
/// shifted to its sub-pixel point (those of `--antialias jitter:64`), each
/// jittered light shadowed from that pass's own point of its disc.
#[must_use]
pub fn scene_for(base: &Scene, viewer: &Viewer, step: Step) -> Scene {
    let mut scene = base.clone();
    (scene.width, scene.height) = viewer.size;
    scene.camera = viewer.orbit.camera(viewer.bounds);
    let t = viewer.toggles;
    let shadows = if step == Step::Quick && t.shadows.costly() { Shadows::All(ShadowMethod::Map) } else { t.shadows };
    for light in &mut scene.lights {
        match shadows {
            Shadows::Scene => {}
            Shadows::All(method) => light.shadow = light.shadow.with_method(method),
            Shadows::Jittered(_) => light.shadow = light.shadow.with_method(ShadowMethod::Map),
        }
        if let Shadows::Jittered(n) = shadows {
            light.shadow.samples = n;
        } else if shadows != Shadows::Scene {
            light.shadow.samples = 1;
        }
    }
    if step == Step::Quick {
        // A moving camera: each light's costlier shadows (jittered maps,
        // silhouette-line buffers, the per-pixel soft term) as one plain map,
        // and textures read at one mip level, not blended between two.
        for light in scene.lights.iter_mut().filter(|l| costly(l)) {
            light.shadow = ShadowSettings { samples: 1, ..light.shadow.with_method(ShadowMethod::Map) };
        }
        for m in scene.materials.iter_mut().filter(|m| m.maps.filter == Filter::Trilinear) {
            m.maps.filter = Filter::NearestLevel;
        }
    }
    if !t.fog {
        scene.fog = None;
    }
    if t.xray {
        scene.xray(kage::scene::XRAY_OPACITY);
    }
    match t.lines {
        LineStyle::Off => scene.lines = None,
        LineStyle::Lines => scene.lines = Some(scene.lines.unwrap_or_default()),
        LineStyle::Drawing => scene.drawing(),
    }
    scene.ambient_occlusion = match step {
        _ if !t.ao => None,
        // A moving camera: the screen-space estimate (rays cost several
        // frames' time).
        Step::Quick => Some(AmbientOcclusion { screen_space: true, ..scene.ambient_occlusion.unwrap_or_default() }),
        Step::Full => Some(scene.ambient_occlusion.unwrap_or_default()),
        // Each pass casts PASS_OCCLUSION_RAYS new rays a pixel: 64 passes, 256.
        Step::Pass(n) => Some(AmbientOcclusion {
            rays: PASS_OCCLUSION_RAYS,
            pass: n.clamp(1, MAX_PASSES) - 1,
            ..scene.ambient_occlusion.unwrap_or_default()
        }),
    };
    if !t.ghosts {
        scene.objects.retain(|o| !o.ghost);
    }
    scene.antialias = match step {
        Step::Full if t.smoothing != Smoothing::None => match base.antialias {
            edge @ Antialias::Edge(_) => edge,
            _ => Antialias::Edge(Default::default()),
        },
        _ => Antialias::None,
    };
    if let Step::Pass(n) = step {
        let n = n.clamp(1, MAX_PASSES);
        let offset = Antialias::Jitter(MAX_PASSES).offsets()[(n - 1) as usize];
        scene.camera = scene.camera.shifted(offset, viewer.size);
        // A jittered light is shadowed from one point of its disc a pass, a
        // new one each pass: 64 passes average 64 points, for the cost of one
        // map a pass instead of all of them.
        for light in scene.lights.iter_mut().filter(|l| jittered(l)) {
            light.shadow.samples = MAX_PASSES;
            light.shadow.only_sample = Some(n);
        }
    }
    scene
}

/// Whether a light's shadows cost more than one plain map (jittered maps
/// over its disc, a silhouette-line buffer, the two-map soft term).
#[must_use]
pub fn costly(light: &Light) -> bool {
    jittered(light) || matches!(light.shadow.method, ShadowMethod::Slb | ShadowMethod::Soft)
}

/// Whether a light's soft shadow comes from maps jittered over its disc.
fn jittered(light: &Light) -> bool {
    light.size > 0.0 && light.shadow.samples > 1 && matches!(light.shadow.method, ShadowMethod::Map | ShadowMethod::Slb)
}

/// What `display` shows of `frame` (rendered from `scene`), as linear
/// colour, into `out` (resized to the frame).
fn display_image(scene: &Scene, frame: &kage::Frame, display: Display, out: &mut LinearImage) {
    out.resize(frame.image.width(), frame.image.height());
    let vb = &frame.visibility;
    let copy = |out: &mut LinearImage, from: &LinearImage| out.pixels_mut().copy_from_slice(from.pixels());
    match display {
        Display::Image => copy(out, &frame.image),
        Display::Component(c) => match frame.aovs.iter().find(|(k, _)| *k == c) {
            Some((_, image)) => copy(out, image),
            None => out.pixels_mut().fill(Vec3::ZERO),
        },
        Display::Shadow => {
            let first = scene.lights.iter().position(kage::scene::Light::casts_shadows);
            match first.and_then(|i| frame.shadows.get(i)) {
                Some(image) => copy(out, image),
                None => out.pixels_mut().fill(Vec3::ONE),
            }
        }
        Display::Occlusion if frame.occlusion.pixels().len() == out.pixels().len() => copy(out, &frame.occlusion),
        Display::Occlusion => out.pixels_mut().fill(Vec3::ONE),
        Display::Depth => {
            let seen = vb.depths().iter().copied().filter(|d| d.is_finite());
            let (near, far) = seen.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), d| (a.min(d), b.max(d)));
            let span = (far - near).max(1e-9);
            for (p, &d) in out.pixels_mut().iter_mut().zip(vb.depths()) {
                *p = if d.is_finite() { Vec3::splat(1.0 - 0.9 * (d - near) / span) } else { Vec3::ZERO };
            }
        }
        Display::Normals => {
            for (p, n) in out.pixels_mut().iter_mut().zip(frame.normals(scene)) {
                *p = if n == Vec3::ZERO { Vec3::ZERO } else { n * 0.5 + 0.5 };
            }
        }
        Display::Items => {
            for (p, item) in out.pixels_mut().iter_mut().zip(vb.items()) {
                *p = if item.is_none() { Vec3::ZERO } else { false_colour(item.object) };
            }
        }
    }
}

/// A bright colour of its own for object `id`.
fn false_colour(id: u32) -> Vec3 {
    let h = id.wrapping_mul(0x9E37_79B9).rotate_left(7) ^ 0x5bd1_e995;
    let c = |s: u32| 0.25 + 0.75 * ((h >> s) & 0xff) as f32 / 255.0;
    Vec3::new(c(0), c(8), c(16))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::orbit::Orbit;
    use glam::Vec3;

    #[test]
    fn ambient_occlusion_is_screen_space_in_quick_frames_and_casts_new_rays_each_pass() {
        let base = kage::scene::demo::demo_scene().expect("the demo");
        let orbit = Orbit::from_camera(&base.camera);
        let mut viewer = Viewer::new(orbit, (Vec3::splat(-1.0), Vec3::ONE), (320, 180));
        let ao = |viewer: &Viewer, step| scene_for(&base, viewer, step).ambient_occlusion;
        let off = [ao(&viewer, Step::Quick), ao(&viewer, Step::Full), ao(&viewer, Step::Pass(3))];
        assert_eq!(off, [None; 3], "off until O");
        viewer.toggles.ao = true;
        let ao = |step| ao(&viewer, step);
        assert!(ao(Step::Quick).is_some_and(|a| a.screen_space), "quick frames: from the depth buffer");
        assert_eq!(ao(Step::Full), Some(AmbientOcclusion::default()));
        let passes: Vec<(u32, u32)> =
            (1..=MAX_PASSES).map(|n| ao(Step::Pass(n)).map(|a| (a.pass, a.rays)).expect("on")).collect();
        assert!(passes.iter().enumerate().all(|(k, &p)| p == (k as u32, PASS_OCCLUSION_RAYS)), "{passes:?}");
    }

    #[test]
    fn l_draws_the_scenes_lines_then_a_technical_drawing_in_every_step() {
        let base = kage::scene::demo::demo_scene().expect("the demo");
        let orbit = Orbit::from_camera(&base.camera);
        let mut viewer = Viewer::new(orbit, (Vec3::splat(-1.0), Vec3::ONE), (320, 180));
        let with_lines =
            Scene { lines: Some(kage::scene::FeatureLines { width: 3.0, ..Default::default() }), ..base.clone() };
        assert_eq!(scene_for(&with_lines, &viewer, Step::Full).lines, None, "L off leaves even the scene's lines out");
        viewer.toggles.lines = LineStyle::Lines;
        for step in [Step::Quick, Step::Full, Step::Pass(5)] {
            assert_eq!(scene_for(&base, &viewer, step).lines, Some(Default::default()));
            assert_eq!(scene_for(&with_lines, &viewer, step).lines.map(|l| l.width), Some(3.0), "the scene's own");
        }
        viewer.toggles.lines = LineStyle::Drawing;
        let drawing = scene_for(&base, &viewer, Step::Quick);
        assert!(drawing.lines.is_some_and(|l| l.hidden), "hidden lines dashed");
        assert_eq!(drawing.background, Vec3::ONE);
        assert_eq!(drawing.objects.len(), base.objects.len() - 1, "the ground left out");
    }
}
