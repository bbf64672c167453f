// Original Prusa i3 MK3, Printed-Parts/SCAD/PSU-cover-MK3.scad as it is.
include <Original-Prusa-i3/Printed-Parts/SCAD/PSU-cover-MK3.scad>
