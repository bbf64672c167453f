// NopSCADlib tests/pocket_handle.scad as it is: the library's printed pocket_handle parts.
include <NopSCADlib/tests/pocket_handle.scad>
