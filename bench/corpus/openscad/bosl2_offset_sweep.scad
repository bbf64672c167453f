// A box rounded top and bottom by offset_sweep: BOSL2 rounding.
include <BOSL2/std.scad>
include <BOSL2/rounding.scad>
offset_sweep(rect([40, 20]), height = 10, bottom = os_circle(r = 2), top = os_circle(r = 2));
