// A gasket drawn in a DXF file (lines, arcs, circles, an ellipse, a closed
// polyline, a block inserted twice, text and a spline OpenSCAD ignores):
// one layer extruded, and again moved and scaled, and the old way
// of naming a file in the extrusions themselves.
linear_extrude(height = 3) import("parts/gasket.dxf", layer = "outline");
translate([0, 50, 0]) linear_extrude(height = 2) import("parts/gasket.dxf", layer = "outline", scale = 0.5, $fn = 12);
translate([0, -20, 0]) linear_extrude(height = 5, file = "parts/gasket.dxf", layer = "tab");
translate([0, 0, 10]) rotate_extrude(file = "parts/gasket.dxf", layer = "tab", origin = [60, 0], $fn = 40);
