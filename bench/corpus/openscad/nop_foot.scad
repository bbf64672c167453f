// NopSCADlib tests/foot.scad as it is: the library's printed foot parts.
include <NopSCADlib/tests/foot.scad>
