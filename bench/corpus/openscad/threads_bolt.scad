// An M8 bolt: threads-scad MetricBolt (a threaded polyhedron unioned with a head).
use <threads-scad/threads.scad>
MetricBolt(8, 20);
