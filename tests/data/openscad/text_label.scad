// A label: text on a plate, raised and engraved (Liberation Sans, OpenSCAD's default font).
difference() {
  cube([70, 22, 3]);
  translate([4, 13, 2]) linear_extrude(height = 2) text("Kage 52", size = 7);
}
translate([4, 3, 3]) linear_extrude(height = 1.5) text("gQ&%", size = 6, spacing = 1.1);
translate([66, 3, 3]) linear_extrude(height = 1) text("Ab", size = 5, halign = "right");
