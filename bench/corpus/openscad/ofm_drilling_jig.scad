// OpenFlexure Microscope openscad/actuator_drilling_jig.scad as it is.
include <openflexure_microscope/openscad/actuator_drilling_jig.scad>
