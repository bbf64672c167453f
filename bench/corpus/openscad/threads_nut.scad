// An M10 nut: threads-scad MetricNut (a threaded hole through a hexagon).
use <threads-scad/threads.scad>
MetricNut(10);
