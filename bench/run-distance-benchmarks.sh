#!/usr/bin/env bash
# Cloud/cloud and cloud/mesh distances, scandiff against CloudCompare 2.11 on the
# same files in the same run. Usage: bench/run-distance-benchmarks.sh [BUILD_DIR] [POINTS]
# Prints one line per run: tool, operation, wall seconds, peak resident memory (KB).
set -euo pipefail
build=${1:-build}
points=${2:-1000000}
data=${BENCH_DATA:-/tmp/scandiff-bench}
runs=${RUNS:-3}
mkdir -p "$data"
cli="$build/app/cli/scandiff-cli"
make_scan="$build/bench/scandiff-make-scan"

reference="$data/reference_$points.ply"
compared="$data/compared_$points.ply"
mesh="$data/terrain_mesh.ply"
[ -f "$reference" ] || "$make_scan" "$points" "$reference" 1
[ -f "$compared" ] || "$make_scan" "$points" "$compared" 2
[ -f "$mesh" ] || "$make_scan" --mesh 300 "$mesh"

timed() { # label command...
  local label=$1; shift
  /usr/bin/time -f "$label %e s %M KB" "$@" > /dev/null 2> >(tail -n 1 >&2)
}
cloudcompare=(env QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -NO_TIMESTAMP -AUTO_SAVE OFF)

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
cat "$reference" "$compared" "$mesh" > /dev/null
for i in $(seq "$runs"); do
  timed "scandiff c2c" "$cli" c2c --reference "$reference" --compared "$compared"
  timed "CloudCompare c2c" "${cloudcompare[@]}" -O "$compared" -O "$reference" -C2C_DIST
done
# Local models against plain NN: rounds of all four, so that each ratio is
# taken within a round (this machine's speed drifts by 10-20 % over minutes).
for i in $(seq "$runs"); do
  for model in none plane quadric delaunay; do
    timed "scandiff c2c --model $model" "$cli" c2c --reference "$reference" --compared "$compared" --model "$model"
  done
done
if "$cli" c2m --help > /dev/null 2>&1; then
  for i in $(seq "$runs"); do
    timed "scandiff c2m" "$cli" c2m --reference "$mesh" --compared "$compared"
    timed "CloudCompare c2m" "${cloudcompare[@]}" -O "$compared" -O "$mesh" -C2M_DIST
  done
fi
