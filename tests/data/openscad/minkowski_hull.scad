// A rounded box (minkowski of convex parts) and hulls of cut and extruded parts.
minkowski() { cube([20, 12, 4]); sphere(r = 2, $fn = 16); }
translate([30, 0, 0]) hull() {
  difference() { cube(10); translate([5, 5, 5]) cube(10); }
  translate([0, 0, 12]) linear_extrude(height = 1) circle(r = 2, $fn = 12);
}
translate([0, 25, 0]) minkowski() {
  linear_extrude(height = 2) polygon([[0, 0], [15, 0], [15, 3], [3, 3], [3, 12], [0, 12]]);
  cylinder(r = 1, h = 1, $fn = 12);
}
