// NopSCADlib tests/microview.scad as it is: a vitamin drawn from the maker's STL housings.
include <NopSCADlib/tests/microview.scad>
