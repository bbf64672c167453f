#!/usr/bin/env bash
# Runs one fuzz target: fuzz/run.sh TARGET [SECONDS] [extra libFuzzer flags].
# 2 GiB memory limit, 10 s a case (a case is one input at 32 × 24), the
# format's dictionary when there is one; prints libFuzzer's final figures.
set -euo pipefail
cd "$(dirname "$0")"
target=$1
seconds=${2:-3600}
shift $(( $# < 2 ? $# : 2 ))
dict=()
case $target in
    scene_tree|csg_tree|texture|openscad_flat|font) ;;
    *) dict=("-dict=dict/$target.dict") ;;
esac
mkdir -p "corpus/$target" "artifacts/$target"
RAYON_NUM_THREADS=1 exec cargo +nightly fuzz run -O "$target" "corpus/$target" -- \
    -rss_limit_mb=2048 -timeout=10 -max_total_time="$seconds" -print_final_stats=1 \
    -artifact_prefix="artifacts/$target/" "${dict[@]}" "$@"
