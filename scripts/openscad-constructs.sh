#!/usr/bin/env bash
# Rebuilds the OpenSCAD construct models the tests compare kage with:
# for each tests/data/openscad/NAME.scad, OpenSCAD's flattened tree (NAME.csg,
# what kage reads) and its exact mesh (NAME.stl, binary, from OpenSCAD's own
# CGAL render). Needs OpenSCAD 2021.01 (Debian: `apt-get install openscad`)
# and, for text, the Liberation fonts (`fonts-liberation2`).
set -euo pipefail
cd "$(dirname "$0")/../tests/data/openscad"
# Meshes the models import, first.
for scad in parts/*.scad; do
  openscad --export-format binstl -o "${scad%.scad}.stl" "$scad" 2>/dev/null
done
for scad in *.scad; do
  name="${scad%.scad}"
  openscad -o "$name.csg" "$scad" 2>/dev/null
  openscad --export-format binstl -o "$name.stl" "$scad" 2>/dev/null
  echo "$name: $(stat -c %s "$name.stl") bytes of STL"
done
