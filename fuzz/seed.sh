#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ with seed inputs: the repository's example
# scenes, test data and regression files, and the shared corpus of real
# models when KAGE_ASSETS (default ../shared/assets) is there. Small files
# only (≤ 256 KiB): libFuzzer's mutations work best on small inputs.
set -euo pipefail
cd "$(dirname "$0")"
repo=..
assets=${KAGE_ASSETS:-../../shared/assets}
findings=${KAGE_FINDINGS:-../../shared/findings/bad-input}
add() { # target, files...
    local target=$1; shift
    mkdir -p "corpus/$target"
    for f in "$@"; do
        [ -f "$f" ] && [ "$(stat -c %s "$f")" -le 262144 ] && cp "$f" "corpus/$target/$(basename "$f")" || true
    done
}
shopt -s nullglob globstar
add scene $repo/tests/data/fuzz/*.toml $repo/examples/scenes/*.toml $repo/tests/regressions/scene/* $findings/**/*.toml $assets/scenes/**/*.toml
add obj $repo/tests/data/**/*.obj $repo/tests/regressions/obj/**/*.obj $findings/**/*.obj $assets/meshes/**/*.obj
add stl $repo/tests/data/**/*.stl $assets/csg/ex00*.stl $assets/meshes/**/*.stl
add gltf $repo/tests/data/fuzz/*.gltf $repo/tests/data/fuzz/*.glb $repo/tests/data/assets/gltf/**/*.gltf $repo/tests/data/assets/gltf/**/*.glb $repo/tests/regressions/gltf/* $findings/**/*.gltf $findings/**/*.glb $assets/gltf/**/*.gltf $assets/gltf/**/*.glb
add csg $repo/tests/data/**/*.csg $repo/tests/regressions/csg/* $findings/**/*.csg $assets/csg/*.csg
add drawing $repo/tests/data/**/*.dxf $repo/tests/data/**/*.svg $repo/tests/regressions/csg/**/*.dxf
add texture $repo/examples/scenes/*.png $repo/tests/data/**/*.png $repo/tests/data/**/*.jpg $repo/tests/data/**/*.exr $assets/**/*.png
for t in scene obj stl gltf csg drawing texture csg_tree scene_tree; do
    mkdir -p "corpus/$t"
    echo "$t: $(ls "corpus/$t" | wc -l) seed files"
done
