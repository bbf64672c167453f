// An OFF mesh with non-convex polygon faces (an L-shaped step), cut by a
// cylinder, and a mirrored copy unioned with a sphere.
difference() { import("parts/step.off"); translate([8, 4, -1]) cylinder(r = 2, h = 8, $fn = 24); }
translate([-2, 0, 0]) mirror([1, 0, 0]) union() { import("parts/step.off"); translate([2, 4, 10]) sphere(r = 3, $fn = 24); }
