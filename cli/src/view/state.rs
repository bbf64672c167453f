//! What the viewer is doing, apart from any window: input events turn into
//! camera moves, toggles and requests (render, reload, screenshot, quit),
//! and a refinement schedule says what the next frame renders — a quick one
//! while the camera moves, then, once it rests, the full frame and up to 64
//! jittered passes accumulated, started over by the next input.

use std::path::PathBuf;

use glam::Vec3;
use kage::scene::framing::View;
use kage::scene::ShadowMethod;
use kage::Component;

use super::orbit::Orbit;

/// Jittered passes the progressive antialiasing accumulates at most.
pub const MAX_PASSES: u32 = 64;

/// A mouse button.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Button {
    /// Orbits (pans with shift).
    Left,
    /// Pans.
    Middle,
    /// Not bound.
    Right,
}

/// A key the viewer knows, apart from the window system's codes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Key {
    /// A printable key, lower case.
    Char(char),
    /// Home: the camera the scene was opened with.
    Home,
    /// F12: a screenshot.
    F12,
    /// Escape: quit.
    Escape,
}

/// One input event.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// The mouse moved `dx`, `dy` pixels (right, down) with `button` held.
    Drag {
        /// The button held.
        button: Button,
        /// Pixels right.
        dx: f32,
        /// Pixels down.
        dy: f32,
        /// Shift held.
        shift: bool,
    },
    /// The wheel turned this many steps (positive: away from the user, in).
    Wheel(f32),
    /// A key was pressed.
    Key(Key),
    /// The window's inside is now this many pixels.
    Resize(u32, u32),
    /// A file was dropped onto the window.
    Dropped(PathBuf),
    /// A watched file changed on disk.
    FileChanged,
}

/// What the window should do after an input.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Request {
    /// Nothing changed.
    Nothing,
    /// Render again from the first refinement step (the camera or a setting
    /// of the frame changed).
    Render,
    /// Show the last frame again (what is drawn over it changed).
    Redraw,
    /// Load the scene again (the camera kept), then render.
    Reload,
    /// Open this file instead (its own camera), then render.
    Open(PathBuf),
    /// Write the image shown to a PNG.
    Screenshot,
    /// Close the window.
    Quit,
}

/// The shadow technique every light uses, as the viewer cycles through
/// them (S).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shadows {
    /// Each light's own, as the scene says.
    Scene,
    /// Every light by this method.
    All(ShadowMethod),
    /// Every light's disc sampled by this many jittered maps (seed 002 §3.3).
    Jittered(u32),
}

impl Shadows {
    /// Every choice, in the order S steps through them: the scene's, each
    /// method of the library's list, jittered maps.
    #[must_use]
    pub fn cycle() -> Vec<Shadows> {
        let methods = ShadowMethod::all().map(Shadows::All);
        std::iter::once(Shadows::Scene).chain(methods).chain([Shadows::Jittered(16)]).collect()
    }

    /// A short name for the HUD.
    #[must_use]
    pub fn name(self) -> String {
        match self {
            Shadows::Scene => "scene's".to_string(),
            Shadows::All(method) => method.label().to_string(),
            Shadows::Jittered(n) => format!("jittered {n}"),
        }
    }

    /// Whether a frame with these shadows costs more than a plain map's, so
    /// that a moving camera is shown with plain maps instead.
    #[must_use]
    pub fn costly(self) -> bool {
        matches!(self, Shadows::All(ShadowMethod::Slb | ShadowMethod::Soft) | Shadows::Jittered(_))
    }
}

/// How edges are smoothed (A cycles).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Smoothing {
    /// Not at all.
    None,
    /// Seed 004's edge pass on the full frame.
    Edge,
    /// The edge pass, then jittered passes accumulated while the camera
    /// rests, up to [`MAX_PASSES`].
    Progressive,
}

/// Feature lines (L cycles).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineStyle {
    /// None (the scene's own `[lines]` left out too).
    Off,
    /// Silhouettes, boundaries and creases over the shaded image.
    Lines,
    /// A technical drawing: white surfaces in flat light, hidden lines
    /// dashed ([`kage::Scene::drawing`]).
    Drawing,
}

impl LineStyle {
    /// Its name, for the HUD ("" when off).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            LineStyle::Off => "",
            LineStyle::Lines => "  lines",
            LineStyle::Drawing => "  drawing",
        }
    }
}

/// What the window shows (V cycles).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Display {
    /// The image.
    Image,
    /// One of the image's components (seed 002's passes).
    Component(Component),
    /// The first shadowed light's shadow term.
    Shadow,
    /// Ambient occlusion's open share (white where it is off).
    Occlusion,
    /// Eye depth, near white to far black.
    Depth,
    /// Shading normals as colours.
    Normals,
    /// Each object in a colour of its own.
    Items,
}

impl Display {
    /// Every display, in the order V steps through them.
    #[must_use]
    pub fn cycle() -> Vec<Display> {
        let mut all = vec![Display::Image];
        all.extend(Component::ALL.map(Display::Component));
        all.extend([Display::Shadow, Display::Occlusion, Display::Depth, Display::Normals, Display::Items]);
        all
    }

    /// A short name for the HUD.
    #[must_use]
    pub fn name(self) -> String {
        match self {
            Display::Image => "image".to_string(),
            Display::Component(c) => c.name().to_string(),
            Display::Shadow => "shadow term".to_string(),
            Display::Occlusion => "ambient occlusion".to_string(),
            Display::Depth => "depth".to_string(),
            Display::Normals => "normals".to_string(),
            Display::Items => "items".to_string(),
        }
    }
}

/// How far `[` and `]` move a section plane: a share of the model's extent.
pub const SECTION_STEP: f32 = 0.05;

/// Steps of [`SECTION_STEP`] across the model.
pub const SECTION_STEPS: u8 = 20;

/// The settings the toggles change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Toggles {
    /// The shadow technique (S).
    pub shadows: Shadows,
    /// Edge smoothing (A).
    pub smoothing: Smoothing,
    /// Mirrors and glass traced (R).
    pub traced: bool,
    /// The scene's fog (G).
    pub fog: bool,
    /// The ground under a model (P).
    pub ground: bool,
    /// A `.csg` model's spheres and cylinders as true quadrics (C; off:
    /// OpenSCAD's facets).
    pub exact_csg: bool,
    /// OpenSCAD's `#` and `%` parts drawn see-through (M).
    pub ghosts: bool,
    /// Ambient occlusion (O): the scene's, or the defaults.
    pub ao: bool,
    /// Every object see-through (X).
    pub xray: bool,
    /// Feature lines (L).
    pub lines: LineStyle,
    /// A section plane across a model (K: along x, y, z, off; `[` and `]`
    /// move it): the axis (0, 1, 2 of the model file's coordinates) and
    /// where it crosses the model, in steps of [`SECTION_STEP`] of its
    /// extent.
    pub section: Option<(usize, u8)>,
}

impl Default for Toggles {
    fn default() -> Self {
        Toggles {
            shadows: Shadows::Scene,
            smoothing: Smoothing::Progressive,
            traced: true,
            fog: true,
            ground: true,
            exact_csg: true,
            ghosts: true,
            ao: false,
            xray: false,
            lines: LineStyle::Off,
            section: None,
        }
    }
}

/// What a frame renders.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// A frame at interactive cost: no edge pass, plain maps in place of
    /// costlier shadows.
    Quick,
    /// The full frame: the chosen shadows and smoothing.
    Full,
    /// Jittered pass `n` (1 ≤ n ≤ [`MAX_PASSES`]), averaged with the ones
    /// before it.
    Pass(u32),
}

/// The viewer's state.
#[derive(Debug, Clone)]
pub struct Viewer {
    /// The camera.
    pub orbit: Orbit,
    /// The camera the scene was opened with (Home).
    pub home: Orbit,
    /// What the scene's objects span (the near and far planes keep all of it).
    pub bounds: (Vec3, Vec3),
    /// What F and the number keys frame: the objects that cast shadows, not
    /// the ground they stand on ([`kage::Scene::caster_bounds`]), as
    /// `kage render --view` frames them.
    pub framed: (Vec3, Vec3),
    /// The toggles.
    pub toggles: Toggles,
    /// What is shown.
    pub display: Display,
    /// The HUD (Z).
    pub hud: bool,
    /// The cheat sheet of keys (H).
    pub help: bool,
    /// The window's inside, pixels.
    pub size: (u32, u32),
    /// The last load's error, shown over the last good scene.
    pub error: Option<String>,
    /// What the loaded scene's files could not draw or drew otherwise
    /// (OpenSCAD nodes skipped, meshes repaired), shown over the image.
    pub warnings: Vec<String>,
    /// Whether the scene's own shadows cost more than plain maps (jittered
    /// maps, silhouette-line buffers, two-map soft shadows).
    pub costly_scene: bool,
    /// The next step of the refinement; `None` when it is done.
    next: Option<Step>,
    /// The step being rendered, if any.
    rendering: Option<Step>,
    /// Whether the step being rendered is stale: input came that a refinement
    /// step gives way to.
    stale: bool,
}

impl Viewer {
    /// A viewer of a scene within `bounds` seen through `orbit`, in a window
    /// of `size` pixels.
    #[must_use]
    pub fn new(orbit: Orbit, bounds: (Vec3, Vec3), size: (u32, u32)) -> Viewer {
        Viewer {
            orbit,
            home: orbit,
            bounds,
            framed: bounds,
            toggles: Toggles::default(),
            display: Display::Image,
            hud: true,
            help: false,
            size,
            error: None,
            warnings: Vec::new(),
            costly_scene: false,
            next: Some(Step::Quick),
            rendering: None,
            stale: false,
        }
    }

    /// Takes one input; says what the window should do.
    pub fn apply(&mut self, input: Input) -> Request {
        let request = match input {
            Input::Drag { button, dx, dy, shift } => match (button, shift) {
                (Button::Left, false) => {
                    self.orbit.rotate(dx, -dy);
                    Request::Render
                }
                (Button::Left, true) | (Button::Middle, _) => {
                    self.orbit.pan(dx, dy, self.size.1);
                    Request::Render
                }
                (Button::Right, _) => Request::Nothing,
            },
            Input::Wheel(steps) => {
                self.orbit.zoom(steps);
                Request::Render
            }
            Input::Resize(w, h) if (w, h) != self.size && w > 0 && h > 0 => {
                self.size = (w, h);
                Request::Render
            }
            Input::Resize(..) => Request::Nothing,
            Input::Dropped(path) => Request::Open(path),
            Input::FileChanged => Request::Reload,
            Input::Key(key) => self.key(key),
        };
        if matches!(request, Request::Render | Request::Reload | Request::Open(_)) {
            self.next = Some(Step::Quick);
            // A quick frame finishes (the next one shows the camera's newest
            // place); anything costlier is given up at once.
            self.stale |= self.rendering.is_some_and(|s| s != Step::Quick);
        }
        request
    }

    fn key(&mut self, key: Key) -> Request {
        let aspect = self.size.0 as f32 / self.size.1.max(1) as f32;
        let t = &mut self.toggles;
        match key {
            Key::Escape | Key::Char('q') => return Request::Quit,
            Key::F12 => return Request::Screenshot,
            Key::Home => self.orbit = self.home,
            Key::Char('f') => self.orbit.frame(self.framed, aspect),
            Key::Char('1') => self.orbit.look_from(View::FRONT, self.framed, aspect),
            Key::Char('3') => self.orbit.look_from(View::RIGHT, self.framed, aspect),
            Key::Char('7') => self.orbit.look_from(View::TOP, self.framed, aspect),
            Key::Char('9') => self.orbit.look_from(View::ISO, self.framed, aspect),
            Key::Char('5') => self.orbit.toggle_projection(),
            Key::Char('s') => t.shadows = next_of(&Shadows::cycle(), t.shadows),
            Key::Char('a') => {
                t.smoothing = next_of(&[Smoothing::None, Smoothing::Edge, Smoothing::Progressive], t.smoothing);
            }
            Key::Char('r') => t.traced = !t.traced,
            Key::Char('g') => t.fog = !t.fog,
            Key::Char('m') => t.ghosts = !t.ghosts,
            Key::Char('o') => t.ao = !t.ao,
            Key::Char('x') => t.xray = !t.xray,
            Key::Char('l') => t.lines = next_of(&[LineStyle::Off, LineStyle::Lines, LineStyle::Drawing], t.lines),
            Key::Char('k') => {
                t.section = match t.section {
                    None => Some((0, SECTION_STEPS / 2)),
                    Some((axis, at)) if axis < 2 => Some((axis + 1, at)),
                    Some(_) => None,
                };
                return Request::Reload;
            }
            Key::Char(c @ ('[' | ']')) => {
                let Some((axis, at)) = t.section else { return Request::Nothing };
                let at = if c == ']' { (at + 1).min(SECTION_STEPS) } else { at.saturating_sub(1) };
                t.section = Some((axis, at));
                return Request::Reload;
            }
            Key::Char('p') => {
                t.ground = !t.ground;
                return Request::Reload;
            }
            Key::Char('c') => {
                t.exact_csg = !t.exact_csg;
                return Request::Reload;
            }
            Key::Char('v') => {
                self.display = next_of(&Display::cycle(), self.display);
                return Request::Render;
            }
            Key::Char('z') => {
                self.hud = !self.hud;
                return Request::Redraw;
            }
            Key::Char('h') => {
                self.help = !self.help;
                return Request::Redraw;
            }
            Key::Char(_) => return Request::Nothing,
        }
        Request::Render
    }

    /// The step to render next, advancing the schedule; `None` when the
    /// image is as refined as the toggles ask or a step is still rendering
    /// ([`Viewer::rendered`] says when it is done).
    pub fn step(&mut self) -> Option<Step> {
        if self.rendering.is_some() {
            return None;
        }
        let now = self.next?;
        self.rendering = Some(now);
        self.next = match now {
            Step::Quick if self.quick_is_full() => self.after_full(),
            Step::Quick => Some(Step::Full),
            Step::Full => self.after_full(),
            Step::Pass(n) if n < MAX_PASSES => Some(Step::Pass(n + 1)),
            Step::Pass(_) => None,
        };
        Some(now)
    }

    /// Ends the refinement without rendering the rest of it (nothing to
    /// render, or the scene cannot be rendered).
    pub fn settle(&mut self) {
        (self.next, self.rendering, self.stale) = (None, None, false);
    }

    /// The step being rendered is done (or given up).
    pub fn rendered(&mut self) {
        (self.rendering, self.stale) = (None, false);
    }

    /// The step being rendered, if any.
    #[must_use]
    pub fn rendering(&self) -> Option<Step> {
        self.rendering
    }

    /// Whether the step being rendered should be given up: input since it
    /// began starts the refinement over (a quick frame is never given up).
    #[must_use]
    pub fn stale(&self) -> bool {
        self.stale
    }

    /// Whether the next input would be a new start: the refinement has
    /// nothing left to render and nothing is rendering.
    #[must_use]
    pub fn at_rest(&self) -> bool {
        self.next.is_none() && self.rendering.is_none()
    }

    /// Whether the quick frame would render the same as the full one (no
    /// edge pass wanted, no costlier shadows, no ambient occlusion).
    fn quick_is_full(&self) -> bool {
        let scene_costly = self.toggles.shadows == Shadows::Scene && self.costly_scene;
        let t = &self.toggles;
        t.smoothing == Smoothing::None && !t.shadows.costly() && !scene_costly && !t.ao
    }

    fn after_full(&self) -> Option<Step> {
        (self.toggles.smoothing == Smoothing::Progressive).then_some(Step::Pass(1))
    }
}

/// The item after `now` in `all`, round to the first.
fn next_of<T: Copy + PartialEq>(all: &[T], now: T) -> T {
    let i = all.iter().position(|&x| x == now).map_or(0, |i| (i + 1) % all.len());
    all[i]
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNIT: (Vec3, Vec3) = (Vec3::splat(-1.0), Vec3::ONE);

    fn viewer() -> Viewer {
        let orbit =
            Orbit { target: Vec3::ZERO, distance: 8.0, view: View::DEFAULT, fov_y_deg: 40.0, orthographic: false };
        Viewer::new(orbit, UNIT, (1280, 720))
    }

    /// The next step, rendered at once.
    fn next(v: &mut Viewer) -> Option<Step> {
        let step = v.step();
        v.rendered();
        step
    }

    /// Input gives up a refinement step that is rendering, but not a quick
    /// frame; nothing new is handed out while a step renders.
    #[test]
    fn input_gives_up_a_refinement_step_but_not_a_quick_frame() {
        let mut v = viewer();
        assert_eq!(v.step(), Some(Step::Quick));
        assert_eq!(v.step(), None, "one step at a time");
        v.apply(drag(Button::Left, 5.0, 0.0, false));
        assert!(!v.stale(), "a quick frame finishes");
        v.rendered();
        assert_eq!(v.step(), Some(Step::Quick), "the camera's newest place");
        v.rendered();
        assert_eq!(v.step(), Some(Step::Full));
        assert!(!v.at_rest());
        v.apply(Input::Key(Key::Char('z')));
        assert!(!v.stale(), "the HUD toggle leaves the image as it is");
        v.apply(Input::Wheel(1.0));
        assert!(v.stale(), "the full frame is given up");
        v.rendered();
        assert!(!v.stale());
        assert_eq!(v.step(), Some(Step::Quick));
    }

    fn drag(button: Button, dx: f32, dy: f32, shift: bool) -> Input {
        Input::Drag { button, dx, dy, shift }
    }

    /// The refinement runs quick, full, then passes 1 to 64, and stops.
    #[test]
    fn a_resting_camera_refines_to_64_passes_then_stops() {
        let mut v = viewer();
        let mut steps = Vec::new();
        while let Some(s) = next(&mut v) {
            steps.push(s);
            assert!(steps.len() < 100, "the schedule ends");
        }
        let mut want = vec![Step::Quick, Step::Full];
        want.extend((1..=MAX_PASSES).map(Step::Pass));
        assert_eq!(steps, want);
        assert!(v.at_rest());
    }

    /// Input mid-refinement starts it over; a key that changes nothing does
    /// not.
    #[test]
    fn input_starts_the_refinement_over() {
        let mut v = viewer();
        for _ in 0..10 {
            next(&mut v);
        }
        assert_eq!(v.apply(drag(Button::Left, 5.0, 0.0, false)), Request::Render);
        assert_eq!(next(&mut v), Some(Step::Quick));
        assert_eq!(next(&mut v), Some(Step::Full));
        assert_eq!(v.apply(Input::Key(Key::Char('j'))), Request::Nothing);
        assert_eq!(next(&mut v), Some(Step::Pass(1)));
        assert_eq!(v.apply(Input::Key(Key::Char('z'))), Request::Redraw, "the HUD is drawn over the frame");
        assert_eq!(next(&mut v), Some(Step::Pass(2)));
    }

    /// Without smoothing or costly shadows the quick frame is the final one;
    /// with the edge pass only, the full frame ends it.
    #[test]
    fn the_schedule_follows_the_toggles() {
        let mut v = viewer();
        v.apply(Input::Key(Key::Char('a')));
        assert_eq!(v.toggles.smoothing, Smoothing::None);
        assert_eq!((next(&mut v), next(&mut v)), (Some(Step::Quick), None));
        v.apply(Input::Key(Key::Char('a')));
        assert_eq!(v.toggles.smoothing, Smoothing::Edge);
        assert_eq!((next(&mut v), next(&mut v), next(&mut v)), (Some(Step::Quick), Some(Step::Full), None));
        v.toggles.smoothing = Smoothing::None;
        v.toggles.shadows = Shadows::All(ShadowMethod::Soft);
        v.apply(Input::Wheel(1.0));
        assert_eq!((next(&mut v), next(&mut v), next(&mut v)), (Some(Step::Quick), Some(Step::Full), None));
        // The scene's own jittered lights count as costly too.
        v.toggles.shadows = Shadows::Scene;
        v.apply(Input::Wheel(1.0));
        assert_eq!((next(&mut v), next(&mut v)), (Some(Step::Quick), None));
        v.costly_scene = true;
        v.apply(Input::Wheel(1.0));
        assert_eq!((next(&mut v), next(&mut v), next(&mut v)), (Some(Step::Quick), Some(Step::Full), None));
        // Ambient occlusion is left out of quick frames: the full frame follows.
        v.costly_scene = false;
        assert_eq!(v.apply(Input::Key(Key::Char('o'))), Request::Render);
        assert!(v.toggles.ao);
        assert_eq!((next(&mut v), next(&mut v), next(&mut v)), (Some(Step::Quick), Some(Step::Full), None));
    }

    /// Left drag orbits, shift + left and middle pan, the wheel zooms, the
    /// right button does nothing.
    #[test]
    fn the_mouse_moves_the_camera() {
        let mut v = viewer();
        let start = v.orbit;
        v.apply(drag(Button::Left, 10.0, 0.0, false));
        assert!(v.orbit.view.azimuth_deg < start.view.azimuth_deg && v.orbit.target == start.target);
        let turned = v.orbit;
        v.apply(drag(Button::Left, 0.0, 0.0, true));
        v.apply(drag(Button::Left, 10.0, 0.0, true));
        assert!(v.orbit.target != turned.target && v.orbit.view == turned.view);
        let panned = v.orbit;
        v.apply(drag(Button::Middle, 0.0, 10.0, false));
        assert!(v.orbit.target.y > panned.target.y, "dragging down moves the scene down");
        v.apply(Input::Wheel(2.0));
        assert!(v.orbit.distance < start.distance);
        let before = v.orbit;
        assert_eq!(v.apply(drag(Button::Right, 10.0, 10.0, false)), Request::Nothing);
        assert_eq!(v.orbit, before);
        v.apply(Input::Key(Key::Home));
        assert_eq!(v.orbit, start);
    }

    /// F and the number keys frame the part, not the ground square under it.
    #[test]
    fn presets_frame_the_part_not_its_ground() {
        let mut v = viewer();
        v.bounds = (Vec3::new(-50.0, -50.0, -0.1), Vec3::new(50.0, 50.0, 2.0));
        v.framed = UNIT;
        for key in ['f', '1', '3', '7', '9'] {
            v.apply(Input::Key(Key::Char(key)));
            assert!(v.orbit.distance < 10.0, "key {key}: {} away, framing the ground", v.orbit.distance);
        }
    }

    /// The number keys put the eye at the standard views; 5 switches the lens.
    #[test]
    fn number_keys_put_the_standard_views() {
        let mut v = viewer();
        for (key, view) in [('1', View::FRONT), ('3', View::RIGHT), ('7', View::TOP), ('9', View::ISO)] {
            assert_eq!(v.apply(Input::Key(Key::Char(key))), Request::Render);
            assert_eq!(v.orbit.view, view, "key {key}");
        }
        v.apply(Input::Key(Key::Char('5')));
        assert!(v.orbit.orthographic);
    }

    /// S, A and V cycle through every choice and come back; P and C reload;
    /// Esc and Q quit; F12 asks for a screenshot; a file dropped is opened;
    /// a change on disk reloads.
    #[test]
    fn toggles_cycle_and_requests_follow_keys() {
        let mut v = viewer();
        let mut seen = vec![v.toggles.shadows];
        for _ in 1..Shadows::cycle().len() {
            v.apply(Input::Key(Key::Char('s')));
            seen.push(v.toggles.shadows);
        }
        assert_eq!(seen, Shadows::cycle());
        assert_eq!(seen.len(), 7, "the scene's, five methods, jittered");
        v.apply(Input::Key(Key::Char('s')));
        assert_eq!(v.toggles.shadows, Shadows::Scene);
        let displays = Display::cycle();
        for d in displays.iter().skip(1) {
            v.apply(Input::Key(Key::Char('v')));
            assert_eq!(v.display, *d);
        }
        v.apply(Input::Key(Key::Char('v')));
        assert_eq!(v.display, Display::Image);
        assert_eq!(v.apply(Input::Key(Key::Char('p'))), Request::Reload);
        assert!(!v.toggles.ground);
        assert_eq!(v.apply(Input::Key(Key::Char('c'))), Request::Reload);
        assert!(!v.toggles.exact_csg);
        v.apply(Input::Key(Key::Char('r')));
        v.apply(Input::Key(Key::Char('g')));
        assert_eq!(v.apply(Input::Key(Key::Char('m'))), Request::Render);
        assert!(!v.toggles.ghosts);
        assert!(!v.toggles.traced && !v.toggles.fog, "R and G turn them off");
        assert_eq!(v.apply(Input::Key(Key::Char('x'))), Request::Render);
        assert!(v.toggles.xray, "X turns x-ray on");
        let mut styles = Vec::new();
        for _ in 0..3 {
            assert_eq!(v.apply(Input::Key(Key::Char('l'))), Request::Render);
            styles.push(v.toggles.lines);
        }
        assert_eq!(styles, [LineStyle::Lines, LineStyle::Drawing, LineStyle::Off], "L cycles the line styles");
        assert_eq!(v.apply(Input::Key(Key::Char('['))), Request::Nothing, "no section to move");
        let mut sections = Vec::new();
        for key in ['k', ']', ']', 'k', '[', 'k', 'k'] {
            assert_eq!(v.apply(Input::Key(Key::Char(key))), Request::Reload);
            sections.push(v.toggles.section);
        }
        let want = [Some((0, 10)), Some((0, 11)), Some((0, 12)), Some((1, 12)), Some((1, 11)), Some((2, 11)), None];
        assert_eq!(sections, want);
        assert_eq!(v.apply(Input::Key(Key::Escape)), Request::Quit);
        assert_eq!(v.apply(Input::Key(Key::Char('q'))), Request::Quit);
        assert_eq!(v.apply(Input::Key(Key::F12)), Request::Screenshot);
        let path = PathBuf::from("part.stl");
        assert_eq!(v.apply(Input::Dropped(path.clone())), Request::Open(path));
        assert_eq!(v.apply(Input::FileChanged), Request::Reload);
        assert_eq!(next(&mut v), Some(Step::Quick), "a reload starts the refinement over");
    }

    /// A resize to the same size or to nothing changes nothing.
    #[test]
    fn resizes_render_only_when_the_size_changes() {
        let mut v = viewer();
        assert_eq!(v.apply(Input::Resize(1280, 720)), Request::Nothing);
        assert_eq!(v.apply(Input::Resize(0, 0)), Request::Nothing);
        assert_eq!(v.apply(Input::Resize(640, 480)), Request::Render);
        assert_eq!(v.size, (640, 480));
    }
}
