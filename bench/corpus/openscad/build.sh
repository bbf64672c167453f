#!/usr/bin/env bash
# Rebuilds the OpenSCAD corpus from the public projects it is drawn from:
# each NAME.scad here names one part of one project (SOURCES.md: which, at
# which commit, under which licence). For each, OpenSCAD 2021.01 writes
#   NAME.csg        the flattened tree kage reads (kept in the repository),
#   files/*         the drawings and meshes a tree imports (kept: the tree
#                   names them by paths relative to itself),
#   stl/NAME.stl    the exact mesh of that tree, by OpenSCAD's own CGAL render (not kept:
#                   rebuilt here; models whose render fails or passes the
#                   time limit get none, and the benchmark says so).
#
# Usage: build.sh SOURCES [NAME...]
#   SOURCES  a folder of clones named OWNER+REPO/repo (as the workplace's
#            fetch tool leaves them) or OWNER+REPO (a plain `git clone`).
#   NAME     only these models (default: every NAME.scad here).
# Environment: STL_TIMEOUT (seconds, default 1800) per exact render (the slowest
# corpus model takes about 12 minutes).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
sources="$(cd "${1:?usage: build.sh SOURCES [NAME...]}" && pwd)"
shift
timeout_s="${STL_TIMEOUT:-1800}"

# The projects, pinned: folder name in OPENSCADPATH, OWNER+REPO, commit.
projects=(
  "Original-Prusa-i3 prusa3d+Original-Prusa-i3 529e5ad6892ce3b25015b7cca7f0481b8335a76c"
  "threads-scad rcolyer+threads-scad 4ae9aeb3b136f9858200f77a304b909a000ce3b4"
  "BOSL2 BelfrySCAD+BOSL2 df336a2c28f31ffc6554d331d8323f48cbe7a04b"
  "NopSCADlib nophead+NopSCADlib cae9cdd778cd33329cf3b817505d7b58353f5fb0"
  "MCAD openscad+MCAD 4b4caeb5dad3301139541d039f14eac654f90487"
  "Round-Anything Irev-Dev+Round-Anything 061fef7c429628808e847696bb345a9b0ec6e279"
  "LEGO.scad cfinke+LEGO.scad d717ca8e29dbb62f271bf351b35179060eaa744e"
  "openflexure_microscope rwb27+openflexure_microscope 0cedf45238bb1cf8185f4ad92d366eb36f44efc3"
  "YAPP_Box mrWheel+YAPP_Box f9400c419ef1dea7dc0b3607876989b4f3faa2b7"
)

# The projects sit in a folder beside the trees while OpenSCAD runs, so that
# the paths it writes for imported files are relative ones that can be moved.
lib="$here/.lib"
rm -rf "$lib"
mkdir -p "$lib"
trap 'rm -rf "$lib"' EXIT
for p in "${projects[@]}"; do
  read -r folder repo commit <<<"$p"
  git_dir="$sources/$repo/repo"
  [ -d "$git_dir" ] || git_dir="$sources/$repo"
  mkdir -p "$lib/$folder"
  # Source files and the drawings and meshes they import (snapshots may lack
  # large binary files).
  git -C "$git_dir" ls-tree -r "$commit" | grep -E '\.(scad|dxf|svg|stl|STL|dat)$' |
    while IFS=$'\t' read -r meta path; do
      if git -C "$git_dir" cat-file -e "${meta##* }" 2>/dev/null; then printf '%s\n' "$path"; fi
    done |
    xargs -d '\n' git -C "$git_dir" --literal-pathspecs archive "$commit" -- | tar -x -C "$lib/$folder"
done
# Prusa's parts include their neighbours by plain names.
export OPENSCADPATH="$lib"

mkdir -p "$here/stl"
cd "$here"
names=("$@")
[ ${#names[@]} -gt 0 ] || names=($(ls *.scad | sed 's/\.scad$//'))
for name in "${names[@]}"; do
  if ! openscad -o "$name.csg" "$name.scad" >"$lib/log" 2>&1; then
    echo "$name: openscad could not export the tree:"; tail -3 "$lib/log"; continue
  fi
  # Files imported from a project move to files/, and the tree names them there.
  { grep -o 'file = "\.lib/[^"]*"' "$name.csg" || true; } | sed 's/^file = "//; s/"$//' | sort -u |
    while read -r imported; do
      mkdir -p files
      cp "$imported" "files/$(basename "$imported")"
      # A licence beside an imported file travels with it.
      licence="$(dirname "$imported")/LICENSE.txt"
      [ ! -f "$licence" ] || cp "$licence" "files/$(basename "$(dirname "$imported")")-LICENSE.txt"
      sed -i "s|file = \"$imported\"|file = \"files/$(basename "$imported")\"|g" "$name.csg"
    done
  # The exact mesh of the tree itself: a library that draws more in
  # OpenSCAD's preview ($preview) baked that into the tree.
  if timeout "$timeout_s" openscad --export-format binstl -o "stl/$name.stl" "$name.csg" >"$lib/log" 2>&1; then
    echo "$name: $(wc -c <"$name.csg") bytes of tree, $(wc -c <"stl/$name.stl") bytes of mesh"
  else
    rm -f "stl/$name.stl"
    echo "$name: $(wc -c <"$name.csg") bytes of tree, no exact mesh ($(tail -1 "$lib/log"))"
  fi
done
