// OpenFlexure Microscope openscad/main_body.scad as it is: the microscope's body with its
// flexure stage and the project's logos (DXF drawings) on its walls.
include <openflexure_microscope/openscad/main_body.scad>
