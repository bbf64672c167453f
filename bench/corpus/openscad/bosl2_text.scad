// Raised text on a rounded plate: BOSL2 cuboid and text3d.
include <BOSL2/std.scad>
cuboid([70, 20, 3], rounding = 2, edges = "Z") attach(TOP) text3d("BOSL2 kage", h = 1.5, size = 8, anchor = BOTTOM);
