// YAPP_Box examples/YAPP_Demo_imagesPlane_v3.scad: a project box whose lid carries an SVG
// image. Its image list is named again here with the path from this folder (OpenSCAD
// finds an included file's imports beside the including file; build.sh puts the
// projects in .lib/); the last assignment wins, before the box is made.
include <YAPP_Box/examples/YAPP_Demo_imagesPlane_v3.scad>
imagesPlane = [[40, 40, 0, 1, yappLid, ".lib/YAPP_Box/examples/YAPP_Demo_imagesPlane.svg", 0.2]];
