// A PNG image as a heightmap (its pixels' luma, 0 to 100): a ring, a red and
// a blue square on a shaded ground, flattened to a tenth; centred, and
// inverted beside it (OpenSCAD 2021.01 inverts to below 0).
scale([1, 1, 0.1]) surface(file = "parts/relief.png", center = true);
translate([0, 30, 0]) scale([1, 1, 0.1]) surface(file = "parts/relief.png", invert = true);
