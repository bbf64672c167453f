// A PCO-1881 bottle cap: BOSL2 pco1881_cap.
include <BOSL2/std.scad>
include <BOSL2/bottlecaps.scad>
pco1881_cap();
