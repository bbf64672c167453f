// An M6 socket-head screw with its thread: BOSL2 screw.
include <BOSL2/std.scad>
include <BOSL2/screws.scad>
screw("M6", length = 20, head = "socket", drive = "hex");
