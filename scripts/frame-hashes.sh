#!/usr/bin/env bash
# Hashes everything kage renders — image, visibility buffer and every component
# image — for the demo, every example scene and every model of the shared corpus
# (OpenSCAD models exact and faceted), each as its file says, with the edge pass
# and with four jittered passes, plus a small ray-traced reference of each.
#
#   scripts/frame-hashes.sh > before.txt    # on one build
#   scripts/frame-hashes.sh > after.txt     # on another
#   diff before.txt after.txt               # nothing: the builds render alike
#
# The corpus is read from $KAGE_ASSETS (default ../shared/assets); models it
# lacks are left out.
set -euo pipefail
cd "$(dirname "$0")/.."
assets=${KAGE_ASSETS:-../shared/assets}
inputs=(demo examples/scenes/*.toml)
if [ -d "$assets" ]; then
  while IFS= read -r f; do inputs+=("$f"); done < <(
    find "$assets" -type f \( -name '*.csg' -o -name '*.obj' -o -name '*.stl' -o -name '*.gltf' -o -name '*.glb' \) \
      -not -path '*/scad-src/*' | LC_ALL=C sort)
fi
cargo build --release --quiet --example frame_hashes
exec "${CARGO_TARGET_DIR:-target}/release/examples/frame_hashes" --reference "${inputs[@]}"
