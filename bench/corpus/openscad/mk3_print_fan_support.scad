// Original Prusa i3 MK3, Printed-Parts/SCAD/print-fan-support.scad as it is.
include <Original-Prusa-i3/Printed-Parts/SCAD/print-fan-support.scad>
