// Original Prusa i3 MK3, Printed-Parts/SCAD/z-axis-bottom.scad as it is.
include <Original-Prusa-i3/Printed-Parts/SCAD/z-axis-bottom.scad>
