// A twisted bar: linear_extrude with twist and slices.
linear_extrude(height = 20, twist = 120, slices = 24) square([8, 4], center = true);
translate([20, 0, 0]) linear_extrude(height = 10, twist = -45, slices = 6, scale = 0.5) circle(r = 4, $fn = 6);
