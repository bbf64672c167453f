// A knuckle hinge leaf: BOSL2 knuckle_hinge on a plate.
include <BOSL2/std.scad>
include <BOSL2/hinges.scad>
cuboid([40, 4, 30]) position(TOP + BACK) knuckle_hinge(length = 35, segs = 5, offset = 3, arm_height = 1, arm_angle = 45);
