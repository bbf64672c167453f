// Original Prusa i3 MK3, Printed-Parts/SCAD/x-carriage-back.scad as it is.
include <Original-Prusa-i3/Printed-Parts/SCAD/x-carriage-back.scad>
