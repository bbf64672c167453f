// An involute gear with a hub and bore: MCAD gear.
use <MCAD/involute_gears.scad>
gear(number_of_teeth = 17, circular_pitch = 500, bore_diameter = 5, hub_diameter = 15, rim_width = 5);
