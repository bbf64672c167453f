// A knob: a revolved profile with a groove, knurl pins and a partial ring.
difference() {
  rotate_extrude($fn = 64)
    polygon([[0, 0], [15, 0], [15, 4], [13, 5], [13, 7], [15, 8], [15, 12], [0, 12]]);
  translate([0, 0, -1]) cylinder(r = 3, h = 20, $fn = 32);
}
for (a = [0:30:330]) rotate([0, 0, a]) translate([15, 0, 0]) cylinder(r = 1, h = 12, $fn = 12);
translate([0, 0, 14]) rotate_extrude(angle = 240, $fn = 48) translate([8, 0]) circle(r = 2, $fn = 16);
