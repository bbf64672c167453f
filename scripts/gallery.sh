#!/usr/bin/env bash
# Renders the README's gallery: models dropped in as they are — an STL, a
# glTF, an OBJ and an OpenSCAD .csg from the shared corpus, and two OpenSCAD
# parts from this repository (a revolved knob, a label plate made with
# BOSL2's text3d) — each with plain `kage render FILE` (no options but the size),
# into docs/gallery/.
#
#   scripts/gallery.sh            # after a change that alters how models come out
#
# The corpus is read from $KAGE_ASSETS (default ../shared/assets).
set -euo pipefail
cd "$(dirname "$0")/.."
assets=${KAGE_ASSETS:-../shared/assets}
out=docs/gallery
mkdir -p "$out"
cargo build --release -q -p kage-cli
kage=target/release/kage
# From the shared corpus, then OpenSCAD parts kept in this repository.
models=(
  "$assets/csg/ex006_hull_dice.stl:stl.png"
  "$assets/gltf/CesiumMilkTruck/CesiumMilkTruck.glb:gltf.png"
  "$assets/meshes/utah-teapot/teapot.obj:obj.png"
  "$assets/csg/ex_csg_modules.csg:csg.png"
  "examples/openscad/knob.csg:knob.png"
  "bench/corpus/openscad/bosl2_text.csg:label.png"
)
for entry in "${models[@]}"; do
  model=${entry%%:*} name=${entry##*:}
  if [ ! -f "$model" ]; then
    echo "skipped $model: not there" >&2
    continue
  fi
  "$kage" render "$model" --width 480 --height 270 -o "$out/$name" 2>/dev/null
  echo "$out/$name  <-  kage render $model"
done
