// Letters for a necklace: MCAD bitmap/letter_necklace.
include <MCAD/bitmap/letter_necklace.scad>
