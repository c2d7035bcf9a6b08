#!/usr/bin/env bash
# scandiff-mpi c2c on 1, 2 and 4 ranks against scandiff-cli c2c on the same
# 10 M x 10 M pair, output written by both. Usage:
#   bench/run-scale-out-benchmarks.sh [BUILD_DIR] [POINTS]
# Prints wall seconds and the peak resident memory of every rank.
set -euo pipefail
build=${1:-build}
points=${2:-10000000}
data=${BENCH_DATA:-/tmp/scandiff-bench}
mkdir -p "$data"
reference="$data/reference_$points.ply"
compared="$data/compared_$points.ply"
[ -f "$reference" ] || "$build/bench/scandiff-make-scan" "$points" "$reference" 1
[ -f "$compared" ] || "$build/bench/scandiff-make-scan" "$points" "$compared" 2
cat "$reference" "$compared" > /dev/null
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
/usr/bin/time -f "scandiff-cli c2c: %e s, %M KB" "$build/app/cli/scandiff-cli" c2c \
  --reference "$reference" --compared "$compared" -o "$data/cli.ply" > /dev/null
for ranks in 1 2 4; do
  /usr/bin/time -f "mpirun -np $ranks: %e s" mpirun --allow-run-as-root --oversubscribe -np "$ranks" \
    /usr/bin/time -f "  one rank: %M KB" "$build/app/mpi/scandiff-mpi" c2c \
    --reference "$reference" --compared "$compared" --tile-size 50 --halo 0.5 -o "$data/mpi$ranks.ply" > /dev/null
  cmp "$data/cli.ply" "$data/mpi$ranks.ply" && echo "  output identical to scandiff-cli's"
done
