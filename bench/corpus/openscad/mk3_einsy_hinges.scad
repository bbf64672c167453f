// Original Prusa i3 MK3, Printed-Parts/SCAD/Einsy-hinges.scad as it is.
include <Original-Prusa-i3/Printed-Parts/SCAD/Einsy-hinges.scad>
