// NopSCADlib tests/knob.scad as it is: the library's printed knob parts.
include <NopSCADlib/tests/knob.scad>
