// LEGO.scad examples/85984.scad as it is.
include <LEGO.scad/examples/85984.scad>
