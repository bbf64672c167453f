// An L bracket with a hole: exported to parts/bracket.stl for imports.scad.
difference() {
  union() { cube([20, 4, 12]); cube([20, 14, 4]); }
  translate([10, 9, -1]) cylinder(r = 2.5, h = 6, $fn = 20);
  translate([10, -1, 8]) rotate([-90, 0, 0]) cylinder(r = 2, h = 6, $fn = 20);
}
