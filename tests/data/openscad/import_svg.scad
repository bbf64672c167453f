// An SVG drawing imported, extruded and cut into a plate; and centred at a
// higher dpi beside it: OpenSCAD's units, view box, holes, curves, strokes.
difference() {
  translate([-5, -5, 0]) cube([70, 50, 3]);
  translate([0, 0, 1.5]) linear_extrude(height = 2) import("parts/badge.svg");
}
translate([0, -40, 0]) linear_extrude(height = 4) import("parts/badge.svg", center = true, dpi = 96);
