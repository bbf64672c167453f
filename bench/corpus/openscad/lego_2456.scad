// LEGO.scad examples/2456.scad as it is.
include <LEGO.scad/examples/2456.scad>
