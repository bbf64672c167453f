// A vase scaled differently in x and y: its side quads are not planar.
linear_extrude(height = 15, scale = [1.5, 0.6]) circle(r = 5, $fn = 32);
