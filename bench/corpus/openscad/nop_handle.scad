// NopSCADlib tests/handle.scad as it is: the library's printed handle parts.
include <NopSCADlib/tests/handle.scad>
