//! Per-stage timings that need no peer, one criterion group per stage of the
//! frame, on the built-in demo (960x540: a teapot, Spot and a sphere, two
//! shadowed lights), the reflections example scene and an OpenSCAD part.
//!
//! `cargo bench -p kage-bench` (criterion keeps each run's estimates in
//! `target/criterion/` and reports the change from the last one).

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use kage::image::LinearImage;
use kage::raytrace::{traced, TraceCache};
use kage::scene::{demo::demo_scene, file, model, Antialias, EdgeMode, Scene};
use kage::shading::{shade_lit, ComponentSet, SubpixelShading, Target};
use kage::shadows::{MapPool, ShadowTerm};
use kage::visibility::{rasterize, solids, VisibilityBuffer};
use kage::{RenderOptions, Renderer};

/// The demo, aliased (the edge pass has its own row).
fn demo() -> Scene {
    Scene { antialias: Antialias::None, ..demo_scene().expect("the demo loads") }
}

/// An example scene, aliased.
fn example(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes").join(name);
    Scene { antialias: Antialias::None, ..file::load_scene(&path).expect("the example loads") }
}

/// The demo's visibility buffer, for the stages that read one.
fn visibility_of(scene: &Scene) -> VisibilityBuffer {
    let mut vb = VisibilityBuffer::new(scene.width, scene.height);
    rasterize(scene, &mut vb);
    vb
}

fn frames(c: &mut Criterion) {
    let mut group = c.benchmark_group("frame");
    group.sample_size(20);
    for (name, scene) in [("demo", demo()), ("reflections", example("reflections.toml"))] {
        let mut renderer = Renderer::new(&RenderOptions::default()).expect("renderer");
        group.bench_function(name, |b| b.iter(|| black_box(renderer.render(&scene).expect("renders").stats)));
    }
    let edged = Scene { antialias: Antialias::Edge(EdgeMode::default()), ..demo() };
    let mut renderer = Renderer::new(&RenderOptions::default()).expect("renderer");
    group.bench_function("demo, edge pass", |b| b.iter(|| black_box(renderer.render(&edged).expect("renders").stats)));
    group.finish();
}

fn visibility(c: &mut Criterion) {
    let scene = demo();
    let mut vb = VisibilityBuffer::new(scene.width, scene.height);
    c.bench_function("visibility/demo", |b| b.iter(|| black_box(rasterize(&scene, &mut vb))));
}

fn shadow_maps(c: &mut Criterion) {
    let scene = demo();
    let bounds = scene.caster_bounds().expect("casters");
    let mut pool = MapPool::default();
    c.bench_function("shadow maps/demo, every light", |b| {
        b.iter(|| {
            for light in &scene.lights {
                let term = ShadowTerm::build_within(&scene, light, bounds, &mut pool);
                pool.recycle(black_box(term));
            }
        })
    });
}

fn shading(c: &mut Criterion) {
    let scene = demo();
    let vb = visibility_of(&scene);
    let (mut image, mut pool, mut subpixel) =
        (LinearImage::new(scene.width, scene.height), MapPool::default(), SubpixelShading::default());
    c.bench_function("shading/demo, maps kept", |b| {
        b.iter(|| {
            let mut targets = [Target { parts: ComponentSet::ALL, image: &mut image }];
            black_box(shade_lit(&scene, &vb, &mut targets, &mut pool, &mut subpixel))
        })
    });
}

fn traced_term(c: &mut Criterion) {
    let scene = example("reflections.toml");
    let vb = visibility_of(&scene);
    let (mut image, mut cache) = (LinearImage::new(scene.width, scene.height), TraceCache::default());
    let mut group = c.benchmark_group("traced");
    group.sample_size(20);
    group.bench_function("reflections, BVH kept", |b| {
        b.iter(|| black_box(traced::add_traced(&scene, &vb, &mut image, 4, &mut cache, traced::Refine::Never)))
    });
    group.finish();
}

fn csg_walk(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/csg/ex001_sphere_minus_cylinders.csg");
    // The part seen through its OpenSCAD camera sidecar.
    let sidecar = model::ModelOptions { file_camera: true, ..Default::default() };
    let scene = model::scene_for_model_with(&path, 1280, 720, &sidecar).expect("the part loads");
    let object = scene.objects.iter().find(|o| o.solid().is_some()).expect("a solid");
    let solid = object.solid().expect("a solid").transformed(&object.transform);
    let prepared = solids::PreparedSolid::new(&solid, solids::CsgMethod::Segments).expect("no expansion");
    let mut out = solids::SurfaceFrame::new();
    c.bench_function("csg walk/ex001 at 1280x720", |b| {
        b.iter(|| prepared.scan_into(&scene.camera, (scene.width, scene.height), black_box(&mut out)))
    });
}

criterion_group!(stages, frames, visibility, shadow_maps, shading, traced_term, csg_walk);
criterion_main!(stages);
