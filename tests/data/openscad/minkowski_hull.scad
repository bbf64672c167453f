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
// The hull and the Minkowski sum of a star (a polyhedron that is not convex).
module star() polyhedron(points = [for (z = [0, 3]) for (i = [0:9]) let(r = i % 2 ? 2 : 5) [r * cos(36 * i), r * sin(36 * i), z]],
  faces = concat([[for (i = [9:-1:0]) i]], [[for (i = [0:9]) i + 10]], [for (i = [0:9]) [i, (i + 1) % 10, (i + 1) % 10 + 10, i + 10]]));
translate([0, 45, 0]) hull() star();
translate([20, 45, 0]) minkowski() { star(); sphere(r = 1, $fn = 8); }
