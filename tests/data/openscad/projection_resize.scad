// projection (outline and cut) of a solid, extruded; a resized sphere.
linear_extrude(height = 2) projection() rotate([30, 20, 0]) cube([12, 8, 6], center = true);
translate([25, 0, 0]) linear_extrude(height = 2) projection(cut = true) translate([0, 0, -1]) sphere(r = 8, $fn = 24);
translate([0, 25, 0]) resize([30, 10, 6]) sphere(r = 5, $fn = 24);
