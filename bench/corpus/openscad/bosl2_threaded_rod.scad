// A threaded rod: BOSL2 threaded_rod.
include <BOSL2/std.scad>
include <BOSL2/threading.scad>
threaded_rod(d = 10, l = 20, pitch = 1.5);
