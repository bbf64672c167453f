// OpenFlexure Microscope openscad/logo.scad, the call the file itself makes: the
// open-hardware gear logo (a DXF drawing, resized) beside mirrored text. (`use`, not
// `include`: OpenSCAD finds an included file's imports beside the including file.)
use <openflexure_microscope/openscad/logo.scad>
oshw_logo_and_text("4ah75s");
