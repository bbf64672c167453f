#!/usr/bin/env bash
# Runs jobs/slurm-array.sh under a real, single-node Slurm on this machine:
# munged, slurmctld and slurmd started from a throwaway folder, a 6-frame
# turntable array and a 2-share batch array submitted with sbatch, each
# frame compared with `kage render --frame` byte for byte, the daemons
# stopped. Needs root and Debian's slurm-wlm (apt-get install slurm-wlm).
#
#   cargo build --release && sudo jobs/slurm-local-check.sh
set -euo pipefail
cd "$(dirname "$0")/.."
kage=${KAGE:-$PWD/target/release/kage}
dir=$(mktemp -d)
host=$(hostname -s)
cat >"$dir/slurm.conf" <<CONF
ClusterName=kagecheck
SlurmctldHost=$host
AuthType=auth/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=main Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
mkdir -p "$dir/state" "$dir/spool" /run/munge
export SLURM_CONF=$dir/slurm.conf KAGE=$kage
[ -f /etc/munge/munge.key ] || { dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null; chmod 400 /etc/munge/munge.key; }
chown -R munge:munge /etc/munge /run/munge 2>/dev/null || true
pgrep -x munged >/dev/null || su -s /bin/sh munge -c munged || munged --force
stop() { kill "$(cat "$dir/slurmd.pid" 2>/dev/null)" "$(cat "$dir/slurmctld.pid" 2>/dev/null)" 2>/dev/null || true; }
trap 'stop; rm -rf "$dir"' EXIT
slurmctld
slurmd
for _ in $(seq 30); do sinfo -h -o %t 2>/dev/null | grep -q idle && break; sleep 1; done
wait_for() { for _ in $(seq 120); do [ -z "$(squeue -h -j "$1")" ] && return; sleep 1; done; echo "job $1 did not finish" >&2; exit 1; }

job=$(sbatch --parsable --array=0-5 --cpus-per-task=1 --output="$dir/t-%a.log" jobs/slurm-array.sh \
  turntable "$PWD/assets/teapot.obj" "$dir/out" 6 --width 96 --height 54)
wait_for "$job"
for i in 0 1 2 3 4 5; do
  "$kage" render assets/teapot.obj --turntable 6 --frame "$i" --width 96 --height 54 -o "$dir/alone.png" 2>/dev/null
  cmp "$dir/alone.png" "$dir/out/spin.000$i.png"
done
mkdir -p "$dir/models"
cp assets/teapot.obj assets/heatsink.obj tests/data/csg/ex001_sphere_minus_cylinders.csg "$dir/models/"
job=$(sbatch --parsable --array=0-1 --cpus-per-task=1 --output="$dir/b-%a.log" jobs/slurm-array.sh \
  batch "$dir/models" "$dir/thumbs" --width 64 --height 48)
wait_for "$job"
[ "$(ls "$dir/thumbs" | wc -l)" = 3 ]
echo "slurm: 6 turntable frames equal kage render --frame; 3 models in 2 batch shares"
