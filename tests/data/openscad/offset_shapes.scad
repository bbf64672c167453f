// offset: rounded (r), sharp (delta) and chamfered corners, and an inward offset.
linear_extrude(height = 3) offset(r = 3, $fn = 32) square([20, 10]);
translate([0, 25, 0]) linear_extrude(height = 3) offset(delta = 2) polygon([[0, 0], [20, 0], [10, 12]]);
translate([30, 25, 0]) linear_extrude(height = 3) offset(delta = 2, chamfer = true) square([10, 10]);
translate([30, 0, 0]) linear_extrude(height = 3) offset(r = -2, $fn = 24) difference() { square(16); translate([8, 8]) circle(r = 4, $fn = 24); }
