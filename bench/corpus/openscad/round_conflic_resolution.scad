// Round-Anything roundAnythingExamples.scad, conflicResolutionExample().
use <Round-Anything/roundAnythingExamples.scad>
conflicResolutionExample();
