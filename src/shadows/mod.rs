//! Shadows: the shadow term `shadow_i(x, y)` ∈ [0, 1] of seed 002 eq. 4, one per
//! light, multiplying that light's diffuse and specular components (never its
//! ambient).
//!
//! This is the plain version — shadow maps (`map.rs`) placed per light type:
//! a spot light sees its cone through one perspective map, a point light through a
//! cube of six 90° maps, a directional light through one orthographic map fitted to
//! the part of the scene the camera sees. The silhouette-line buffer (seed 000) and
//! the two-map soft shadows (seed 001) plug into the same [`ShadowTerm`].

mod footprint;
mod map;
pub mod pcss;
pub mod screen;
pub mod slb;
pub mod soft;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use wide::f32x8;

pub use footprint::{PixelView, Receiver, ReceiverLanes, UNKNOWN_RECEIVER};
pub use map::{DepthMap, Located, LocatedLanes};
pub use pcss::PcssLight;
pub use screen::{ScreenSurfaces, ScreenTerm, SurfaceRows, VisibleSurface};
pub use slb::SlbMap;
pub use soft::TwoMaps;

use crate::scene::{GeometryKey, HardShadows, Light, LightKind, Scene, ShadowMethod, ShadowSettings};

use crate::camera::{Camera, Projection};
use crate::visibility::{VisibilityBuffer, Workers};

/// Widest spot cone (half-angle, degrees) one perspective map covers; wider spots
/// use a cube like point lights.
const MAX_SPOT_HALF_ANGLE_DEG: f32 = 75.0;

/// How one light's shadow term is evaluated.
#[derive(Debug, Clone)]
pub enum ShadowTerm {
    /// No shadow: the light reaches every point.
    Unshadowed,
    /// One map (spot, directional).
    Map(Box<DepthMap>, ShadowSettings),
    /// Six maps around a point (point lights, wide spots): +x, −x, +y, −y, +z, −z,
    /// each at half the configured resolution.
    Cube(Box<[DepthMap; 6]>, Vec3, ShadowSettings),
    /// One map with its silhouette-line buffer (seed 000).
    Slb(Box<SlbMap>, ShadowSettings),
    /// Six of them around a point.
    SlbCube(Box<[SlbMap; 6]>, Vec3, ShadowSettings),
    /// Soft shadows from two hard shadows (seed 001), computed per pixel of
    /// the frame ([`ShadowTerm::prepare`]).
    Soft(Box<TwoMaps>),
    /// Percentage-closer soft shadows over a hard term's maps (a `Map` or a
    /// `Cube`).
    Pcss(Box<ShadowTerm>, PcssLight),
}

impl ShadowTerm {
    /// Builds the term of `light` in `scene`, rendering its maps.
    #[must_use]
    pub fn build(scene: &Scene, light: &Light) -> ShadowTerm {
        match scene.caster_bounds() {
            Some(bounds) => ShadowTerm::build_within(scene, light, bounds, &mut MapPool::default()),
            None => ShadowTerm::Unshadowed,
        }
    }

    /// [`ShadowTerm::build`] with the casters' bounds already known, its maps in
    /// buffers taken from `pool` (give them back with [`MapPool::recycle`]).
    #[must_use]
    pub fn build_within(scene: &Scene, light: &Light, bounds: (Vec3, Vec3), pool: &mut MapPool) -> ShadowTerm {
        match light.shadow.method {
            ShadowMethod::Soft => return ShadowTerm::build_soft(scene, light, bounds, pool),
            ShadowMethod::Pcss => return ShadowTerm::build_pcss(scene, light, bounds, pool),
            _ => {}
        }
        let settings = light.shadow;
        let view = *pool.view(scene);
        let casters = pool.casters(scene);
        let (w, h) = (scene.width, scene.height);
        let slb = settings.method == ShadowMethod::Slb;
        let map = |cam: Camera, most: u32, pool: &mut MapPool| {
            let res = map_resolution(&settings, most, &view, (w, h), &cam, bounds);
            DepthMap::render(scene, &cam, res, &casters, pool.workers, pool.take())
        };
        let lines = |cam: Camera, most: u32, pool: &mut MapPool| {
            let res = map_resolution(&settings, most, &view, (w, h), &cam, bounds);
            SlbMap::render(scene, &cam, res, &casters, pool.workers, pool.take(), &settings)
        };
        // A cube's six faces take half the resolution: 1.5 single maps of memory.
        let (single, face) = (settings.resolution.max(1), (settings.resolution / 2).max(16));
        // The virtual projection space (seed 000 §4.4): the view `scale` times wider.
        let scale = if slb { settings.scale.max(f32::MIN_POSITIVE) } else { 1.0 };
        let one = |cam: Camera, pool: &mut MapPool| {
            if slb {
                ShadowTerm::Slb(Box::new(lines(cam, single, pool)), settings)
            } else {
                ShadowTerm::Map(Box::new(map(cam, single, pool)), settings)
            }
        };
        match placement(light, bounds) {
            Placement::None => ShadowTerm::Unshadowed,
            Placement::Cone { eye, axis, fov_y_deg } => {
                let wider = 2.0 * ((fov_y_deg.to_radians() * 0.5).tan() * scale).atan().to_degrees().min(85.0);
                let fov_y_deg = if slb { wider } else { fov_y_deg };
                one(light_camera(eye, axis, Projection::Perspective { fov_y_deg }, bounds), pool)
            }
            Placement::Cube { eye } => {
                let cams = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z]
                    .map(|axis| (axis, light_camera(eye, axis, Projection::Perspective { fov_y_deg: 90.0 }, bounds)));
                if slb {
                    let faces = cams.map(|(axis, cam)| {
                        // No caster in this face's pyramid: nothing to draw.
                        let most = if face_sees(eye, axis, bounds) { face } else { 1 };
                        lines(cam, most, pool)
                    });
                    return ShadowTerm::SlbCube(Box::new(faces), eye, settings);
                }
                let faces = cams.map(|(axis, cam)| {
                    if face_sees(eye, axis, bounds) {
                        map(cam, face, pool)
                    } else {
                        DepthMap::empty(&cam, pool.take())
                    }
                });
                ShadowTerm::Cube(Box::new(faces), eye, settings)
            }
            Placement::Parallel { direction } => {
                let aspect = w as f32 / h as f32;
                let mut cam = fitted_orthographic(&view, aspect, direction, bounds);
                if let Projection::Orthographic { height } = &mut cam.projection {
                    *height *= scale;
                }
                one(cam, pool)
            }
        }
    }

    /// The two-map soft term of `light`: its hard shadows (by
    /// [`ShadowSettings::hard`]) from the two points of seed 001, or its
    /// hard shadow alone where it has no size.
    fn build_soft(scene: &Scene, light: &Light, bounds: (Vec3, Vec3), pool: &mut MapPool) -> ShadowTerm {
        let hard = soft_hard_settings(&light.shadow);
        let mut build = |l: &Light| ShadowTerm::build_within(scene, &Light { shadow: hard, ..l.clone() }, bounds, pool);
        match TwoMaps::build(light, bounds, &mut build) {
            Some(two) => ShadowTerm::Soft(Box::new(two)),
            None => build(light),
        }
    }

    /// The PCSS term of `light`: a hard map (or cube) from its centre, read
    /// by [`pcss::lit`].
    fn build_pcss(scene: &Scene, light: &Light, bounds: (Vec3, Vec3), pool: &mut MapPool) -> ShadowTerm {
        let hard = pcss_hard_settings(&light.shadow);
        let term = ShadowTerm::build_within(scene, &Light { shadow: hard, ..light.clone() }, bounds, pool);
        let (size, at) = match light.kind {
            LightKind::Point { position } | LightKind::Spot { position, .. } => (light.size.max(0.0), position),
            LightKind::Directional { .. } => return term,
        };
        // The nearest caster: the distance to the casters' bounds (a light
        // among them: a small share of the way to their centre).
        let centre = (bounds.0 + bounds.1) * 0.5;
        let outside = (bounds.0 - at).max(at - bounds.1).max(Vec3::ZERO).length();
        let nearest = outside.max(0.05 * (centre - at).length()).max(f32::MIN_POSITIVE);
        ShadowTerm::Pcss(Box::new(term), PcssLight { size, nearest })
    }

    /// Bytes the maps of `light` hold at most (before they are rendered) in a
    /// scene with these bounds, counted from the maps its method builds: at
    /// the full configured resolution, a cube's six faces at half of it, a
    /// two-map soft term's hard shadows from each of its points (two, or the
    /// ring's four), a silhouette-line buffer's lines on top of its map
    /// ([`slb_bytes`]), PCSS's one map. A per-pixel term's screen images are
    /// the frame's and not counted.
    #[must_use]
    pub fn bytes_needed(light: &Light, bounds: (Vec3, Vec3)) -> usize {
        let with = |l: &Light, shadow: ShadowSettings| Self::bytes_needed(&Light { shadow, ..l.clone() }, bounds);
        match light.shadow.method {
            ShadowMethod::Soft => {
                let hard = soft_hard_settings(&light.shadow);
                match TwoMaps::hard_lights(light, bounds) {
                    Some(lights) => lights.iter().map(|l| with(l, hard)).sum(),
                    None => with(light, hard),
                }
            }
            ShadowMethod::Pcss => with(light, pcss_hard_settings(&light.shadow)),
            ShadowMethod::None | ShadowMethod::Map | ShadowMethod::Slb => {
                let res = light.shadow.resolution.max(1) as usize;
                let map = |res: usize| {
                    let depth = res * res * std::mem::size_of::<f32>();
                    depth + if light.shadow.method == ShadowMethod::Slb { slb_bytes(res) } else { 0 }
                };
                match placement(light, bounds) {
                    Placement::None => 0,
                    Placement::Cone { .. } | Placement::Parallel { .. } => map(res),
                    Placement::Cube { .. } => 6 * map((res / 2).max(16)),
                }
            }
        }
    }

    /// The terms of every light of `scene`.
    #[must_use]
    pub fn build_all(scene: &Scene) -> Vec<ShadowTerm> {
        scene.lights.iter().map(|l| ShadowTerm::build(scene, l)).collect()
    }

    /// Sets the pixel rays of the frame its lookups are for (antialiased
    /// silhouette-line lookups average over each pixel's footprint; other
    /// methods ignore it).
    pub fn set_view(&mut self, view: Option<PixelView>) {
        match self {
            ShadowTerm::Slb(map, _) => map.set_view(view),
            ShadowTerm::SlbCube(faces, ..) => faces.iter_mut().for_each(|f| f.set_view(view)),
            ShadowTerm::Soft(two) => two.set_view(view),
            _ => {}
        }
    }

    /// Whether this term is computed per pixel of the frame, and needs
    /// [`ShadowTerm::prepare`] before its lookups.
    #[must_use]
    pub fn per_pixel(&self) -> bool {
        matches!(self, ShadowTerm::Soft(_))
    }

    /// Computes a per-pixel term at every pixel of the frame whose surfaces
    /// are `surfaces` (others have nothing to compute). Its lookups of
    /// points the frame's pixels show read the result; other points (a
    /// reflection's) are decided on their own.
    pub fn prepare(&mut self, surfaces: &ScreenSurfaces) {
        if let ShadowTerm::Soft(two) = self {
            two.prepare(surfaces);
        }
    }

    /// Whether this term can shadow anything.
    #[must_use]
    pub fn casts(&self) -> bool {
        !matches!(self, ShadowTerm::Unshadowed)
    }

    /// `shadow_i` at world point `p` on `receiver` with N·L = `cos_theta`: 1
    /// lit, 0 in shadow (between on an antialiased edge).
    #[must_use]
    pub fn lit(&self, p: Vec3, cos_theta: f32, receiver: &Receiver) -> f32 {
        match self {
            ShadowTerm::Unshadowed => 1.0,
            ShadowTerm::Map(map, s) => map.lit(p, cos_theta, s),
            ShadowTerm::Cube(faces, centre, s) => faces[cube_face(p - *centre)].lit(p, cos_theta, s),
            ShadowTerm::Slb(map, s) => map.lit(p, cos_theta, s, receiver),
            ShadowTerm::SlbCube(faces, centre, s) => faces[cube_face(p - *centre)].lit(p, cos_theta, s, receiver),
            ShadowTerm::Soft(two) => two.lit(p, cos_theta, receiver),
            ShadowTerm::Pcss(hard, light) => match hard.as_ref() {
                ShadowTerm::Map(map, s) => pcss::lit(map, p, cos_theta, s, light),
                ShadowTerm::Cube(faces, centre, s) => pcss::lit(&faces[cube_face(p - *centre)], p, cos_theta, s, light),
                other => other.lit(p, cos_theta, receiver),
            },
        }
    }

    /// [`ShadowTerm::lit`] for eight points (x, y, z lanes) on `receivers`
    /// with N·L `cos_theta`.
    #[must_use]
    pub fn lit_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
        match self {
            ShadowTerm::Unshadowed => f32x8::ONE,
            ShadowTerm::Map(map, s) => map.lit_lanes(p, cos_theta, s),
            ShadowTerm::Cube(faces, centre, s) => match same_cube_face(p, *centre) {
                // Neighbouring pixels usually look into the same face.
                Some(face) => faces[face].lit_lanes(p, cos_theta, s),
                None => self.lit_each(p, cos_theta, receivers),
            },
            ShadowTerm::Slb(map, s) => map.lit_lanes(p, cos_theta, s, receivers),
            ShadowTerm::Pcss(hard, light) => match hard.as_ref() {
                ShadowTerm::Map(map, s) => pcss::lit_lanes(map, p, cos_theta, s, light),
                ShadowTerm::Cube(faces, centre, s) => match same_cube_face(p, *centre) {
                    Some(face) => pcss::lit_lanes(&faces[face], p, cos_theta, s, light),
                    None => self.lit_each(p, cos_theta, receivers),
                },
                _ => self.lit_each(p, cos_theta, receivers),
            },
            ShadowTerm::SlbCube(..) | ShadowTerm::Soft(_) => self.lit_each(p, cos_theta, receivers),
        }
    }

    /// [`ShadowTerm::lit`] at each of eight points in turn.
    fn lit_each(&self, p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
        let (x, y, z, c) = (p[0].to_array(), p[1].to_array(), p[2].to_array(), cos_theta.to_array());
        f32x8::new(std::array::from_fn(|i| self.lit(Vec3::new(x[i], y[i], z[i]), c[i], &receivers.lane(i))))
    }

    /// The mean of `terms`' [`ShadowTerm::lit`] (1 when there are none): the
    /// shadow term of an area light from its jittered samples' maps.
    #[must_use]
    pub fn mean_lit(terms: &[ShadowTerm], p: Vec3, cos_theta: f32, receiver: &Receiver) -> f32 {
        match terms {
            [] => 1.0,
            [one] => one.lit(p, cos_theta, receiver),
            _ => terms.iter().map(|t| t.lit(p, cos_theta, receiver)).sum::<f32>() / terms.len() as f32,
        }
    }

    /// [`ShadowTerm::mean_lit`] for eight points.
    #[must_use]
    pub fn mean_lit_lanes(terms: &[ShadowTerm], p: [f32x8; 3], cos_theta: f32x8, receivers: &ReceiverLanes) -> f32x8 {
        match terms {
            [] => f32x8::ONE,
            [one] => one.lit_lanes(p, cos_theta, receivers),
            _ => {
                let sum = terms.iter().fold(f32x8::ZERO, |acc, t| acc + t.lit_lanes(p, cos_theta, receivers));
                sum * f32x8::splat(1.0 / terms.len() as f32)
            }
        }
    }

    /// Bytes held by the maps.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        match self {
            ShadowTerm::Unshadowed => 0,
            ShadowTerm::Map(m, _) => m.memory_bytes(),
            ShadowTerm::Cube(f, ..) => f.iter().map(DepthMap::memory_bytes).sum(),
            ShadowTerm::Slb(m, _) => m.memory_bytes(),
            ShadowTerm::SlbCube(f, ..) => f.iter().map(SlbMap::memory_bytes).sum(),
            ShadowTerm::Soft(two) => two.memory_bytes(),
            ShadowTerm::Pcss(hard, _) => hard.memory_bytes(),
        }
    }
}

/// The settings of a two-map soft term's hard shadows: its `hard` method,
/// one map each.
fn soft_hard_settings(soft: &ShadowSettings) -> ShadowSettings {
    let method = match soft.hard {
        HardShadows::Map => ShadowMethod::Map,
        HardShadows::Slb => ShadowMethod::Slb,
    };
    ShadowSettings { samples: 1, ..soft.with_method(method) }
}

/// The settings of PCSS's one hard map: no filter of its own.
fn pcss_hard_settings(pcss: &ShadowSettings) -> ShadowSettings {
    ShadowSettings { samples: 1, pcf: 1, ..pcss.with_method(ShadowMethod::Map) }
}

/// Silhouette lines each texel of a silhouette-line buffer is budgeted,
/// on average over the map (the edge texels' share times their lines): the
/// example scenes' 1024² maps hold 0.013 (the demo) to 0.058 (the atrium's
/// arcades), measured by `every_methods_maps_fit_the_memory_it_budgets` in
/// `tests/shadows.rs`, which holds the budget to what the maps take.
const SLB_LINES_PER_TEXEL: f64 = 0.08;

/// Bytes a silhouette-line buffer adds to a map of `res` × `res` texels:
/// the map's item per texel (which object is nearest the light), its edge
/// bits, ranks and solids' step bits (1.5 + 1 bits a texel), the busy bits
/// and ranks of the texels round the lines (1.5 bits a texel), and per
/// budgeted line its record, its texel's start indices, a surface over the
/// texel's centre and the nearest depth round three texels (a line's texel
/// and the two beside it across the line).
#[must_use]
pub fn slb_bytes(res: usize) -> usize {
    let texels = res * res;
    let per_line = std::mem::size_of::<slb::line::SilhouetteLine>() + std::mem::size_of::<slb::line::Layer>() + 8 + 12;
    let per_texel = std::mem::size_of::<crate::visibility::ItemId>() * 16 + 8;
    texels * per_texel / 16 + (texels as f64 * SLB_LINES_PER_TEXEL) as usize * per_line
}

/// How a light's shadow maps are placed.
enum Placement {
    /// No shadows.
    None,
    /// One perspective map from `eye` along `axis`.
    Cone { eye: Vec3, axis: Vec3, fov_y_deg: f32 },
    /// Six 90° maps around `eye`.
    Cube { eye: Vec3 },
    /// One orthographic map fitted to the view.
    Parallel { direction: Vec3 },
}

/// A spot light sees through its own cone; a point light (or a spot wider than
/// one map can hold) outside the scene's bounding sphere sees the whole scene
/// through one cone just holding that sphere (the peers' placement), and needs a
/// cube only when it is among the objects.
fn placement(light: &Light, bounds: (Vec3, Vec3)) -> Placement {
    if !light.casts_shadows() {
        return Placement::None;
    }
    let (centre, radius) = ((bounds.0 + bounds.1) * 0.5, (bounds.1 - bounds.0).length() * 0.5);
    match light.kind {
        LightKind::Spot { position, direction, outer, .. } if outer.to_degrees() <= MAX_SPOT_HALF_ANGLE_DEG => {
            Placement::Cone { eye: position, axis: direction, fov_y_deg: (2.0 * outer.to_degrees() + 2.0).min(170.0) }
        }
        LightKind::Point { position } | LightKind::Spot { position, .. } => {
            let to_centre = centre - position;
            let half = (radius / to_centre.length().max(f32::MIN_POSITIVE)).min(1.0).asin().to_degrees();
            if half + 1.0 <= MAX_SPOT_HALF_ANGLE_DEG {
                Placement::Cone { eye: position, axis: to_centre.normalize(), fov_y_deg: 2.0 * half + 2.0 }
            } else {
                Placement::Cube { eye: position }
            }
        }
        LightKind::Directional { direction } => Placement::Parallel { direction },
    }
}

/// Depth buffers kept from one shadow map to the next and from frame to frame
/// (a fresh 2048² map costs ~2 ms of page faults alone), and the shadow terms
/// of the last frame, reused while nothing they depend on changes: an
/// interactive viewer whose camera moves re-renders no spot or point light's
/// maps (a directional light's map is fitted to the view, so it follows the
/// camera; the jittered passes of one frame share the map fitted to the
/// unshifted view: [`MapPool::fit_to`]).
#[derive(Debug)]
pub struct MapPool {
    free: Vec<VisibilityBuffer>,
    /// Terms of this frame, offered to the next.
    kept: Vec<(MapKey, ShadowTerm)>,
    /// Terms of the last frame not yet taken by this one.
    previous: Vec<(MapKey, ShadowTerm)>,
    /// The geometry the kept terms saw: every object's body, transform and
    /// whether it casts shadows.
    geometry: GeometryKey,
    /// Terms reused since [`MapPool::begin_frame`].
    reused: usize,
    /// The view directional lights' maps are fitted to (`None`: each scene's
    /// camera).
    view: Option<Camera>,
    /// Where the pool's maps are drawn: on every worker, or on the calling one
    /// (a pool lent to one of several maps drawn side by side).
    workers: Workers,
    /// The objects this frame's maps draw ([`Scene::map_casters`]), found
    /// once a frame ([`MapPool::begin_frame`]; empty: found per term).
    casters: Vec<bool>,
    /// Whether the shadow stage measures its workers' idle time.
    measure_idle: bool,
}

impl Default for MapPool {
    fn default() -> Self {
        MapPool {
            free: Vec::new(),
            kept: Vec::new(),
            previous: Vec::new(),
            geometry: GeometryKey::default(),
            reused: 0,
            view: None,
            workers: Workers::All,
            casters: Vec::new(),
            measure_idle: false,
        }
    }
}

/// What a light's shadow term depends on besides the geometry.
#[derive(Debug, Clone, PartialEq)]
struct MapKey {
    light: Light,
    bounds: (Vec3, Vec3),
    /// The view, for a map fitted to it (directional lights).
    view: Option<(Camera, u32, u32)>,
    /// For a map sized by need, the octave of the pixel size it was sized
    /// for: a camera moving within it keeps the map.
    octave: Option<i32>,
}

impl MapKey {
    fn of(scene: &Scene, light: &Light, bounds: (Vec3, Vec3), view: &Camera) -> MapKey {
        let fitted = matches!(placement(light, bounds), Placement::Parallel { .. });
        let octave =
            light.shadow.by_need.then(|| pixel_size(view, (scene.width, scene.height), bounds).log2().floor() as i32);
        MapKey { light: light.clone(), bounds, view: fitted.then_some((*view, scene.width, scene.height)), octave }
    }
}

impl MapPool {
    /// Forgets every kept term (their buffers stay, for reuse): the next
    /// frame renders every map again.
    pub fn forget(&mut self) {
        let kept: Vec<_> = self.kept.drain(..).chain(self.previous.drain(..)).collect();
        kept.into_iter().for_each(|(_, term)| self.recycle(term));
    }

    /// Starts a frame of `scene`: last frame's terms become reusable, unless
    /// the geometry changed ([`GeometryKey`]: an object's body, transform or
    /// whether it casts shadows), which drops them all.
    pub fn begin_frame(&mut self, scene: &Scene) {
        if !self.geometry.matches(scene) {
            self.geometry = GeometryKey::of(scene);
            let stale: Vec<_> = self.kept.drain(..).chain(self.previous.drain(..)).collect();
            stale.into_iter().for_each(|(_, term)| self.recycle(term));
        }
        let previous = std::mem::take(&mut self.kept);
        let older = std::mem::replace(&mut self.previous, previous);
        older.into_iter().for_each(|(_, term)| self.recycle(term));
        self.reused = 0;
        self.casters = scene.map_casters();
    }

    /// The objects the maps of `scene` draw: this frame's, or found now when
    /// the pool has not begun a frame of a scene of this many objects.
    fn casters(&self, scene: &Scene) -> Vec<bool> {
        if self.casters.len() == scene.objects.len() {
            self.casters.clone()
        } else {
            scene.map_casters()
        }
    }

    /// The shadow term of `light`: last frame's if it still holds, else newly
    /// rendered. Give it back with [`MapPool::keep`] or [`MapPool::recycle`].
    pub fn term(&mut self, scene: &Scene, light: &Light, bounds: (Vec3, Vec3)) -> ShadowTerm {
        let key = MapKey::of(scene, light, bounds, self.view(scene));
        self.reuse(&key).unwrap_or_else(|| ShadowTerm::build_within(scene, light, bounds, self))
    }

    /// Last frame's term for `key`, if it is still held (counted as reused).
    fn reuse(&mut self, key: &MapKey) -> Option<ShadowTerm> {
        let k = self.previous.iter().position(|(have, _)| have == key)?;
        self.reused += 1;
        Some(self.previous.swap_remove(k).1)
    }

    /// The shadow terms of `lights` (an area light's jittered samples), as
    /// [`MapPool::term`] gives each: those to render drawn side by side, one
    /// per worker, each map's triangles on its worker alone
    /// ([`Workers::One`]), which for two or more maps takes less time than
    /// drawing them one after another across all workers: 0.79× for a lone
    /// Stanford bunny's four 512² maps, 0.77× for the demo's eight 1024² maps
    /// and its sun's (two workers, the two ways alternated in one build).
    pub fn terms(&mut self, scene: &Scene, lights: &[Light], bounds: (Vec3, Vec3)) -> Vec<ShadowTerm> {
        let key = |l: &Light| MapKey::of(scene, l, bounds, self.view(scene));
        let keys: Vec<MapKey> = lights.iter().map(key).collect();
        let mut terms: Vec<Option<ShadowTerm>> = keys.iter().map(|key| self.reuse(key)).collect();
        let todo: Vec<usize> = (0..lights.len()).filter(|&i| terms[i].is_none()).collect();
        if todo.len() < 2 || rayon::current_num_threads() < 2 {
            for i in todo {
                terms[i] = Some(ShadowTerm::build_within(scene, &lights[i], bounds, self));
            }
        } else {
            let mut lent: Vec<MapPool> = todo
                .iter()
                .map(|_| MapPool {
                    free: self.free.pop().into_iter().collect(),
                    view: self.view,
                    workers: Workers::One,
                    casters: self.casters.clone(),
                    ..MapPool::default()
                })
                .collect();
            let built: Vec<ShadowTerm> = todo
                .par_iter()
                .zip(lent.par_iter_mut())
                .map(|(&i, pool)| ShadowTerm::build_within(scene, &lights[i], bounds, pool))
                .collect();
            lent.into_iter().for_each(|pool| self.free.extend(pool.free));
            todo.into_iter().zip(built).for_each(|(i, term)| terms[i] = Some(term));
        }
        terms.into_iter().map(|t| t.expect("every term reused or built")).collect()
    }

    /// Calls `f` with `light`'s term of this frame: the one kept for the next
    /// frame ([`MapPool::keep`]) when there is one, else a term rendered for
    /// the call and recycled after it.
    pub fn with_term<T>(
        &mut self,
        scene: &Scene,
        light: &Light,
        bounds: (Vec3, Vec3),
        f: impl FnOnce(&mut ShadowTerm) -> T,
    ) -> T {
        let key = MapKey::of(scene, light, bounds, self.view(scene));
        if let Some((_, term)) = self.kept.iter_mut().find(|(have, _)| *have == key) {
            return f(term);
        }
        let mut term = ShadowTerm::build_within(scene, light, bounds, self);
        let out = f(&mut term);
        self.recycle(term);
        out
    }

    /// Keeps `light`'s term for the next frame.
    pub fn keep(&mut self, scene: &Scene, light: &Light, bounds: (Vec3, Vec3), term: ShadowTerm) {
        self.kept.push((MapKey::of(scene, light, bounds, self.view(scene)), term));
    }

    /// Fits directional lights' maps to `view` instead of each scene's camera
    /// (`None`): the jittered passes of a frame shift the camera by a fraction
    /// of a pixel each, and share the maps fitted to the unshifted view.
    pub fn fit_to(&mut self, view: Option<Camera>) {
        self.view = view;
    }

    /// The view directional lights' maps are fitted to in `scene`.
    fn view<'a>(&'a self, scene: &'a Scene) -> &'a Camera {
        self.view.as_ref().unwrap_or(&scene.camera)
    }

    /// Has the shadow stage measure the time its workers have no work
    /// ([`crate::idle`]), or not.
    pub fn measure_idle(&mut self, on: bool) {
        self.measure_idle = on;
    }

    /// Whether the shadow stage measures its workers' idle time.
    #[must_use]
    pub fn measures_idle(&self) -> bool {
        self.measure_idle
    }

    /// Terms reused from the last frame since this frame began.
    #[must_use]
    pub fn reused(&self) -> usize {
        self.reused
    }
    /// A buffer to render a map into.
    #[must_use]
    pub fn take(&mut self) -> VisibilityBuffer {
        self.free.pop().unwrap_or_else(|| VisibilityBuffer::depth_only(0, 0))
    }

    /// Takes back the buffers of `term`'s maps.
    pub fn recycle(&mut self, term: ShadowTerm) {
        match term {
            ShadowTerm::Unshadowed => {}
            ShadowTerm::Map(map, _) => self.free.push((*map).into_buffer()),
            ShadowTerm::Cube(faces, ..) => self.free.extend(faces.into_iter().map(DepthMap::into_buffer)),
            ShadowTerm::Slb(map, _) => self.free.push(map.into_buffer()),
            ShadowTerm::SlbCube(faces, ..) => self.free.extend(faces.into_iter().map(SlbMap::into_buffer)),
            ShadowTerm::Soft(two) => two.into_hard().into_iter().for_each(|t| self.recycle(t)),
            ShadowTerm::Pcss(hard, _) => self.recycle(*hard),
        }
    }

    /// Bytes held by the pool: free buffers and kept terms.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        let kept = self.kept.iter().chain(&self.previous).map(|(_, t)| t.memory_bytes()).sum::<usize>();
        self.free.iter().map(VisibilityBuffer::memory_bytes).sum::<usize>() + kept
    }
}

/// The cube face every one of eight points (x, y, z lanes) lies in, seen
/// from `centre`, if they share one.
fn same_cube_face(p: [f32x8; 3], centre: Vec3) -> Option<usize> {
    let (x, y, z) = (p[0].to_array(), p[1].to_array(), p[2].to_array());
    let first = cube_face(Vec3::new(x[0], y[0], z[0]) - centre);
    (1..8).all(|i| cube_face(Vec3::new(x[i], y[i], z[i]) - centre) == first).then_some(first)
}

/// The cube face (+x, −x, +y, −y, +z, −z) that direction `d` from the centre
/// looks into.
fn cube_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        usize::from(d.x < 0.0)
    } else if a.y >= a.z {
        2 + usize::from(d.y < 0.0)
    } else {
        4 + usize::from(d.z < 0.0)
    }
}

/// Fewest texels a map chosen by need has along a side: below it a map costs
/// its triangles, hardly its texels, and a small image's soft shadows would
/// show the texels.
const MIN_NEEDED_RESOLUTION: u32 = 512;

/// Texels along a side of the map `light_cam` renders for a light with
/// `settings`, in a frame of `size` pixels seen through `view`, of casters
/// within `bounds`: `most` (the configured resolution; a cube face: half of
/// it), or by need at most that — two texels across a pixel at the casters' centre,
/// where their shadows fall (with one, shadow maps and shadow rays disagree on
/// 1.3% of the lit tests of the CAD example, against under 0.5%), half of one
/// for a soft light's jittered maps (their average hides the coarser texels), more
/// for a light low over the floor (whose texels the floor stretches); the
/// nearest power of two, so a camera moving a little keeps a kept map's size.
fn map_resolution(
    settings: &ShadowSettings,
    most: u32,
    view: &Camera,
    size: (u32, u32),
    light_cam: &Camera,
    bounds: (Vec3, Vec3),
) -> u32 {
    if !settings.by_need {
        return most;
    }
    let centre = (bounds.0 + bounds.1) * 0.5;
    let pixel = pixel_size(view, size, bounds);
    let covered = match light_cam.projection {
        Projection::Perspective { fov_y_deg } => {
            let along = (centre - light_cam.eye).length().max(light_cam.near);
            2.0 * along * (fov_y_deg.to_radians() * 0.5).tan()
        }
        Projection::Orthographic { height } => height,
    };
    let per_pixel = if settings.samples > 1 { 0.5 } else { 2.0 };
    // A light low over the floor stretches each texel along the floor by
    // 1 / sin(elevation): up to four times.
    let towards = match light_cam.projection {
        Projection::Perspective { .. } => (centre - light_cam.eye).normalize_or(Vec3::NEG_Y),
        Projection::Orthographic { .. } => (light_cam.target - light_cam.eye).normalize_or(Vec3::NEG_Y),
    };
    let stretch = 1.0 / towards.y.abs().max(0.25);
    let need = per_pixel * stretch * covered / pixel.max(f32::MIN_POSITIVE);
    if !need.is_finite() {
        return most;
    }
    // The nearest power of two: a texel between 0.7 and 1.4 pixels wide.
    let octave = need.max(1.0).log2().round().min(16.0) as u32;
    (1u32 << octave).clamp(MIN_NEEDED_RESOLUTION.min(most), most)
}

/// The world width of a pixel at the centre of `bounds`, seen through `view`
/// in a frame of `size` pixels.
fn pixel_size(view: &Camera, size: (u32, u32), bounds: (Vec3, Vec3)) -> f32 {
    let centre = (bounds.0 + bounds.1) * 0.5;
    match view.projection {
        Projection::Perspective { fov_y_deg } => {
            let along = (centre - view.eye).dot((view.target - view.eye).normalize()).max(view.near);
            2.0 * along * (fov_y_deg.to_radians() * 0.5).tan() / size.1 as f32
        }
        Projection::Orthographic { height } => height / size.1 as f32,
    }
}

/// Whether the 90° pyramid of the cube face looking along `axis` from `eye`
/// holds any part of `bounds`: false when all eight corners lie outside one
/// of its four side planes.
fn face_sees(eye: Vec3, axis: Vec3, (lo, hi): (Vec3, Vec3)) -> bool {
    let side = [Vec3::X, Vec3::Y, Vec3::Z].into_iter().filter(|a| a.dot(axis).abs() < 0.5);
    let corners: Vec<Vec3> = (0..8)
        .map(|k| Vec3::new([lo.x, hi.x][k & 1], [lo.y, hi.y][(k >> 1) & 1], [lo.z, hi.z][(k >> 2) & 1]) - eye)
        .collect();
    // Inside: (axis · d) ≥ |s · d| for both side axes s.
    side.flat_map(|s| [s, -s]).all(|s| corners.iter().any(|&d| axis.dot(d) >= s.dot(d)))
}

/// A camera at `eye` looking along `axis` whose depth range holds `bounds`.
fn light_camera(eye: Vec3, axis: Vec3, projection: Projection, bounds: (Vec3, Vec3)) -> Camera {
    let (lo, hi) = bounds;
    let r = ((hi - lo).length() * 0.5).max(1e-6);
    let far = (eye - (lo + hi) * 0.5).length() + 2.0 * r;
    Camera {
        eye,
        target: eye + axis,
        up: up_for(axis),
        near: (r * 1e-4).min(far * 1e-3),
        far,
        projection,
        shift: Vec2::ZERO,
    }
}

/// An up vector not parallel to `axis`.
fn up_for(axis: Vec3) -> Vec3 {
    if axis.normalize().y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// The orthographic light camera of a directional light travelling along `dir`:
/// across the light, the intersection of the scene's bounds with what the eye sees
/// (its view frustum cut at the far side of the scene); along it, the whole scene,
/// so casters outside the view still cast into it.
fn fitted_orthographic(eye: &Camera, aspect: f32, dir: Vec3, bounds: (Vec3, Vec3)) -> Camera {
    let dir = dir.normalize();
    let up = up_for(dir);
    let right = dir.cross(up).normalize();
    let up = right.cross(dir);
    let to_light = |p: Vec3| Vec3::new(p.dot(right), p.dot(up), p.dot(dir));
    let (lo, hi) = bounds;
    let corners: Vec<Vec3> = (0..8)
        .map(|k| Vec3::new([lo.x, hi.x][k & 1], [lo.y, hi.y][(k >> 1) & 1], [lo.z, hi.z][(k >> 2) & 1]))
        .collect();
    let (mut slo, mut shi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &c in &corners {
        let l = to_light(c);
        (slo, shi) = (slo.min(l), shi.max(l));
    }
    // The eye's frustum, from its near plane to the farthest scene corner.
    let rays = eye.pixel_rays(Vec2::new(aspect, 1.0));
    let fwd = (eye.target - eye.eye).normalize();
    let reach = corners.iter().map(|&c| (c - eye.eye).dot(fwd)).fold(eye.near, f32::max).min(eye.far);
    let (mut flo, mut fhi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for (x, y) in [(0.0, 0.0), (aspect, 0.0), (0.0, 1.0), (aspect, 1.0)] {
        let ray = rays.ray(Vec2::new(x, y));
        let along = ray.dir.dot(fwd).max(1e-6);
        for t in [eye.near, reach] {
            let l = to_light(ray.origin + ray.dir * (t / along));
            (flo, fhi) = (flo.min(l), fhi.max(l));
        }
    }
    let (xy_lo, xy_hi) = (slo.truncate().max(flo.truncate()), shi.truncate().min(fhi.truncate()));
    let (xy_lo, xy_hi) = if xy_lo.cmple(xy_hi).all() { (xy_lo, xy_hi) } else { (slo.truncate(), shi.truncate()) };
    let size = (xy_hi - xy_lo).max_element().max(1e-6) * 1.02;
    let centre = (xy_lo + xy_hi) * 0.5;
    let margin = (shi.z - slo.z).max(1e-6) * 0.01 + 1e-6;
    let eye_pos = right * centre.x + up * centre.y + dir * (slo.z - margin);
    Camera {
        eye: eye_pos,
        target: eye_pos + dir,
        up,
        near: margin * 0.5,
        far: shi.z - slo.z + 2.0 * margin,
        projection: Projection::Orthographic { height: size },
        shift: Vec2::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::radical_inverse;

    /// The eight-lane lookup gives the scalar lookup's answer, lane by lane, for
    /// one tap and for 2 × 2 and 3 × 3 PCF, on the demo's lights.
    #[test]
    fn lanes_equal_scalar_lookups_for_every_pcf_size() {
        let scene = crate::scene::demo::demo_scene().expect("the demo loads");
        // Around the teapot, the cow and the ball, where their shadows fall.
        let (lo, hi) = (Vec3::new(-4.0, 0.0, -3.0), Vec3::new(4.0, 1.5, 3.0));
        for pcf in 1..=3 {
            for light in &scene.lights {
                let mut light = light.clone();
                (light.shadow.pcf, light.shadow.resolution) = (pcf, 512);
                let term = ShadowTerm::build(&scene, &light);
                assert!(term.casts());
                let (mut differ, mut shadowed, mut total) = (0, 0, 0);
                for block in 0..2000u32 {
                    let point = |i: u32| {
                        let k = block * 8 + i + 1;
                        let t = Vec3::new(radical_inverse(k, 2), radical_inverse(k, 3), radical_inverse(k, 5));
                        (lo + (hi - lo) * t, radical_inverse(k, 7))
                    };
                    let lanes: [(Vec3, f32); 8] = std::array::from_fn(|i| point(i as u32));
                    let p = [0, 1, 2].map(|a| f32x8::new(lanes.map(|(p, _)| p[a])));
                    let got = term.lit_lanes(p, f32x8::new(lanes.map(|(_, c)| c)), &ReceiverLanes::UNKNOWN).to_array();
                    for (&(p, c), g) in lanes.iter().zip(got) {
                        let want = term.lit(p, c, &Receiver::UNKNOWN);
                        differ += usize::from((want - g).abs() > 1e-6);
                        shadowed += usize::from(want < 1.0);
                        total += 1;
                    }
                }
                assert!(shadowed * 50 > total && shadowed < total, "pcf {pcf}: {shadowed} of {total} shadowed");
                assert!(differ * 500 < total, "pcf {pcf}: {differ} of {total} lanes differ from the scalar lookup");
            }
        }
    }
}
