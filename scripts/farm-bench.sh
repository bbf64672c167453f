#!/usr/bin/env bash
# Rendering past one machine, measured on this one: a turntable of the showroom
# scene and a tiled poster, each rendered three ways —
#   one process with every core;
#   two OpenJD workers (`openjd run` of jobs/openjd-turntable.yaml, each given
#     half the tasks, one thread each), render step then merge step;
#   N processes of one thread each (N = cores): `--shard I/N` for the frames,
#     one process per tile (N at a time) and `kage merge` for the poster —
# and the cost of one unit of work beyond its pixels (start-up, scene load,
# BVH and shadow maps). Prints Markdown tables.
#
#   cargo build --release && scripts/farm-bench.sh [FRAMES [TILES]]
#
# Defaults: 120 frames of 1920x1080, 16 tiles of 7680x4320; FRAMES = 0 measures
# the poster alone. Needs openjd (.ci/venv/bin/openjd, which .ci/run installs,
# or on the PATH) for its rows, and GNU time (/usr/bin/time, Debian's `time`)
# for the poster's core-seconds and peak memory.
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-120}
tiles=${2:-16}
kage=${KAGE:-$PWD/target/release/kage}
openjd=${OPENJD:-$PWD/.ci/venv/bin/openjd}
command -v "$openjd" >/dev/null 2>&1 || openjd=$(command -v openjd || true)
scene=$PWD/examples/scenes/showroom.toml
template=$PWD/jobs/openjd-turntable.yaml
cores=$(nproc)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

now() { date +%s.%N; }
since() { echo "$(now) - $1" | bc -l; }
fmt() { printf '%.1f' "$1"; }

# Tasks of a step split between two workers: the JSON lists of every other one.
tasks() { # first count step tile-count
  local first=$1 count=$2 step=$3 tiles_per=$4 out="[" sep=""
  for ((k = first; k < count; k += step)); do
    if [ "$tiles_per" = 0 ]; then
      out+="$sep{\"Frame\": $k}"
    else
      out+="$sep{\"Frame\": $((k / tiles_per)), \"Tile\": $((k % tiles_per))}"
    fi
    sep=", "
  done
  echo "$out]"
}

openjd_two_workers() { # out frames tiles width height
  local out=$1 n=$2 t=$3 w=$4 h=$5
  local params=(-p "Input=$scene" -p "OutputDir=$out" -p "Frames=$n" -p "FrameRange=0-$((n - 1))"
    -p "Tiles=$t" -p "TileRange=0-$((t - 1))" -p "Width=$w" -p "Height=$h" -p Threads=1 -p "Kage=$kage")
  for step in Render Merge; do
    local units=$((n * t)) per=$t
    [ "$step" = Merge ] && units=$n per=0
    for worker in 0 1; do
      "$openjd" run "$template" --step "$step" --no-run-dependencies "${params[@]}" \
        --tasks "$(tasks "$worker" "$units" 2 "$per")" >"$out/openjd-$step-$worker.log" 2>&1 &
    done
    wait
  done
}

echo "Machine: $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)), $(free -g | awk '/Mem/ {print $2}') GiB"
echo

# --- Turntable ------------------------------------------------------------
turntable() {
w=1920 h=1080
mkdir -p "$work/a" "$work/b" "$work/c"
start=$(now)
"$kage" render "$scene" --turntable "$frames" --width $w --height $h -o "$work/a/spin.####.png" 2>/dev/null
one=$(since "$start")
two=""
if [ -n "$openjd" ]; then
  start=$(now)
  openjd_two_workers "$work/b" "$frames" 1 $w $h
  two=$(since "$start")
fi
start=$(now)
for ((i = 0; i < cores; i++)); do
  "$kage" render "$scene" --turntable "$frames" --shard "$i/$cores" --threads 1 --width $w --height $h \
    -o "$work/c/spin.####.png" 2>/dev/null &
done
wait
shards=$(since "$start")
cmp -s "$work/a/spin.0007.png" "$work/c/spin.0007.png" || echo "warning: --shard frame 7 differs from the one-process run"
[ -z "$two" ] || cmp -s "$work/a/spin.0007.png" "$work/b/frame.0007.png" || echo "warning: OpenJD frame 7 differs"

# One unit of work on its own: a frame in a process of its own, and a process
# that loads the scene and renders next to nothing.
start=$(now)
"$kage" render "$scene" --turntable "$frames" --frame 7 --width $w --height $h -o "$work/unit.png" 2>/dev/null
unit=$(since "$start")
start=$(now)
"$kage" render "$scene" --width 8 --height 8 -o "$work/tiny.png" 2>/dev/null
tiny=$(since "$start")
per_frame=$(echo "$one / $frames" | bc -l)

echo "#### A $frames-frame ${w}x$h turntable of the showroom"
echo
echo "| how | wall time | frames per minute | vs one process |"
echo "|---|---|---|---|"
row() { echo "| $1 | $(fmt "$2") s | $(fmt "$(echo "60 * $frames / $2" | bc -l)") | $(printf '%.2f' "$(echo "$one / $2" | bc -l)")x |"; }
row "one process, $cores threads" "$one"
[ -z "$two" ] || row "2 OpenJD workers (render + merge steps), 1 thread each" "$two"
row "$cores \`--shard\` processes, 1 thread each" "$shards"
echo
echo "| one unit of work | time |"
echo "|---|---|"
echo "| a frame inside the one-process run (mean) | $(printf '%.0f' "$(echo "1000 * $per_frame" | bc -l)") ms |"
echo "| \`--frame 7\` in a process of its own | $(printf '%.0f' "$(echo "1000 * $unit" | bc -l)") ms |"
echo "| start-up, scene load, BVH and maps (an 8x8 image) | $(printf '%.0f' "$(echo "1000 * $tiny" | bc -l)") ms |"
echo
}
[ "$frames" = 0 ] || turntable

# A command's wall, user and system seconds and peak resident kilobytes, into
# file $1 (empty without GNU time).
timed() {
  local out=$1
  shift
  if [ -x /usr/bin/time ]; then /usr/bin/time -f "%e %U %S %M" -o "$out" "$@"; else : >"$out" && "$@"; fi
}

# --- Poster ---------------------------------------------------------------
w=7680 h=4320
rm -rf "$work/a" "$work/b" "$work/c" && mkdir -p "$work/a" "$work/b" "$work/c"
start=$(now)
timed "$work/whole.time" "$kage" render "$scene" --width $w --height $h -o "$work/a/poster.exr" 2>/dev/null
one=$(since "$start")
two=""
if [ -n "$openjd" ]; then
  start=$(now)
  openjd_two_workers "$work/b" 1 "$tiles" $w $h
  two=$(since "$start")
fi
start=$(now)
export -f timed
seq 0 $((tiles - 1)) | xargs -P "$cores" -I{} bash -c "timed '$work/c/{}.time' '$kage' render '$scene' \
  --tile '{}/$tiles' --threads 1 --width $w --height $h -o '$work/c/tile.{}.exr' 2>/dev/null"
"$kage" merge "$work"/c/tile.*.exr -o "$work/c/poster.exr" 2>/dev/null
split=$(since "$start")
start=$(now)
"$kage" render "$scene" --tile "5/$tiles" --width $w --height $h -o "$work/tile.exr" 2>/dev/null
tile=$(since "$start")
"$kage" compare "$work/c/poster.exr" "$work/a/poster.exr" | grep -q "max error   0.000000" ||
  echo "warning: the merged poster differs from the whole"

echo "#### A $tiles-tile ${w}x$h poster of the showroom (.exr)"
echo
echo "| how | wall time | vs one process |"
echo "|---|---|---|"
prow() { echo "| $1 | $(fmt "$2") s | $(printf '%.2f' "$(echo "$one / $2" | bc -l)")x |"; }
prow "one process, $cores threads, the whole image" "$one"
[ -z "$two" ] || prow "2 OpenJD workers (tiles, then merge), 1 thread each" "$two"
prow "$tiles tile processes, $cores at a time, 1 thread each, then \`kage merge\`" "$split"
echo
echo "One tile in a process of its own: $(fmt "$tile") s."
if [ -s "$work/whole.time" ]; then
  # Core-seconds (user + system) and peak resident memory: the whole image in
  # one process against the tiles' processes.
  read -r _ wu ws wm <"$work/whole.time"
  cat "$work"/c/*.time | awk -v cs="$(echo "$wu + $ws" | bc -l)" -v wm="$wm" -v n="$tiles" '
    { core += $2 + $3; if ($4 > peak) peak = $4 }
    END {
      printf "\n| | core-seconds | peak memory |\n|---|---|---|\n"
      printf "| the whole image, one process | %.1f s | %.0f MB |\n", cs, wm / 1024
      printf "| %d tiles, a process each | %.1f s (%.2fx) | %.0f MB a tile at most (%.3f of the whole) |\n",
        n, core, core / cs, peak / 1024, peak / wm
    }'
fi
