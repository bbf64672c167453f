#!/usr/bin/env bash
# Renders the Khronos glTF sample models that test one feature each (and a
# few showcase models) with kage, and lays each render beside the model's own
# reference screenshot in one sheet: docs/images/gltf-conformance.jpg.
#
#   scripts/gltf-conformance.sh [MODELS] [OUT]
#
# MODELS: a folder laid out as KhronosGroup/glTF-Sample-Assets' `Models/`
# (default: fetched here once, only the models listed, with their licences,
# by a sparse git clone into target/khronos). OUT: where renders and logs go
# (default target/gltf-conformance). Needs git, python3 with Pillow, and a
# release build of kage (built when missing). Each model's LICENSE.md stays
# beside it; the sheet credits them in docs/gltf-conformance.md.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
out=${2:-$repo/target/gltf-conformance}
# name | variant folder and file | view (front for the test cards)
models=(
  "NegativeScaleTest|glTF-Binary/NegativeScaleTest.glb|front"
  "TextureSettingsTest|glTF-Binary/TextureSettingsTest.glb|front"
  "TextureTransformTest|glTF/TextureTransformTest.gltf|front"
  "TextureTransformMultiTest|glTF/TextureTransformMultiTest.gltf|front"
  "TextureCoordinateTest|glTF/TextureCoordinateTest.gltf|front"
  "OrientationTest|glTF/OrientationTest.gltf|iso"
  "VertexColorTest|glTF/VertexColorTest.gltf|front"
  "MultiUVTest|glTF/MultiUVTest.gltf|front"
  "AlphaBlendModeTest|glTF/AlphaBlendModeTest.gltf|front"
  "EmissiveStrengthTest|glTF/EmissiveStrengthTest.gltf|front"
  "UnlitTest|glTF/UnlitTest.gltf|front"
  "SimpleSparseAccessor|glTF/SimpleSparseAccessor.gltf|front"
  "MeshPrimitiveModes|glTF/MeshPrimitiveModes.gltf|front"
  "TransmissionTest|glTF/TransmissionTest.gltf|front"
  "SpecularTest|glTF/SpecularTest.gltf|front"
  "ClearCoatTest|glTF/ClearCoatTest.gltf|front"
  "DamagedHelmet|glTF/DamagedHelmet.gltf|front"
  "FlightHelmet|glTF/FlightHelmet.gltf|front"
  "WaterBottle|glTF/WaterBottle.gltf|front"
  "Lantern|glTF/Lantern.gltf|front"
  "Lantern|glTF-Quantized/Lantern.gltf|front"
  "BoomBox|glTF/BoomBox.gltf|front"
  "SheenChair|glTF/SheenChair.gltf|iso"
  "ToyCar|glTF/ToyCar.gltf|iso"
  "Fox|glTF/Fox.gltf|right"
  "Duck|glTF-Draco/Duck.gltf|iso"
)
dir=${1:-}
if [ -z "$dir" ]; then
  dir=$repo/target/khronos/Models
  if [ ! -d "$dir" ]; then
    git clone --quiet --depth 1 --filter=blob:none --sparse \
      https://github.com/KhronosGroup/glTF-Sample-Assets "$repo/target/khronos"
    names=$(printf '%s\n' "${models[@]}" | cut -d'|' -f1 | sort -u | sed 's|^|Models/|')
    (cd "$repo/target/khronos" && git sparse-checkout set $names)
  fi
fi
kage=$repo/target/release/kage
[ -x "$kage" ] || cargo build --release -p kage-cli --manifest-path "$repo/Cargo.toml"
mkdir -p "$out"
: > "$out/results.txt"
for m in "${models[@]}"; do
  IFS='|' read -r name file view <<< "$m"
  tag="$name-$(dirname "$file")"
  set +e
  "$kage" render "$dir/$name/$file" -o "$out/$tag.png" --width 320 --height 240 --view "$view" --no-ground \
    > "$out/$tag.log" 2>&1
  rc=$?
  set -e
  echo "$tag|$rc|$(grep -E '^(warning|Error| *×)' "$out/$tag.log" | tr '\n' ' ' | cut -c1-400)" >> "$out/results.txt"
  echo "$tag: exit $rc"
done
python3 - "$dir" "$out" "$repo/docs/images/gltf-conformance.jpg" <<'EOF'
import sys, glob, os
from PIL import Image, ImageDraw
models, out, sheet_path = sys.argv[1:4]
rows = [l.rstrip('\n').split('|', 2) for l in open(os.path.join(out, 'results.txt'))]
# Two models a row, each its render (left) beside its reference (right).
W, H, label, per_row = 320, 240, 16, 2
lines = (len(rows) + per_row - 1) // per_row
sheet = Image.new('RGB', (2 * W * per_row, lines * (H + label)), 'white')
draw = ImageDraw.Draw(sheet)
for i, (tag, rc, _) in enumerate(rows):
    name = tag.split('-glTF')[0]
    x, y = (i % per_row) * 2 * W, (i // per_row) * (H + label)
    draw.text((x + 4, y + 2), f'{tag}: kage' + ('' if rc == '0' else ' (refused)'), fill='black')
    draw.text((x + W + 4, y + 2), 'reference screenshot', fill='black')
    render = os.path.join(out, tag + '.png')
    if os.path.exists(render) and rc == '0':
        sheet.paste(Image.open(render).convert('RGB').resize((W, H)), (x, y + label))
    shots = sorted(glob.glob(os.path.join(models, name, 'screenshot', 'screenshot.*')))
    if shots:
        shot = Image.open(shots[0]).convert('RGB')
        shot.thumbnail((W, H))
        sheet.paste(shot, (x + W + (W - shot.width) // 2, y + label + (H - shot.height) // 2))
sheet.save(sheet_path, quality=80)
print('wrote', sheet_path)
EOF
