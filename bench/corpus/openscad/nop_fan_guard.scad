// NopSCADlib tests/fan_guard.scad as it is: the library's printed fan_guard parts.
include <NopSCADlib/tests/fan_guard.scad>
