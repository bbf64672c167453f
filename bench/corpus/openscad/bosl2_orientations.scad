// BOSL2 examples/orientations.scad as it is.
include <BOSL2/examples/orientations.scad>
