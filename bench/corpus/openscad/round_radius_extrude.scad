// Round-Anything roundAnythingExamples.scad, radiusExtrudeExample().
use <Round-Anything/roundAnythingExamples.scad>
radiusExtrudeExample();
