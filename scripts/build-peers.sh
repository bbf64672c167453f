#!/usr/bin/env bash
# Builds the llvmpipe and Embree peers of ../shared/peers into target/peers/
# (shared/ is read-only), for `kage-bench raster` and `kage-bench rays`. Debian 12;
# installs their packages when run as root.
set -euo pipefail
cd "$(dirname "$0")/.."
peers=${PEERS:-../shared/peers}
if [ "$(id -u)" = 0 ] && ! { [ -e /usr/include/EGL/egl.h ] && [ -e /usr/include/embree3/rtcore.h ]; }; then
  apt-get update
  apt-get install -y build-essential libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri libembree-dev
fi
mkdir -p target/peers
cc -O2 -Wall -Wno-unused-result -DUSE_EGL -I"$peers/common" \
  -o target/peers/llvmpipe_bench_egl "$peers/llvmpipe/llvmpipe_bench.c" -lEGL -lOpenGL -lm
cc -O2 -march=native -Wall -Wno-unused-result -I"$peers/common" \
  -o target/peers/embree_bench "$peers/embree/embree_bench.c" -lembree3 -lpthread -lm
echo "built target/peers/llvmpipe_bench_egl target/peers/embree_bench"
