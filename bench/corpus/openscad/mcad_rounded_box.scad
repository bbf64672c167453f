// A rounded box: MCAD roundedBox.
use <MCAD/boxes.scad>
roundedBox([30, 20, 10], 3, false);
