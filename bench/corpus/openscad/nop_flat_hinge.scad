// NopSCADlib tests/flat_hinge.scad as it is: the library's printed flat_hinge parts.
include <NopSCADlib/tests/flat_hinge.scad>
