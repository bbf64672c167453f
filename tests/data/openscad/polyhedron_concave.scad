// A star prism written as one polyhedron (concave faces, not convex),
// cut by a sphere, intersected with a cylinder, and a thread-like twisted solid.
function star(n, r1, r2, z) = [for (i = [0:2 * n - 1]) let(r = i % 2 ? r2 : r1, a = 180 * i / n) [r * cos(a), r * sin(a), z]];
module star_prism(n, r1, r2, h) {
  pts = concat(star(n, r1, r2, 0), star(n, r1, r2, h));
  m = 2 * n;
  polyhedron(points = pts,
    faces = concat([[for (i = [m - 1:-1:0]) i]], [[for (i = [0:m - 1]) i + m]],
                   [for (i = [0:m - 1]) [i, (i + 1) % m, (i + 1) % m + m, i + m]]));
}
difference() { star_prism(5, 10, 4, 8); translate([0, 0, 8]) sphere(r = 5, $fn = 24); }
translate([28, 0, 0]) intersection() { star_prism(6, 10, 5, 10); translate([0, 0, -1]) cylinder(r = 8, h = 12, $fn = 32); }
translate([0, 28, 0]) difference() { cube([16, 16, 6], center = true); star_prism(4, 7, 2, 4); }
