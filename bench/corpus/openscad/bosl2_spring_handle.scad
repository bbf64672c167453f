// BOSL2 examples/spring_handle.scad as it is.
include <BOSL2/examples/spring_handle.scad>
