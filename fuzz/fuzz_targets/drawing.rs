//! 2-D drawing files as `import()` reads them: any bytes, read as a DXF
//! file (group codes, entities, blocks, paths joined at grid points) and as
//! an SVG document, the outlines filled as OpenSCAD fills them.
#![no_main]

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    for dxf in [true, false] {
        let Some(outlines) = kage::csg::openscad::drawing_outlines(bytes, dxf) else { continue };
        for contour in &outlines {
            assert!(contour.iter().flatten().all(|v| v.is_finite()), "a drawing outline is not finite");
        }
    }
});
