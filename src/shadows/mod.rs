//! Shadows: the shadow term `shadow_i(x, y)` ∈ [0, 1] of seed 002 eq. 4, one per
//! light, multiplying that light's diffuse and specular components (never its
//! ambient).
//!
//! Each method is one unit in `methods/` behind one interface
//! ([`Technique`]: what it builds per light, what that needs in memory);
//! the term it builds ([`LightTerm`]) answers per frame (the pixel rays,
//! the surfaces the pixels show) and per point. Map-based methods place
//! their maps by the light's type (`placement.rs`): a spot light sees its
//! cone through one perspective map, a point light through one cone holding
//! the casters or a cube of six 90° maps, a directional light through one
//! orthographic map fitted to the part of the scene the camera sees. The
//! algorithms the units run are in their own modules: depth maps
//! (`map.rs`), the silhouette-line buffer of seed 000 (`slb/`), the two-map
//! soft shadows of seed 001 (`soft/`), PCSS (`pcss.rs`). [`MapPool`] keeps
//! maps' buffers and last frame's terms for the next frame.

mod footprint;
mod map;
pub mod methods;
pub mod pcss;
mod placement;
pub mod screen;
pub mod slb;
pub mod soft;
mod term;

use glam::Vec3;
use rayon::prelude::*;

pub use footprint::{PixelView, Receiver, ReceiverLanes, UNKNOWN_RECEIVER};
pub use map::{BoxBounds, DepthMap, Located, LocatedLanes};
pub use methods::{MapTerm, PcssTerm, SlbTerm, Technique};
pub use pcss::PcssLight;
pub use placement::Maps;
pub use screen::{ScreenSurfaces, ScreenTerm, SurfaceRows, VisibleSurface};
pub use slb::SlbMap;
pub use soft::TwoMaps;
pub use term::{lit_each, LightTerm, ShadowTerm, Unshadowed};

use crate::camera::Camera;
use crate::scene::{GeometryKey, Light, Scene};
use crate::visibility::{VisibilityBuffer, Workers};
use placement::{pixel_size, placement, Placement};

impl ShadowTerm {
    /// Builds the term of `light` in `scene`, rendering its maps.
    #[must_use]
    pub fn build(scene: &Scene, light: &Light) -> ShadowTerm {
        match scene.caster_bounds() {
            Some(bounds) => ShadowTerm::build_within(scene, light, bounds, &mut MapPool::default()),
            None => ShadowTerm::unshadowed(),
        }
    }

    /// [`ShadowTerm::build`] with the casters' bounds already known, its maps in
    /// buffers taken from `pool` (give them back with [`MapPool::recycle`]):
    /// by the light's method's unit ([`methods::technique`]).
    #[must_use]
    pub fn build_within(scene: &Scene, light: &Light, bounds: (Vec3, Vec3), pool: &mut MapPool) -> ShadowTerm {
        methods::technique(light.shadow.method).build(scene, light, bounds, pool)
    }

    /// Bytes the maps of `light` hold at most (before they are rendered) in a
    /// scene with these bounds, as its method counts them
    /// ([`Technique::bytes_needed`]).
    #[must_use]
    pub fn bytes_needed(light: &Light, bounds: (Vec3, Vec3)) -> usize {
        methods::technique(light.shadow.method).bytes_needed(light, bounds)
    }

    /// The terms of every light of `scene`.
    #[must_use]
    pub fn build_all(scene: &Scene) -> Vec<ShadowTerm> {
        scene.lights.iter().map(|l| ShadowTerm::build(scene, l)).collect()
    }
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
        self.begin_frame_drawing(scene, scene.map_casters());
    }

    /// [`MapPool::begin_frame`] with the objects the maps draw already
    /// found ([`Scene::shadow_casters`]).
    pub fn begin_frame_drawing(&mut self, scene: &Scene, casters: Vec<bool>) {
        if !self.geometry.matches(scene) {
            self.geometry = GeometryKey::of(scene);
            let stale: Vec<_> = self.kept.drain(..).chain(self.previous.drain(..)).collect();
            stale.into_iter().for_each(|(_, term)| self.recycle(term));
        }
        let previous = std::mem::take(&mut self.kept);
        let older = std::mem::replace(&mut self.previous, previous);
        older.into_iter().for_each(|(_, term)| self.recycle(term));
        self.reused = 0;
        self.casters = casters;
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
        self.free.extend(term.into_buffers());
    }

    /// Bytes held by the pool: free buffers and kept terms.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        let kept = self.kept.iter().chain(&self.previous).map(|(_, t)| t.memory_bytes()).sum::<usize>();
        self.free.iter().map(VisibilityBuffer::memory_bytes).sum::<usize>() + kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::radical_inverse;
    use wide::f32x8;

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
