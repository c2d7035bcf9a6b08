#!/usr/bin/env bash
# Registration against CloudCompare 2.11 (-ICP) and Open3D (point-to-plane ICP;
# FPFH + RANSAC for the global case) on the synthetic site of
# tests/support/SyntheticSite.h: 250 k points a scan, two independent samplings
# with 2 mm of noise, at UTM coordinates. Usage:
#   bench/run-registration-benchmarks.sh [BUILD_DIR]
# Data are written to ${BENCH_DATA:-/tmp/scandiff-bench}/registration. Prints,
# for every case and tool: wall seconds and peak resident memory (KB) of the
# whole process, then the error of its matrix against the truth (residual
# rotation, displacement at the site's centre and at the worst corner).
# CloudCompare gets an explicit -GLOBAL_SHIFT (its matrix is then converted
# back); Open3D gets the clouds shifted to the origin (--local): in UTM
# coordinates its ICP diverges (shown once, case 1).
set -euo pipefail
build=${1:-build}
here=$(cd "$(dirname "$0")" && pwd)
data=${BENCH_DATA:-/tmp/scandiff-bench}/registration
mkdir -p "$data"
cd "$data"
cli="$(cd "$OLDPWD" && realpath "$build/app/cli/scandiff-cli")"
make="$(cd "$OLDPWD" && realpath "$build/bench/scandiff-make-scan")"
error="$here/registration-error.py"
open3d="$here/open3d-icp.py"
shift_args=(-GLOBAL_SHIFT -512000 -5423000 -100)

[ -f ref.ply ] || "$make" --site 250000 ref.ply 1
[ -f fine25.ply ] || "$make" --site 250000 fine25.ply 2 --motion 25,3,-2,1.5,-2,0.4
[ -f changed30.ply ] || "$make" --site 250000 changed30.ply 2 --changed --motion 8,1,0.5,0.6,0.4,0.1
[ -f levelled60.ply ] || "$make" --site 250000 levelled60.ply 2 --motion 60,0,0,2,1,-0.3
[ -f global140.ply ] || "$make" --site 250000 global140.ply 2 --motion 140,25,-15,6,-4,1

timed() { # label command...
  local label=$1; shift
  /usr/bin/time -f "$label: %e s %M KB" "$@" > /dev/null 2> >(tail -n 1 >&2)
  sleep 0.2
}
cloudcompare() { # case extra-options...
  local case=$1; shift
  rm -f "${case}_REGISTRATION_MATRIX.txt"
  timed "CloudCompare -ICP $*" env QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -NO_TIMESTAMP -AUTO_SAVE OFF \
    -O "${shift_args[@]}" "$case.ply" -O "${shift_args[@]}" ref.ply -ICP "$@"
  "$error" "${case}_REGISTRATION_MATRIX.txt" "$case.ply.truth.txt" --shift -512000,-5423000,-100
}
ours() { # case options...
  local case=$1; shift
  timed "scandiff register $*" "$cli" register --reference ref.ply --moving "$case.ply" --matrix-out "$case.scandiff.txt" "$@"
  "$error" "$case.scandiff.txt" "$case.ply.truth.txt"
}
open3d() { # case options...
  local case=$1; shift
  timed "Open3D $*" "$open3d" "$case.ply" ref.ply "$case.open3d.txt" "$@"
  "$error" "$case.open3d.txt" "$case.ply.truth.txt"
}

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
echo "== fine25: a 25 degree start"
ours fine25
cloudcompare fine25
open3d fine25 --local
open3d fine25
echo "== changed30: 30 % of the moving scan changed (a building moved 0.3 m, a new block, a new wall), 8 degrees off"
ours changed30 --exclude-changes
ours changed30
cloudcompare changed30
cloudcompare changed30 -FARTHEST_REMOVAL
open3d changed30 --local
echo "== levelled60: a levelled scan turned 60 degrees about the vertical"
ours levelled60 --dof 4 --global
cloudcompare levelled60 -ROT Z
open3d levelled60 --local
echo "== global140: turned 140 degrees about a tilted axis"
ours global140 --global
cloudcompare global140
open3d global140 --local
open3d global140 --local --global
