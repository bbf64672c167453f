//! What kage's fuzz targets share: the limits every target runs under, the
//! small files a fuzzed scene or model may name (served from memory: a target
//! never touches the disk), the tiny render, and the differential checks
//! of the structure-aware targets.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec2;
use kage::limits::{Limit, LimitSetting, Limits};
use kage::scene::load::InMemory;
use kage::{RenderOptions, Scene};

pub mod spec;

/// Image size every target renders at.
pub const SIZE: (u32, u32) = (32, 24);

/// The limits the targets run under: low enough that whatever passes them
/// fits in the fuzzer's 2 GiB and renders in well under its 10 s timeout at
/// [`SIZE`], so any out-of-memory or timeout is a missing check.
#[must_use]
pub fn settings() -> Vec<LimitSetting> {
    [
        (Limit::Nesting, 200),
        (Limit::GltfNodes, 20_000),
        (Limit::Instances, 5_000),
        (Limit::Segments, 256),
        (Limit::Facets, 5_000),
        (Limit::Triangles, 200_000),
        (Limit::Primitives, 300),
        (Limit::Points, 2_000),
        (Limit::Slices, 64),
        (Limit::TextLength, 64),
        (Limit::TexturePixels, 1 << 20),
        (Limit::LightShadowMb, 64),
        (Limit::FrameShadowMb, 128),
        (Limit::FileMb, 16),
        (Limit::MemoryMb, 512),
    ]
    .into_iter()
    .map(|(limit, value)| LimitSetting { limit, value })
    .collect()
}

/// [`settings`] as limits.
#[must_use]
pub fn limits() -> Limits {
    Limits::default().with_settings(&settings())
}

/// The files a fuzzed input may name, next to `extra` (name, bytes).
#[must_use]
pub fn files(extra: &[(&str, &[u8])]) -> InMemory {
    let mut files: HashMap<PathBuf, Vec<u8>> = HashMap::new();
    let fixed: [(&str, Vec<u8>); 7] = [
        ("tex.png", include_bytes!("../../tests/data/fuzz/tex.png").to_vec()),
        ("env.png", include_bytes!("../../tests/data/fuzz/tex.png").to_vec()),
        ("cube.obj", include_bytes!("../../tests/data/fuzz/cube.obj").to_vec()),
        ("cube.mtl", include_bytes!("../../tests/data/fuzz/cube.mtl").to_vec()),
        ("tri.stl", include_bytes!("../../tests/data/fuzz/tri.stl").to_vec()),
        ("part.csg", include_bytes!("../../tests/data/fuzz/part.csg").to_vec()),
        ("buf.bin", include_bytes!("../../tests/data/fuzz/buf.bin").to_vec()),
    ];
    for (name, bytes) in fixed {
        files.insert(name.into(), bytes);
    }
    for (name, bytes) in extra {
        files.insert(name.into(), bytes.to_vec());
    }
    InMemory { files }
}

/// Renders `scene` at [`SIZE`] and checks the image holds only finite,
/// non-negative values.
///
/// # Panics
///
/// On a refused render of a scene that passed its checks, or a pixel that is
/// not a finite value ≥ 0.
pub fn render_small(mut scene: Scene) {
    (scene.width, scene.height) = SIZE;
    // The global pool (run.sh gives it one thread): no pool made per case.
    let options = RenderOptions::default();
    match kage::render(&scene, &options) {
        Ok(frame) => {
            for (i, p) in frame.image.pixels().iter().enumerate() {
                assert!(p.is_finite() && p.min_element() >= 0.0, "pixel {i} is {p}");
            }
        }
        // A scene may still ask for more than its limits allow.
        Err(kage::Error::Limit(_)) => {}
        Err(e) => panic!("a built scene fails to render: {e}"),
    }
}

/// A model file's bytes (named `name`) loaded and, if it loads, rendered.
pub fn model(name: &str, bytes: &[u8]) {
    model_from(name, &files(&[(name, bytes)]));
}

/// Where two ways of finding what a pixel shows may differ without either
/// being wrong: `cast(offset)` (what is seen through the pixel centre moved
/// by `offset` pixels) does not give one answer within a hundredth of a
/// pixel, so the pixel centre lies on an edge.
pub fn on_an_edge<T: PartialEq>(cast: impl Fn(Vec2) -> T) -> bool {
    let centre = cast(Vec2::ZERO);
    let d = 0.01;
    [Vec2::new(d, 0.0), Vec2::new(-d, 0.0), Vec2::new(0.0, d), Vec2::new(0.0, -d)]
        .into_iter()
        .any(|o| cast(o) != centre)
}

/// Whether distances `a` and `b` along a ray agree to 1e-3 relative.
#[must_use]
pub fn same_distance(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-3 * a.abs().max(b.abs()).max(1.0)
}

/// A model (named `name`, among `files`) loaded and, if it loads, rendered.
pub fn model_from(name: &str, files: &InMemory) {
    let path = Path::new(name);
    let options = kage::scene::model::ModelOptions { limits: limits(), ..Default::default() };
    let Ok(model) = kage::scene::load::model_with(path, files, &options.csg, &options.limits) else { return };
    if let Ok(mut scene) = kage::scene::model::scene_for_loaded_model(&model, path, SIZE.0, SIZE.1, &options) {
        // The loaders are under test, not the light rig's maps: one small
        // map a light keeps each case quick.
        for light in &mut scene.lights {
            (light.shadow.resolution, light.shadow.by_need, light.shadow.samples) = (64, false, 1);
        }
        render_small(scene);
    }
}

/// Draws `solid` seen by `camera` at `size` with the scanline walk and casts
/// a ray through every pixel centre with the CSG ray caster; with `check`,
/// both must meet the same surface (the same primitive, or another at the
/// same distance: flush faces) wherever the pixel centre is not on an edge.
///
/// # Panics
///
/// With `check`, at the first pixel where they differ.
pub fn walk_beside_rays(solid: &kage::csg::CsgSolid, camera: &kage::camera::Camera, (w, h): (u32, u32), check: bool) {
    let scanned = kage::visibility::solids::scan_solid(solid, camera, w, h);
    let rays = camera.pixel_rays(Vec2::new(w as f32, h as f32));
    let caster = kage::csg::CsgCaster::new(solid);
    for y in 0..h {
        for x in 0..w {
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let cast_at = |offset: Vec2| {
                let ray = rays.ray(centre + offset);
                let near = camera.distance_at_depth(&ray, 1.0);
                caster.first_hit(&ray, near, f32::INFINITY)
            };
            let (got, cast) = (scanned[(y * w + x) as usize], cast_at(Vec2::ZERO));
            if !check {
                continue;
            }
            let agree = match (got, cast) {
                (None, None) => true,
                (Some(a), Some(b)) => same_distance(a.t, b.t),
                _ => false,
            };
            // Where two primitives' surfaces meet within rounding, what is
            // left between them is a sliver either way may keep or drop.
            let ray = rays.ray(centre);
            let tie = [got, cast].into_iter().flatten().any(|c| near_a_tie(solid, &ray, c.t));
            if !agree && !tie && !on_an_edge(|o| cast_at(o).map(|c| c.primitive)) {
                panic!(
                    "pixel ({x}, {y}): the scanline walk shows {got:?}, a ray meets {cast:?}\n{solid:?}\n{camera:?}"
                );
            }
        }
    }
}

/// Whether surfaces of two primitives of `solid` cross `ray` within 1e-4
/// (relative) of `t`: a boolean there decides a sliver thinner than its
/// rounding, which the scanline walk (eight rays at a time) and the ray
/// caster (one) may round either way.
fn near_a_tie(solid: &kage::csg::CsgSolid, ray: &kage::camera::Ray, t: f32) -> bool {
    let close = |x: f32| (x - t).abs() <= 1e-4 * t.abs().max(1.0);
    let meeting =
        solid.primitives.iter().enumerate().filter(|(i, p)| {
            kage::csg::primitive_span(p, *i, ray).is_some_and(|s| close(s.enter.t) || close(s.exit.t))
        });
    meeting.count() >= 2
}

/// Rasterizes the opaque surfaces of `scene` (every material made opaque and
/// two-sided, as a ray sees them) and casts a ray through every pixel centre
/// at the whole scene: both must meet the same item (or another at the same
/// distance) wherever the pixel centre is not on an edge.
///
/// # Panics
///
/// At the first pixel where they differ.
pub fn items_beside_rays(scene: &Scene) {
    let mut scene = scene.clone();
    for m in &mut scene.materials {
        (m.two_sided, m.opacity) = (true, 1.0);
    }
    let (w, h) = (scene.width, scene.height);
    let mut vb = kage::visibility::VisibilityBuffer::new(w, h);
    kage::visibility::rasterize(&scene, &mut vb);
    let traced = kage::raytrace::TraceScene::new(&scene);
    let camera = &scene.camera;
    let rays = camera.pixel_rays(Vec2::new(w as f32, h as f32));
    // A ray starts at the near plane, where the raster clips: what it meets
    // first beyond it (its distance counted from the eye's plane).
    let cast_at = |centre: Vec2| {
        let ray = rays.ray(centre);
        let near = camera.distance_at_depth(&ray, 1.0);
        let from = kage::camera::Ray { origin: ray.origin + ray.dir * near, dir: ray.dir };
        traced.intersect(&from, f32::INFINITY).map(|hit| (hit.item, hit.t + near))
    };
    for y in 0..h {
        for x in 0..w {
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let ray = rays.ray(centre);
            let cast = cast_at(centre);
            let item = vb.item(x, y);
            let got = (!item.is_none()).then(|| camera.distance_at_depth(&ray, vb.depth(x, y)));
            let agree = match (got, cast) {
                (None, None) => true,
                (Some(t), Some((hit, at))) => hit == item || same_distance(t, at),
                _ => false,
            };
            let item_at = |o: Vec2| cast_at(centre + o).map(|(hit, _)| hit);
            if !agree && !on_an_edge(item_at) {
                panic!("pixel ({x}, {y}): the item buffer shows {item:?} at {got:?}, a ray meets {cast:?}");
            }
        }
    }
}
