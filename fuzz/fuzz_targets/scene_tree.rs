//! Differential: a scene of arbitrary shapes, CSG solids, materials and
//! lights, rendered whole at a tiny size; its item buffer must show at every
//! pixel what a ray cast at the scene meets first, wherever the pixel centre
//! is not on an edge.
#![no_main]
use kage_fuzz::spec::SceneSpec;

libfuzzer_sys::fuzz_target!(|spec: SceneSpec| {
    let Some(scene) = spec.scene(kage_fuzz::SIZE) else { return };
    kage_fuzz::items_beside_rays(&scene);
    kage_fuzz::render_small(scene);
});
