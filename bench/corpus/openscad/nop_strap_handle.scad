// NopSCADlib tests/strap_handle.scad as it is: the library's printed strap_handle parts.
include <NopSCADlib/tests/strap_handle.scad>
