#!/usr/bin/env bash
# Renders the README's gallery: models dropped in as they are — an STL, a
# glTF, an OBJ and an OpenSCAD .csg from the shared corpus, and two OpenSCAD
# parts from this repository (a revolved knob, a label plate made with
# BOSL2's text3d) — each with plain `kage render FILE` (no options but the size),
# then rows of the looks a designer asks for (ambient occlusion, a section,
# x-ray, feature lines, a technical drawing), each one option on the same
# command, into docs/gallery/.
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
# The looks: one option each.
looks=(
  "examples/openscad/knob.csg|ao.png|--ao"
  "examples/openscad/knob.csg|section.png|--section=-y=0"
  "$assets/gltf/CesiumMilkTruck/CesiumMilkTruck.glb|xray.png|--xray"
  "examples/openscad/knob.csg|lines.png|--lines"
  "$assets/csg/ex003_cross_cubes.stl|drawing.png|--drawing"
  "bench/corpus/openscad/mk3_x_end_idler.csg|drawing_part.png|--drawing"
)
for entry in "${looks[@]}"; do
  IFS='|' read -r model name option <<<"$entry"
  if [ ! -f "$model" ]; then
    echo "skipped $model: not there" >&2
    continue
  fi
  "$kage" render "$model" "$option" --width 480 --height 270 -o "$out/$name" 2>/dev/null
  echo "$out/$name  <-  kage render $model $option"
done
