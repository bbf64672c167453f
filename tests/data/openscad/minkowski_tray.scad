// A tray rounded by minkowski: the sum of a cut box (not convex) and a ball.
minkowski() {
  difference() { cube([40, 30, 10]); translate([3, 3, 3]) cube([34, 24, 10]); }
  sphere(r = 1.5, $fn = 12);
}
