//! OpenSCAD `.csg` text: read (syntax, then the solid), then drawn by the
//! scanline walk and cast by the ray caster at a tiny size, then rendered.
#![no_main]
use std::path::Path;
use std::sync::Arc;

use kage::csg::openscad::{load_csg, CsgOptions, Geometry};

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else { return };
    let limits = kage_fuzz::limits();
    for geometry in [Geometry::Exact, Geometry::Faceted] {
        let options = CsgOptions { geometry, skip_unsupported: true };
        let Ok(loaded) = load_csg(Path::new("m.csg"), Arc::from(text), &options, &limits) else { continue };
        if let Some(bounds) = loaded.solid.bounds() {
            let camera = kage::csg::openscad::default_view(bounds);
            kage_fuzz::walk_beside_rays(&loaded.solid, &camera, kage_fuzz::SIZE, false);
        }
    }
    kage_fuzz::model("m.csg", bytes);
});
