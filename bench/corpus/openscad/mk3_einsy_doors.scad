// Original Prusa i3 MK3, Printed-Parts/SCAD/Einsy-doors.scad as it is.
include <Original-Prusa-i3/Printed-Parts/SCAD/Einsy-doors.scad>
