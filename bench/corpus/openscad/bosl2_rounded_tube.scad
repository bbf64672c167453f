// A rounded rectangular tube: BOSL2 rect_tube.
include <BOSL2/std.scad>
rect_tube(size = [40, 30], wall = 2, h = 20, rounding = 5);
