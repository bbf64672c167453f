// Original Prusa i3 MK3, Printed-Parts/SCAD/x-end-idler.scad as it is.
include <Original-Prusa-i3/Printed-Parts/SCAD/x-end-idler.scad>
