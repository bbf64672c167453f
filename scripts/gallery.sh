#!/usr/bin/env bash
# Renders the README's gallery: models dropped in as they are — an STL, a
# glTF, an OBJ and an OpenSCAD .csg from the shared corpus — each with plain
# `kage render FILE` (no options but the size), into docs/gallery/.
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
models=(
  "csg/ex006_hull_dice.stl:stl.png"
  "gltf/CesiumMilkTruck/CesiumMilkTruck.glb:gltf.png"
  "meshes/utah-teapot/teapot.obj:obj.png"
  "csg/ex_csg_modules.csg:csg.png"
)
for entry in "${models[@]}"; do
  model=${entry%%:*} name=${entry##*:}
  if [ ! -f "$assets/$model" ]; then
    echo "skipped $model: not in $assets" >&2
    continue
  fi
  "$kage" render "$assets/$model" --width 480 --height 270 -o "$out/$name" 2>/dev/null
  echo "$out/$name  <-  kage render $model"
done
