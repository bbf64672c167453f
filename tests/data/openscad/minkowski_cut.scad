// Minkowski sums of cut and intersected parts: a slot (two hulls crossed with a
// wedge) widened by a cylinder, a frame (a box less two cutters) rounded by a
// ball, and a sum of two such parts.
minkowski() {
  intersection() {
    union() {
      hull() { cube([20, 4, 1]); translate([0, 2, 0]) cube([20, 2, 4]); }
      translate([0, 0, 8]) hull() { cube([20, 4, 1]); translate([0, 2, 0]) cube([20, 2, 4]); }
    }
    hull() { translate([4, -1, -1]) cube([1, 6, 20]); translate([14, -1, -1]) cube([3, 6, 20]); }
  }
  cylinder(r = 1, h = 2, center = true, $fn = 8);
}
translate([30, 0, 0]) minkowski() {
  difference() {
    cube([16, 12, 6]);
    translate([2, 2, -1]) cube([5, 8, 8]);
    translate([9, 2, 2]) rotate([0, 0, 20]) cube([5, 6, 8]);
  }
  sphere(r = 1, $fn = 8);
}
translate([0, 25, 0]) minkowski() {
  difference() { cube([10, 10, 3]); translate([5, 5, -1]) cylinder(r = 3, h = 5, $fn = 12); }
  intersection() { sphere(r = 2, $fn = 10); cube([3, 3, 1], center = true); }
}
