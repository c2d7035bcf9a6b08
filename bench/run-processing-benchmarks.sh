#!/usr/bin/env bash
# The processing tools against CloudCompare 2.11 (and Open3D for normals) on
# the same terrain, in alternating runs. Usage:
#   bench/run-processing-benchmarks.sh [BUILD_DIR]
# Data: a 1 M-point terrain over 100 x 100 m (scandiff-make-scan --terrain),
# written to ${BENCH_DATA:-/tmp/scandiff-bench}. Prints one line per run: tool,
# operation, wall seconds, peak resident memory (KB). Nothing is written by
# either tool (CloudCompare with -AUTO_SAVE OFF, scandiff without -o), so both
# times are reading + computing. CloudCompare gets -GLOBAL_SHIFT AUTO: without
# it, it keeps these UTM coordinates in float (0.5 m steps) and fits garbage.
set -euo pipefail
build=${1:-build}
data=${BENCH_DATA:-/tmp/scandiff-bench}
runs=${RUNS:-5}
mkdir -p "$data"
cli="$build/app/cli/scandiff-cli"
terrain="$data/terrain_1M.ply"
[ -f "$terrain" ] || "$build/bench/scandiff-make-scan" --terrain 1000000 100 "$terrain" 1

timed() { # label command...
  local label=$1; shift
  /usr/bin/time -f "$label %e s %M KB" "$@" > /dev/null 2> >(tail -n 1 >&2)
}
cloudcompare=(env QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -NO_TIMESTAMP -AUTO_SAVE OFF -O -GLOBAL_SHIFT AUTO "$terrain")
open3d_normals='import sys, open3d as o3d
pcd = o3d.io.read_point_cloud(sys.argv[1])
pcd.estimate_normals(o3d.geometry.KDTreeSearchParamRadius(0.3))
pcd.orient_normals_to_align_with_direction([0, 0, 1])'

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
cat "$terrain" > /dev/null
for i in $(seq "$runs"); do
  timed "scandiff normals r=0.3 +z" "$cli" normals "$terrain" --radius 0.3 --orient +z
  timed "CloudCompare -OCTREE_NORMALS 0.3 -ORIENT PLUS_Z" "${cloudcompare[@]}" -OCTREE_NORMALS 0.3 -ORIENT PLUS_Z
  if /usr/bin/python3 -c 'import open3d' 2> /dev/null; then
    timed "Open3D estimate_normals r=0.3" /usr/bin/python3 -c "$open3d_normals" "$terrain"
  fi
  timed "scandiff subsample --spatial 0.05" "$cli" subsample "$terrain" --spatial 0.05
  timed "CloudCompare -SS SPATIAL 0.05" "${cloudcompare[@]}" -SS SPATIAL 0.05
  timed "scandiff subsample --octree 8" "$cli" subsample "$terrain" --octree 8
  timed "CloudCompare -SS OCTREE 8" "${cloudcompare[@]}" -SS OCTREE 8
done
