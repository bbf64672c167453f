// A spur gear with a shaft hole: BOSL2 spur_gear.
include <BOSL2/std.scad>
include <BOSL2/gears.scad>
spur_gear(circ_pitch = 5, teeth = 20, thickness = 8, shaft_diam = 5);
