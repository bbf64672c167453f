// Round-Anything roundAnythingExamples.scad, polyRoundExtrudeExample().
use <Round-Anything/roundAnythingExamples.scad>
polyRoundExtrudeExample();
