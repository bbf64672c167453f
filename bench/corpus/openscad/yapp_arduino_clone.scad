// YAPP_Box examples/YAPP_ArduinoClone_v30.scad: a project box for an Arduino Uno, with the
// board's STL model in it. The model's path is named again here from this folder (the
// example's `./STL/MODELS/...` is relative to the repository's root; build.sh puts the
// projects in .lib/); the last assignment wins.
include <YAPP_Box/examples/YAPP_ArduinoClone_v30.scad>
myPcb = ".lib/YAPP_Box/STL/MODELS/Arduino_Uno_model.stl";
