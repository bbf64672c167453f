// LEGO.scad examples/3070.scad as it is.
include <LEGO.scad/examples/3070.scad>
