// An alphabet block: MCAD bitmap/alphabet_block.
include <MCAD/bitmap/alphabet_block.scad>
