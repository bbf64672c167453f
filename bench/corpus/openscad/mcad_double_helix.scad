// Meshing double-helix gears: MCAD test_meshing_double_helix.
use <MCAD/involute_gears.scad>
test_meshing_double_helix();
