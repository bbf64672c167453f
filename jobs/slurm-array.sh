#!/usr/bin/env bash
# Slurm array job: one array task per frame of a turntable, or per share of a
# catalogue. The task id picks the frame (--frame) or the share (--shard).
#
#   sbatch --array=0-119 jobs/slurm-array.sh turntable model.glb out 120
#       frame i of a 120-frame turntable → out/spin.NNNN.png
#   sbatch --array=0-15 jobs/slurm-array.sh batch parts/ thumbnails
#       share i of 16 of `kage batch parts/` → thumbnails/...
# Options after the arguments go to every render: ... 120 --width 1920 --height 1080
#
#SBATCH --job-name=kage
#SBATCH --cpus-per-task=4
#SBATCH --output=kage-%A_%a.log
set -euo pipefail
kage=${KAGE:-kage}
task=${SLURM_ARRAY_TASK_ID:?run under sbatch --array, or set SLURM_ARRAY_TASK_ID}
threads=${SLURM_CPUS_PER_TASK:-0}
mode=${1:?turntable or batch}
input=${2:?the model, scene or folder}
out=${3:?the output folder}
shift 3
case "$mode" in
  turntable)
    frames=${1:?the number of frames}
    shift
    mkdir -p "$out"
    exec "$kage" render "$input" --turntable "$frames" --frame "$task" --threads "$threads" "$@" \
      -o "$out/spin.####.png"
    ;;
  batch)
    count=${SLURM_ARRAY_TASK_COUNT:?the number of array tasks}
    exec "$kage" batch "$input" -o "$out" --shard "$task/$count" -- --threads "$threads" "$@"
    ;;
  *)
    echo "slurm-array.sh: the first argument is turntable or batch, not '$mode'" >&2
    exit 2
    ;;
esac
