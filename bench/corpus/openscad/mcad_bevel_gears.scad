// A meshing bevel gear pair: MCAD test_bevel_gear_pair.
use <MCAD/involute_gears.scad>
test_bevel_gear_pair();
