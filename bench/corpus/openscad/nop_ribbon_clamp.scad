// NopSCADlib tests/ribbon_clamp.scad as it is: the library's printed ribbon_clamp parts.
include <NopSCADlib/tests/ribbon_clamp.scad>
