// A tapered star and a cone-tipped pin: linear_extrude with scale.
linear_extrude(height = 12, scale = 0.4, center = true)
  polygon([for (i = [0:9]) let(r = i % 2 ? 4 : 10) [r * cos(36 * i), r * sin(36 * i)]]);
translate([25, 0, 0]) linear_extrude(height = 8, scale = 0) circle(r = 4, $fn = 24);
