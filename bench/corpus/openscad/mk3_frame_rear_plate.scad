// Original Prusa i3 MK3, Frame/MK3-rear-plate.dxf: the frame's rear plate as drawn for
// cutting, extruded to the frame's 6 mm (build.sh puts the projects in .lib/).
linear_extrude(6) import(".lib/Original-Prusa-i3/Frame/MK3-rear-plate.dxf");
