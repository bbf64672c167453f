// Round-Anything roundAnythingExamples.scad, parametricPolyRoundExample().
use <Round-Anything/roundAnythingExamples.scad>
parametricPolyRoundExample();
