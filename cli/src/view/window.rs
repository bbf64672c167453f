//! The window: winit for events, softbuffer for a CPU frame buffer (X11 or
//! Wayland, no GPU). The refinement's steps render one at a time on a thread
//! of their own ([`super::worker`]); the window shows each as it arrives and
//! takes input meanwhile. Input that starts the refinement over gives up the
//! step rendering (a quick frame excepted) before its next stage.

use std::collections::VecDeque;
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use kage::scene::load::InputFormat;
use kage::Scene;
use notify::Watcher;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{Key as WinitKey, NamedKey};
use winit::window::{Window, WindowId};

use super::hud::Text;
use super::orbit::Orbit;
use super::refine::{lock, Shown};
use super::script::Action;
use super::source::Source;
use super::state::{Button, Display, Input, Key, Request, Smoothing, Step, Viewer, MAX_PASSES};
use super::worker::{Done, Job, Outcome, Worker};

/// The colour of a load error drawn over the image (0xRRGGBB).
pub const ERROR_COLOUR: u32 = 0x00ff_4040;

/// What wakes the event loop from outside it.
#[derive(Debug, Clone)]
pub enum Wake {
    /// A watched file changed.
    FileChanged,
    /// The rendering thread finished with a step.
    Rendered(Box<Done>),
}

/// How `kage view` starts.
#[derive(Debug, Clone)]
pub struct Start {
    /// What to show.
    pub source: Source,
    /// Window size asked on the command line.
    pub size: Option<(u32, u32)>,
    /// Scripted input.
    pub script: Vec<Action>,
    /// Worker threads.
    pub threads: Option<usize>,
    /// Print frame timings when the window closes.
    pub timings: bool,
}

/// What the viewer says when it cannot open a window.
const NO_DISPLAY: &str = "no display to open a window on: set DISPLAY (or WAYLAND_DISPLAY), or run under xvfb-run";

/// Runs the viewer until its window closes.
///
/// # Errors
///
/// When no window can be opened (no display) or the event loop fails.
pub fn run(start: Start) -> Result<(), String> {
    let started = Instant::now();
    let unix_desktop = cfg!(all(unix, not(target_os = "macos")));
    if unix_desktop && std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        return Err(NO_DISPLAY.into());
    }
    // winit's error names a source file of its own: say what to do instead.
    let event_loop = EventLoop::<Wake>::with_user_event().build().map_err(|_| NO_DISPLAY.to_string())?;
    let timings = start.timings;
    let mut app = App::new(start, event_loop.create_proxy());
    app.clock.started = started;
    event_loop.run_app(&mut app).map_err(|e| e.to_string())?;
    if timings {
        println!("{}", app.clock.summary());
    }
    app.failure.map_or(Ok(()), Err)
}

/// When frames were shown: for `--timings` and benchmarks.
#[derive(Debug)]
struct Clock {
    started: Instant,
    first_image: Option<Duration>,
    /// Milliseconds of each quick frame (while the camera moves).
    quick_ms: Vec<f64>,
    /// Milliseconds by stage (visibility, shadows, shading, traced, edges)
    /// summed over the quick frames, and over the jittered passes, with how
    /// many were summed.
    stages: [(u32, [f64; 5]); 2],
    /// The last input that started the refinement over.
    last_input: Option<Instant>,
    /// From an input to the refinement's end, each time it ended.
    to_rest: Vec<Duration>,
    /// The last input no frame has been shown for yet.
    unanswered: Option<Instant>,
    /// From an input to the first frame rendered after it.
    to_image: Vec<Duration>,
    /// When the step rendering was asked to stop, if it was.
    stop_raised: Option<Instant>,
    /// From asking a step to stop to hearing it stopped, each time.
    to_stop: Vec<Duration>,
    /// When the last quick frame was shown, while quick frames follow each
    /// other.
    last_quick: Option<Instant>,
    /// Between one quick frame shown and the next: the rate a moving camera
    /// sees.
    quick_apart: Vec<Duration>,
    /// Milliseconds of each presentation (the image copied, text drawn, the
    /// buffer handed to the window system).
    present_ms: Vec<f64>,
}

impl Clock {
    fn new() -> Clock {
        Clock {
            started: Instant::now(),
            first_image: None,
            quick_ms: Vec::new(),
            stages: [(0, [0.0; 5]); 2],
            last_input: None,
            to_rest: Vec::new(),
            unanswered: None,
            to_image: Vec::new(),
            stop_raised: None,
            to_stop: Vec::new(),
            last_quick: None,
            quick_apart: Vec::new(),
            present_ms: Vec::new(),
        }
    }

    /// A line of figures: time to the first image, quick frames (median ms
    /// to render, median ms between two shown, frames per second), input to
    /// fully refined and input to the next image (medians).
    fn summary(&self) -> String {
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            (v.len(), v.get(v.len() / 2).copied())
        };
        // A figure that was never measured (no quick frame, no input) is "-",
        // not NaN.
        let show = |v: Option<f64>, digits: usize| v.map_or_else(|| "-".to_string(), |x| format!("{x:.digits$}"));
        let ms = |d: &[Duration]| d.iter().map(|d| d.as_secs_f64() * 1e3).collect::<Vec<f64>>();
        let (quick, median_quick) = median(self.quick_ms.clone());
        let (rested, rest) = median(ms(&self.to_rest));
        let (answered, answer) = median(ms(&self.to_image));
        let (stopped, stop) = median(ms(&self.to_stop));
        let (_, apart) = median(ms(&self.quick_apart));
        let (_, present) = median(self.present_ms.clone());
        let mean = |(n, sum): (u32, [f64; 5])| {
            if n == 0 {
                return "-".to_string();
            }
            let s = sum.map(|t| t / f64::from(n));
            format!(
                "visibility {:.1}, shadows {:.1}, shading {:.1}, traced {:.1}, edges {:.1}",
                s[0], s[1], s[2], s[3], s[4]
            )
        };
        format!(
            "first image {} ms; {quick} quick frames, median {} ms to render, one shown every {} ms ({} fps; mean \
             ms: {}); presenting median {} ms; {} jittered passes, mean ms: {}; refined {rested} times, median {} ms \
             after the input; new image {answered} times, median {} ms after the input; {stopped} steps given up, \
             median {} ms after the input",
            show(self.first_image.map(|d| d.as_secs_f64() * 1e3), 0),
            show(median_quick, 1),
            show(apart, 1),
            show(apart.filter(|&a| a > 0.0).map(|a| 1e3 / a), 1),
            mean(self.stages[0]),
            show(present, 1),
            self.stages[1].0,
            mean(self.stages[1]),
            show(rest, 0),
            show(answer, 0),
            show(stop, 1),
        )
    }
}

impl Clock {
    /// Adds a quick frame's or a pass's stage timings to the sums.
    fn count(&mut self, step: Step, st: &kage::FrameStats) {
        let (n, sum) = match step {
            Step::Quick => &mut self.stages[0],
            Step::Pass(_) => &mut self.stages[1],
            Step::Full => return,
        };
        *n += 1;
        let stages = [st.visibility_ms, st.shadow_ms, st.shading_ms, st.traced_ms, st.edge_ms];
        sum.iter_mut().zip(stages).for_each(|(s, t)| *s += t);
    }
}

/// The mouse: where it was and which buttons are held.
#[derive(Debug, Default)]
struct Mouse {
    at: Option<(f64, f64)>,
    left: bool,
    middle: bool,
    right: bool,
    shift: bool,
}

struct Surface {
    window: Rc<Window>,
    surface: softbuffer::Surface<Rc<Window>, Rc<Window>>,
}

struct App {
    viewer: Viewer,
    source: Source,
    scene: Option<Arc<Scene>>,
    /// The rendering thread, and the stop flag of the step it renders.
    worker: Worker,
    stop: Arc<AtomicBool>,
    /// What is on screen, written by the rendering thread.
    shown: Arc<Mutex<Shown>>,
    text: Text,
    script: VecDeque<Action>,
    sleep_until: Option<Instant>,
    /// Whether the script gave an input since the step rendering began.
    fed: bool,
    surface: Option<Surface>,
    mouse: Mouse,
    proxy: EventLoopProxy<Wake>,
    watcher: Option<notify::RecommendedWatcher>,
    /// Seconds of the last frames, for the HUD's rate.
    frame_times: VecDeque<f64>,
    step: Option<Step>,
    screenshots: u32,
    failure: Option<String>,
    clock: Clock,
    /// The window's contents as last presented (0RGB), and their size.
    presented: (Vec<u32>, usize, usize),
}

impl App {
    fn new(start: Start, proxy: EventLoopProxy<Wake>) -> App {
        let loaded = start.source.load(&super::state::Toggles::default());
        let (scene, error) = match loaded {
            Ok(s) => (Some(Arc::new(s)), None),
            Err(e) => (None, Some(e)),
        };
        let size = start.size.unwrap_or_else(|| match (&scene, start.source.path.as_deref()) {
            (Some(s), Some(p)) if InputFormat::from_path(p) == Some(InputFormat::Scene) => (s.width, s.height),
            _ => super::source::DEFAULT_SIZE,
        });
        let mut viewer = viewer_for(scene.as_deref(), size);
        viewer.error = error;
        viewer.warnings = scene.as_deref().map(warned).unwrap_or_default();
        let reporter = proxy.clone();
        let shown = Arc::new(Mutex::new(Shown::default()));
        let worker = Worker::spawn(start.threads, shown.clone(), move |done| {
            reporter.send_event(Wake::Rendered(Box::new(done))).ok();
        });
        let mut app = App {
            viewer,
            source: start.source,
            scene,
            worker,
            stop: Arc::new(AtomicBool::new(false)),
            shown,
            text: Text::new(),
            script: start.script.into(),
            sleep_until: None,
            fed: false,
            surface: None,
            mouse: Mouse::default(),
            proxy,
            watcher: None,
            frame_times: VecDeque::new(),
            step: None,
            screenshots: 0,
            failure: None,
            clock: Clock::new(),
            presented: (Vec::new(), 0, 0),
        };
        app.watch();
        app
    }

    /// Watches the source's folder (again, after a new file is opened).
    fn watch(&mut self) {
        self.watcher = None;
        let Some(folder) = self.source.folder() else { return };
        let proxy = self.proxy.clone();
        let handler = move |event: notify::Result<notify::Event>| {
            if let Ok(e) = event {
                let relevant = matches!(e.kind, notify::EventKind::Create(_) | notify::EventKind::Modify(_));
                if relevant && e.paths.iter().any(|p| Source::is_watched(p)) {
                    proxy.send_event(Wake::FileChanged).ok();
                }
            }
        };
        match notify::recommended_watcher(handler) {
            Ok(mut w) => match w.watch(&folder, notify::RecursiveMode::NonRecursive) {
                Ok(()) => self.watcher = Some(w),
                Err(e) => eprintln!("warning: not watching {}: {e}", folder.display()),
            },
            Err(e) => eprintln!("warning: no file watching: {e}"),
        }
    }

    fn input(&mut self, event_loop: &ActiveEventLoop, input: Input) {
        let request = self.viewer.apply(input);
        let changes = matches!(request, Request::Render | Request::Reload | Request::Open(_));
        if changes {
            self.clock.last_input = Some(Instant::now());
            self.clock.unanswered = self.clock.unanswered.or(self.clock.last_input);
        }
        if self.viewer.stale() && !self.stop.swap(true, Ordering::Relaxed) {
            self.clock.stop_raised = Some(Instant::now());
        }
        if changes {
            // What is on screen shows the view before this input: none of
            // its passes count towards a script's `wait N` (the rendering
            // thread, stopped, publishes no more of them).
            lock(&self.shown).passes = 0;
        }
        match request {
            Request::Nothing | Request::Render => {}
            Request::Redraw => self.request_redraw(),
            Request::Reload => self.reload(false),
            Request::Open(path) => {
                self.source = Source { path: Some(path) };
                self.reload(true);
                self.watch();
            }
            Request::Screenshot => {
                self.screenshots += 1;
                let path = PathBuf::from(format!("kage-view-{}.png", self.screenshots));
                self.screenshot(&path);
            }
            Request::Quit => event_loop.exit(),
        }
    }

    /// Loads the source again: the camera kept, or (`fresh`) the new
    /// scene's own. A failure keeps the last good scene and shows the error.
    fn reload(&mut self, fresh: bool) {
        match self.source.load(&self.viewer.toggles) {
            Ok(scene) => {
                if fresh {
                    let keep = (self.viewer.toggles, self.viewer.display, self.viewer.hud);
                    self.viewer = viewer_for(Some(&scene), self.viewer.size);
                    (self.viewer.toggles, self.viewer.display, self.viewer.hud) = keep;
                } else if let Some(bounds) = scene.bounds() {
                    self.viewer.bounds = bounds;
                    self.viewer.framed = scene.caster_bounds().unwrap_or(bounds);
                }
                self.viewer.costly_scene = scene.lights.iter().any(super::refine::costly);
                self.viewer.error = None;
                self.viewer.warnings = warned(&scene);
                self.scene = Some(Arc::new(scene));
            }
            Err(e) => {
                // A save often reaches the watcher as several events: the
                // same error is said once.
                if self.viewer.error.as_deref() != Some(e.as_str()) {
                    eprintln!("{e}");
                }
                self.viewer.error = Some(e);
            }
        }
        self.request_redraw();
    }

    fn screenshot(&mut self, path: &Path) {
        let shown = lock(&self.shown);
        match kage::output::write_image(&shown.image, path, shown.scale, shown.tone) {
            Ok(()) => println!("wrote {}", path.display()),
            Err(e) => eprintln!("screenshot {}: {e}", path.display()),
        }
    }

    /// Writes the window's contents as last presented to a PNG.
    fn capture(&mut self, path: &Path) {
        self.present(true);
        let (pixels, w, h) = &self.presented;
        let mut image = kage::image::LinearImage::new(*w as u32, *h as u32);
        for (out, &p) in image.pixels_mut().iter_mut().zip(pixels) {
            let c = |s: u32| kage::image::srgb_to_linear(((p >> s) & 0xff) as f32 / 255.0);
            *out = glam::Vec3::new(c(16), c(8), c(0));
        }
        match kage::output::write_image(&image, path, 1.0, kage::image::ToneCurve::Clip) {
            Ok(()) => println!("wrote {}", path.display()),
            Err(e) => eprintln!("capture {}: {e}", path.display()),
        }
    }

    fn request_redraw(&self) {
        if let Some(s) = &self.surface {
            s.window.request_redraw();
        }
    }

    /// Runs the script's actions that are due, up to its next input (one a
    /// frame) or until it waits.
    fn run_script(&mut self, event_loop: &ActiveEventLoop) {
        while let Some(action) = self.script.front().cloned() {
            if let Some(until) = self.sleep_until {
                if Instant::now() < until {
                    event_loop.set_control_flow(ControlFlow::WaitUntil(until));
                    return;
                }
                self.sleep_until = None;
            }
            match action {
                Action::Wait if !self.viewer.at_rest() => return,
                Action::Wait => {}
                Action::WaitPasses(n) if lock(&self.shown).passes < n && !self.viewer.at_rest() => return,
                Action::WaitPasses(_) => {}
                Action::Sleep(s) => {
                    self.script.pop_front();
                    self.sleep_until = Some(Instant::now() + Duration::from_secs_f32(s));
                    continue;
                }
                Action::Input(_) if self.viewer.rendering().is_some() && self.fed => return,
                Action::Input(input) => {
                    // One input a step rendered, arriving while it renders,
                    // as a moving mouse's events do.
                    self.script.pop_front();
                    self.fed = true;
                    self.input(event_loop, input);
                    return;
                }
                Action::Screenshot(path) => self.screenshot(&path),
                Action::Capture(path) => self.capture(&path),
                Action::Copy(from, to) => {
                    if let Err(e) = std::fs::copy(&from, &to) {
                        self.failure = Some(format!("script: copy {} to {}: {e}", from.display(), to.display()));
                        event_loop.exit();
                    }
                }
                Action::Quit => event_loop.exit(),
            }
            self.script.pop_front();
        }
    }

    /// Hands the next refinement step, if any, to the rendering thread.
    fn dispatch(&mut self) {
        let Some(scene) = &self.scene else {
            self.viewer.settle();
            return;
        };
        let Some(step) = self.viewer.step() else { return };
        self.stop = Arc::new(AtomicBool::new(false));
        self.fed = false;
        let job = Job { scene: scene.clone(), viewer: self.viewer.clone(), step, stop: self.stop.clone() };
        self.worker.send(job);
    }

    /// Takes a finished step: shows it, unless it was given up.
    fn finished(&mut self, done: Done) {
        self.viewer.rendered();
        match done.outcome {
            Outcome::Stopped => {
                if let Some(at) = self.clock.stop_raised.take() {
                    self.clock.to_stop.push(done.at - at);
                }
                return;
            }
            Outcome::Failed(e) => {
                self.viewer.error = Some(e);
                self.viewer.settle();
            }
            Outcome::Rendered(stats) => self.clock.count(done.step, &stats),
        }
        // The next step renders while this one is shown.
        self.dispatch();
        self.frame_times.push_back(done.took.as_secs_f64());
        if self.frame_times.len() > 10 {
            self.frame_times.pop_front();
        }
        if done.step == Step::Quick {
            self.clock.quick_ms.push(done.took.as_secs_f64() * 1e3);
            if let Some(last) = self.clock.last_quick.replace(done.at) {
                self.clock.quick_apart.push(done.at - last);
            }
        } else {
            self.clock.last_quick = None;
        }
        // An image answers the inputs that came before its step began.
        if let Some(at) = self.clock.unanswered.filter(|&at| done.at - done.took >= at) {
            self.clock.to_image.push(done.at - at);
            self.clock.unanswered = None;
        }
        if self.viewer.at_rest() {
            if let Some(at) = self.clock.last_input.take() {
                self.clock.to_rest.push(done.at - at);
            }
        }
        self.step = Some(done.step);
        self.present(false);
    }

    /// Shows the image, the HUD, the keys and any error; `keep`: also keeps
    /// what is shown for a capture.
    fn present(&mut self, keep: bool) {
        let start = Instant::now();
        let Some(s) = &mut self.surface else { return };
        let size = s.window.inner_size();
        let (Some(w), Some(h)) = (NonZeroU32::new(size.width), NonZeroU32::new(size.height)) else { return };
        if s.surface.resize(w, h).is_err() {
            return;
        }
        let Ok(mut buffer) = s.surface.buffer_mut() else { return };
        let (bw, bh) = (size.width as usize, size.height as usize);
        buffer.fill(0x0020_2020);
        // The image copied out, the lock let go before the rest: the
        // rendering thread waits for it to write the next.
        let (iw, lines) = {
            let shown = lock(&self.shown);
            let (iw, ih) = (shown.image.width() as usize, shown.image.height() as usize);
            if iw > 0 && shown.screen.len() == iw * ih {
                let (w, h) = (iw.min(bw), ih.min(bh));
                for (out, row) in buffer.chunks_mut(bw).zip(shown.screen.chunks(iw)).take(h) {
                    out[..w].copy_from_slice(&row[..w]);
                }
            }
            (iw, hud_lines(&self.viewer, &shown, self.step, &self.frame_times))
        };
        let mut below_hud = 8;
        if self.viewer.hud {
            self.text.draw(&mut buffer, (bw, bh), (8, 8), &lines, 0x00e0_e0e0);
            below_hud += self.text.size(&lines).1 + 8;
        }
        if self.viewer.help {
            let sheet = cheat_sheet();
            let x = bw.saturating_sub(self.text.size(&sheet).0 + 8);
            self.text.draw(&mut buffer, (bw, bh), (x, below_hud), &sheet, 0x00ff_ffff);
        }
        let mut bottom = bh;
        if let Some(e) = &self.viewer.error {
            let lines: Vec<String> = e.lines().map(str::to_string).collect();
            let lines = self.text.wrapped(&lines, bw.saturating_sub(16));
            bottom = bottom.saturating_sub(self.text.size(&lines).1 + 8);
            self.text.draw(&mut buffer, (bw, bh), (8, bottom), &lines, ERROR_COLOUR);
        }
        if !self.viewer.warnings.is_empty() {
            let lines = self.text.wrapped(&warning_lines(&self.viewer.warnings), bw.saturating_sub(16));
            bottom = bottom.saturating_sub(self.text.size(&lines).1 + 8);
            self.text.draw(&mut buffer, (bw, bh), (8, bottom), &lines, WARNING_COLOUR);
        }
        if keep {
            self.presented = (buffer.to_vec(), bw, bh);
        }
        if buffer.present().is_ok() && iw > 0 && self.clock.first_image.is_none() {
            self.clock.first_image = Some(self.clock.started.elapsed());
        }
        self.clock.present_ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
}

/// A viewer of `scene` (or of nothing) in a window of `size`.
fn viewer_for(scene: Option<&Scene>, size: (u32, u32)) -> Viewer {
    let bounds = scene.and_then(Scene::bounds).unwrap_or((glam::Vec3::splat(-1.0), glam::Vec3::ONE));
    let costly = scene.is_some_and(|s| s.lights.iter().any(super::refine::costly));
    let orbit = scene.map_or_else(
        || Orbit {
            target: glam::Vec3::ZERO,
            distance: 5.0,
            view: Default::default(),
            fov_y_deg: 40.0,
            orthographic: false,
        },
        |s| Orbit::from_camera(&s.camera),
    );
    let mut viewer = Viewer::new(orbit, bounds, size);
    viewer.framed = scene.and_then(Scene::caster_bounds).unwrap_or(bounds);
    viewer.costly_scene = costly;
    viewer.toggles.ao = scene.is_some_and(|s| s.ambient_occlusion.is_some());
    if scene.is_some_and(|s| s.lines.is_some()) {
        viewer.toggles.lines = super::state::LineStyle::Lines;
    }
    viewer
}

fn hud_lines(viewer: &Viewer, shown: &Shown, step: Option<Step>, times: &VecDeque<f64>) -> Vec<String> {
    let st = &shown.stats;
    let mean = times.iter().sum::<f64>() / times.len().max(1) as f64;
    let stage = match step {
        None => "-".to_string(),
        Some(Step::Quick) => "quick".to_string(),
        Some(Step::Full) => "full".to_string(),
        Some(Step::Pass(n)) => format!("pass {n}/{MAX_PASSES}"),
    };
    let smoothing = match viewer.toggles.smoothing {
        Smoothing::None => "none",
        Smoothing::Edge => "edge",
        Smoothing::Progressive => "progressive",
    };
    vec![
        if times.is_empty() || mean <= 0.0 {
            // No frame rendered yet (or only an error shown): no rate to give.
            format!("- fps  {}x{}  {stage}", viewer.size.0, viewer.size.1)
        } else {
            format!("{:.1} fps  {}x{}  {stage}", 1.0 / mean, viewer.size.0, viewer.size.1)
        },
        format!(
            "ms: visibility {:.1}  shadows {:.1}  shading {:.1}  traced {:.1}  ao {:.1}  edges {:.1}  lines {:.1}",
            st.visibility_ms, st.shadow_ms, st.shading_ms, st.traced_ms, st.occlusion_ms, st.edge_ms, st.lines_ms
        ),
        format!("{} triangles  {} solids  {} passes averaged", st.raster.triangles, st.raster.solids, shown.passes),
        match skipped(&viewer.warnings) {
            0 => format!("{} warnings", viewer.warnings.len()),
            n => format!("INCOMPLETE: {n} part(s) not drawn"),
        },
        format!(
            "shadows {}  smoothing {smoothing}{}{}{}  show {}{}",
            viewer.toggles.shadows.name(),
            viewer.toggles.section.map_or(String::new(), |(axis, at)| format!(
                "  section {} {:.0}%",
                ["x", "y", "z"][axis],
                f32::from(at) * super::state::SECTION_STEP * 100.0
            )),
            match (viewer.toggles.ao, viewer.toggles.xray) {
                (false, false) => "",
                (true, false) => "  ao",
                (false, true) => "  x-ray",
                (true, true) => "  ao  x-ray",
            },
            viewer.toggles.lines.name(),
            viewer.display.name(),
            if viewer.display == Display::Image { "" } else { " (V: next)" }
        ),
    ]
}

/// Warnings shown over the image.
const WARNING_COLOUR: u32 = 0x00ff_c040;

/// Most warnings drawn in the window (all go to stderr).
const SHOWN_WARNINGS: usize = 6;

/// The scene's warnings, each also written to stderr.
fn warned(scene: &Scene) -> Vec<String> {
    scene.warnings.iter().for_each(|w| eprintln!("warning: {w}"));
    scene.warnings.clone()
}

/// How many parts the warnings say were left out of the image.
#[must_use]
pub fn skipped(warnings: &[String]) -> usize {
    warnings.iter().filter(|w| w.contains("skipped")).count()
}

/// The warnings as the window draws them: a headline when parts are left
/// out, then the first few, then how many more there are.
#[must_use]
pub fn warning_lines(warnings: &[String]) -> Vec<String> {
    let mut lines = Vec::new();
    match skipped(warnings) {
        0 => {}
        n => lines.push(format!("INCOMPLETE IMAGE: {n} part(s) of the file not drawn")),
    }
    lines.extend(warnings.iter().take(SHOWN_WARNINGS).map(|w| format!("warning: {w}")));
    if warnings.len() > SHOWN_WARNINGS {
        lines.push(format!("... and {} more warnings (on stderr)", warnings.len() - SHOWN_WARNINGS));
    }
    lines
}

/// The keys, as H shows them.
#[must_use]
pub fn cheat_sheet() -> Vec<String> {
    [
        "left drag   orbit",
        "middle/shift+left drag   pan",
        "wheel       zoom",
        "F           frame all",
        "1 3 7 9     front right top iso",
        "5           perspective/ortho",
        "Home        reset camera",
        "S           shadow method",
        "A           antialiasing",
        "R           traced reflections",
        "G           fog",
        "O           ambient occlusion",
        "X           x-ray",
        "L           lines, drawing, off",
        "K  [  ]     section x/y/z/off, move",
        "P           ground plane",
        "C           CSG exact/faceted",
        "M           OpenSCAD # and % parts",
        "V           show: image, passes,",
        "            shadow, depth, normals, ids",
        "Z           HUD    H  this sheet",
        "F12         screenshot",
        "Esc, Q      quit",
    ]
    .map(str::to_string)
    .to_vec()
}

impl ApplicationHandler<Wake> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.surface.is_some() {
            return;
        }
        let title = self.source.path.as_ref().map_or("kage: demo".to_string(), |p| format!("kage: {}", p.display()));
        let attributes = Window::default_attributes()
            .with_title(title)
            .with_inner_size(PhysicalSize::new(self.viewer.size.0, self.viewer.size.1));
        let opened = event_loop.create_window(attributes).map_err(|e| e.to_string()).and_then(|window| {
            let window = Rc::new(window);
            let context = softbuffer::Context::new(window.clone()).map_err(|e| e.to_string())?;
            let surface = softbuffer::Surface::new(&context, window.clone()).map_err(|e| e.to_string())?;
            Ok(Surface { window, surface })
        });
        match opened {
            Ok(s) => self.surface = Some(s),
            Err(e) => {
                self.failure = Some(format!("no window: {e}"));
                event_loop.exit();
            }
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, event: Wake) {
        match event {
            Wake::FileChanged => self.input(event_loop, Input::FileChanged),
            Wake::Rendered(done) => self.finished(*done),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => self.input(event_loop, Input::Resize(size.width, size.height)),
            WindowEvent::RedrawRequested => self.present(false),
            WindowEvent::ModifiersChanged(m) => self.mouse.shift = m.state().shift_key(),
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.mouse.left = down,
                    MouseButton::Middle => self.mouse.middle = down,
                    MouseButton::Right => self.mouse.right = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let last = self.mouse.at.replace((position.x, position.y));
                let button = if self.mouse.left {
                    Some(Button::Left)
                } else if self.mouse.middle {
                    Some(Button::Middle)
                } else if self.mouse.right {
                    Some(Button::Right)
                } else {
                    None
                };
                if let (Some((x, y)), Some(button)) = (last, button) {
                    let (dx, dy) = ((position.x - x) as f32, (position.y - y) as f32);
                    self.input(event_loop, Input::Drag { button, dx, dy, shift: self.mouse.shift });
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 50.0) as f32,
                };
                self.input(event_loop, Input::Wheel(steps));
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                let key = match event.logical_key {
                    WinitKey::Named(NamedKey::Home) => Some(Key::Home),
                    WinitKey::Named(NamedKey::F12) => Some(Key::F12),
                    WinitKey::Named(NamedKey::Escape) => Some(Key::Escape),
                    WinitKey::Character(c) => c.chars().next().map(|c| Key::Char(c.to_ascii_lowercase())),
                    _ => None,
                };
                if let Some(key) = key {
                    self.input(event_loop, Input::Key(key));
                }
            }
            WindowEvent::DroppedFile(path) => self.input(event_loop, Input::Dropped(path)),
            _ => {}
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        // The rendering thread gives its step up; closing waits for it.
        self.stop.store(true, Ordering::Relaxed);
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.surface.is_none() {
            return;
        }
        // The step first, then the script: a scripted input then arrives
        // while a step renders, as a user's does.
        self.dispatch();
        self.run_script(event_loop);
        if event_loop.exiting() {
            return;
        }
        self.dispatch();
        if self.sleep_until.is_none() {
            // The rendering thread wakes the loop when a step is done; a
            // script with nothing rendering goes on at once.
            let idle = self.viewer.rendering().is_none() && !self.script.is_empty();
            event_loop.set_control_flow(if idle { ControlFlow::Poll } else { ControlFlow::Wait });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A window closed before any frame or input: every figure is "-", none
    /// NaN.
    #[test]
    fn timings_of_nothing_say_so_without_nan() {
        let summary = Clock::new().summary();
        assert!(!summary.contains("NaN") && !summary.contains("inf"), "{summary}");
        assert!(summary.starts_with("first image - ms; 0 quick frames"), "{summary}");
    }
}
