// 2-D booleans, hull and minkowski, mirrored and resized, then extruded.
linear_extrude(height = 5) difference() {
  union() { square([30, 20]); translate([30, 10]) circle(r = 10, $fn = 40); }
  intersection() { translate([10, 10]) circle(r = 8, $fn = 40); square([14, 30]); }
}
translate([0, 30, 0]) linear_extrude(height = 2) hull() { circle(r = 4, $fn = 24); translate([20, 5]) circle(r = 2, $fn = 16); }
translate([0, 50, 0]) linear_extrude(height = 2) minkowski() { square([15, 5]); circle(r = 2, $fn = 16); }
mirror([1, 0, 0]) linear_extrude(height = 4) polygon([[5, 0], [20, 0], [20, 4], [9, 4], [9, 15], [5, 15]]);
translate([-30, 30, 0]) linear_extrude(height = 3) resize([20, 0], auto = true) circle(r = 3, $fn = 30);
