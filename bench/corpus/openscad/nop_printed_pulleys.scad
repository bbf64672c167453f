// NopSCADlib tests/printed_pulleys.scad as it is: the library's printed printed_pulleys parts.
include <NopSCADlib/tests/printed_pulleys.scad>
