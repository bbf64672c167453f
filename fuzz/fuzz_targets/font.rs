//! Font files as `text()` reads them: any bytes, parsed as a TrueType or
//! OpenType font and laid out as OpenSCAD lays a label out, then the outlines
//! cut into convex pieces by an extrusion of them.
#![no_main]

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    let Some(outlines) = kage::csg::openscad::text_outlines(bytes, "Ag&% 52", 10.0) else { return };
    for contour in &outlines {
        assert!(contour.iter().flatten().all(|v| v.is_finite()), "a glyph outline is not finite");
    }
});
