// A block with a threaded hole: threads-scad ScrewHole around a cube.
use <threads-scad/threads.scad>
ScrewHole(8, 12, position = [10, 10, 0]) cube([20, 20, 12]);
