#!/usr/bin/env bash
# Builds the llvmpipe peer of ../shared/peers into target/peers/ (shared/ is
# read-only), for `kage bench`. Debian 12; installs its packages when run as root.
set -euo pipefail
cd "$(dirname "$0")/.."
peers=${PEERS:-../shared/peers}
if [ "$(id -u)" = 0 ] && ! [ -e /usr/include/EGL/egl.h ]; then
  apt-get update
  apt-get install -y build-essential libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
fi
mkdir -p target/peers
cc -O2 -Wall -Wno-unused-result -DUSE_EGL -I"$peers/common" \
  -o target/peers/llvmpipe_bench_egl "$peers/llvmpipe/llvmpipe_bench.c" -lEGL -lOpenGL -lm
echo "built target/peers/llvmpipe_bench_egl"
