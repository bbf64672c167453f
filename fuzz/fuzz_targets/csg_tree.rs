//! Differential: a CSG tree of arbitrary convex primitives, drawn by the
//! scanline walk and cast pixel by pixel by the CSG ray caster: both must
//! find the same surface wherever the pixel centre is not on an edge.
#![no_main]
use kage_fuzz::spec::{CameraSpec, TreeSpec};

libfuzzer_sys::fuzz_target!(|input: (TreeSpec, CameraSpec)| {
    let (tree, camera) = input;
    let Some(solid) = tree.solid() else { return };
    kage_fuzz::walk_beside_rays(&solid, &camera.camera(), kage_fuzz::SIZE, true);
});
