// Revolutions of profiles on both sides of the axis, part turns both ways:
// which way each sweeps, from where. A stepped ring left of the axis turned
// -250 degrees, a tube right of it turned 100 degrees, and a whole-turn bead
// with a slanted inner face.
rotate_extrude(angle = -250, $fn = 60) polygon([[-2, 0], [-6, 0], [-6, 1], [-3, 1], [-3, 4], [-2, 4]]);
translate([0, 0, 6]) rotate_extrude(angle = 100, $fn = 60) translate([3, 0]) square([2, 1.5]);
translate([0, 0, 9]) rotate_extrude($fn = 60) polygon([[4, 0], [6, 0], [6, 1], [3, 1.5]]);
