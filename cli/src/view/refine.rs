//! Renders the viewer's steps: the scene as the toggles and the refinement
//! step set it (quick frames with plain maps and no edge pass, the full
//! frame, jittered passes averaged), and what the window shows of the frame
//! (the image, a component, the shadow term, depth, normals, items).

use glam::Vec3;
use kage::image::{LinearImage, ToneCurve};
use kage::scene::{Antialias, Light, Scene, ShadowMethod, ShadowSettings};
use kage::shading::ComponentSet;
use kage::{FrameStats, RenderOptions, Renderer};

use super::state::{Display, Shadows, Smoothing, Step, Viewer, MAX_PASSES};

/// Jittered passes averaged before the average replaces the full frame on
/// screen (fewer look noisier than the edge pass's frame).
pub const SHOWN_FROM_PASS: u32 = 4;

/// What the window shows: linear colour, how to map it to the screen, and
/// the frame it came from.
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
}

/// Renders steps and keeps the accumulation of jittered passes.
pub struct Refiner {
    renderer: Option<(RenderOptions, Renderer)>,
    threads: Option<usize>,
    /// The sum of the jittered passes so far.
    sum: LinearImage,
    passes: u32,
    /// What is on screen.
    pub shown: Shown,
}

impl Refiner {
    /// A refiner rendering on `threads` workers (`None`: one per core).
    #[must_use]
    pub fn new(threads: Option<usize>) -> Refiner {
        Refiner { renderer: None, threads, sum: LinearImage::default(), passes: 0, shown: Shown::default() }
    }

    /// Renders `step` of `base` as `viewer` sets it up; updates what is
    /// shown (a jittered pass only once [`SHOWN_FROM_PASS`] are averaged).
    ///
    /// # Errors
    ///
    /// When the scene cannot be rendered (too large for the limits).
    pub fn render(&mut self, base: &Scene, viewer: &Viewer, step: Step) -> kage::error::Result<()> {
        let scene = scene_for(base, viewer, step);
        let options = RenderOptions {
            threads: self.threads,
            ray_depth: if viewer.toggles.traced { RenderOptions::default().ray_depth } else { 0 },
            aovs: match viewer.display {
                Display::Component(c) => ComponentSet::of(&[c]),
                _ => ComponentSet::EMPTY,
            },
            shadow_images: viewer.display == Display::Shadow,
            ..RenderOptions::default()
        };
        if self.renderer.as_ref().is_none_or(|(o, _)| *o != options) {
            self.renderer = Some((options, Renderer::new(&options)?));
        }
        let (_, renderer) = self.renderer.as_mut().expect("made above");
        let frame = renderer.render(&scene)?;
        let image = shown_image(&scene, frame, viewer.display);
        let is_image = viewer.display == Display::Image;
        let stats = frame.stats;
        match step {
            Step::Pass(n) => {
                if n == 1 || self.sum.width() != image.width() || self.sum.height() != image.height() {
                    self.sum = LinearImage::new(image.width(), image.height());
                    self.passes = 0;
                }
                self.sum.pixels_mut().iter_mut().zip(image.pixels()).for_each(|(s, p)| *s += *p);
                self.passes += 1;
                if self.passes >= SHOWN_FROM_PASS {
                    let mut mean = self.sum.clone();
                    let k = 1.0 / self.passes as f32;
                    mean.pixels_mut().iter_mut().for_each(|p| *p *= k);
                    let (scale, tone) = (self.shown.scale, self.shown.tone);
                    self.shown = Shown { image: mean, scale, tone, stats, passes: self.passes };
                }
            }
            Step::Quick | Step::Full => {
                let (scale, tone) =
                    if is_image { (scene.exposure.scale(&image), scene.tone) } else { (1.0, ToneCurve::Clip) };
                self.shown = Shown { image, scale, tone, stats, passes: 0 };
            }
        }
        Ok(())
    }
}

/// `base` as `viewer` and `step` set it up: the orbit's camera at the
/// window's size, the toggles' shadows, smoothing, fog; a quick step with
/// plain maps in place of costlier shadows and no edge pass; a jittered pass
/// shifted to its sub-pixel point (those of `--antialias jitter:64`), each
/// jittered light shadowed from that pass's own point of its disc.
#[must_use]
pub fn scene_for(base: &Scene, viewer: &Viewer, step: Step) -> Scene {
    let mut scene = base.clone();
    (scene.width, scene.height) = viewer.size;
    let bounds = base.bounds().unwrap_or(viewer.bounds);
    scene.camera = viewer.orbit.camera(bounds);
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
        // silhouette-line buffers, the per-pixel soft term) as one plain map.
        for light in scene.lights.iter_mut().filter(|l| costly(l)) {
            light.shadow = ShadowSettings { samples: 1, ..light.shadow.with_method(ShadowMethod::Map) };
        }
    }
    if !t.fog {
        scene.fog = None;
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
        scene.camera = kage::resolve::jitter::shifted(&scene.camera, offset, viewer.size);
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

/// What `display` shows of `frame` (rendered from `scene`), as linear colour.
fn shown_image(scene: &Scene, frame: &kage::Frame, display: Display) -> LinearImage {
    let (w, h) = (frame.image.width(), frame.image.height());
    let mut out = LinearImage::new(w, h);
    let vb = &frame.visibility;
    match display {
        Display::Image => return frame.image.clone(),
        Display::Component(c) => {
            if let Some((_, image)) = frame.aovs.iter().find(|(k, _)| *k == c) {
                return image.clone();
            }
        }
        Display::Shadow => {
            let first = scene.lights.iter().position(|l| l.shadow.method != ShadowMethod::None);
            if let Some(image) = first.and_then(|i| frame.shadows.get(i)) {
                return image.clone();
            }
            out.pixels_mut().fill(Vec3::ONE);
        }
        Display::Depth => {
            let seen: Vec<f32> = vb.depths().iter().copied().filter(|d| d.is_finite()).collect();
            let (near, far) = seen.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &d| (a.min(d), b.max(d)));
            let span = (far - near).max(1e-9);
            for (p, &d) in out.pixels_mut().iter_mut().zip(vb.depths()) {
                *p = if d.is_finite() { Vec3::splat(1.0 - 0.9 * (d - near) / span) } else { Vec3::ZERO };
            }
        }
        Display::Normals => {
            let surfaces = kage::shading::screen_surfaces(scene, vb);
            for (p, s) in out.pixels_mut().iter_mut().zip(&surfaces.surfaces) {
                *p = s.map_or(Vec3::ZERO, |s| s.normal * 0.5 + 0.5);
            }
        }
        Display::Items => {
            for (p, item) in out.pixels_mut().iter_mut().zip(vb.items()) {
                *p = if item.is_none() { Vec3::ZERO } else { false_colour(item.object) };
            }
        }
    }
    out
}

/// A bright colour of its own for object `id`.
fn false_colour(id: u32) -> Vec3 {
    let h = id.wrapping_mul(0x9E37_79B9).rotate_left(7) ^ 0x5bd1_e995;
    let c = |s: u32| 0.25 + 0.75 * ((h >> s) & 0xff) as f32 / 255.0;
    Vec3::new(c(0), c(8), c(16))
}
