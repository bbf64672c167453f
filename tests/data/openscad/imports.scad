// Imported meshes and heightmaps: an STL bracket cut by a sphere, and a
// surface() heightmap intersected with a cylinder.
difference() { import("parts/bracket.stl"); translate([20, 14, 12]) sphere(r = 8, $fn = 24); }
translate([30, 0, 0]) intersection() { scale([3, 3, 1]) surface(file = "parts/terrain.dat"); translate([6, 6, 0]) cylinder(r = 6, h = 20, $fn = 32); }
