// NopSCADlib tests/screw_knob.scad as it is: the library's printed screw_knob parts.
include <NopSCADlib/tests/screw_knob.scad>
