// A volume knob: a revolved body with a grip and a skirt, a D-shaft bore,
// a pointer, and a label engraved in its top. kage's gallery part.
$fn = 96;

module body()
  rotate_extrude()
    polygon([[0, 0], [22, 0], [22, 2], [17, 4], [16, 18], [14, 20], [0, 20]]);

module grip()
  for (a = [0:15:345]) rotate([0, 0, a]) translate([16.4, 0, 4]) cylinder(r = 1.2, h = 14, $fn = 16);

difference() {
  union() { body(); grip(); }
  // The D-shaft bore.
  translate([0, 0, -1]) difference() {
    cylinder(r = 3.1, h = 15);
    translate([1.6, -5, 0]) cube([10, 10, 16]);
  }
  // The label, engraved 1 mm into the top.
  translate([0, -4, 19]) linear_extrude(height = 2) text("VOLUME", size = 3.2, halign = "center", valign = "center");
  // The pointer: a groove from the edge.
  translate([0, 7, 19]) linear_extrude(height = 2) offset(r = 0.4) square([0.8, 6], center = true);
}
// The scale round the skirt.
for (i = [0:10]) rotate([0, 0, -135 + 27 * i]) translate([0, 19.5, 2.8])
  linear_extrude(height = 0.8) text(str(i), size = 2.2, halign = "center", valign = "center");
