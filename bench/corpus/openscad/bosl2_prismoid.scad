// A rounded prismoid: BOSL2 prismoid.
include <BOSL2/std.scad>
prismoid([40, 40], [20, 20], h = 15, rounding = 3);
