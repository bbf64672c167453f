// Round-Anything roundAnythingExamples.scad, beamChainExample().
use <Round-Anything/roundAnythingExamples.scad>
beamChainExample();
