// NopSCADlib tests/cable_grommets.scad as it is: the library's printed cable_grommets parts.
include <NopSCADlib/tests/cable_grommets.scad>
