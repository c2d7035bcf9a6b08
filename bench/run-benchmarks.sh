#!/usr/bin/env bash
# Times scandiff against CloudCompare 2.11 (Debian package `cloudcompare`) on the
# same files, in the same run. Usage: bench/run-benchmarks.sh [BUILD_DIR] [POINTS]
# Writes data to ${BENCH_DATA:-/tmp/scandiff-bench} and prints one line per run:
# tool, operation, wall seconds, peak resident memory (KB).
set -euo pipefail
build=${1:-build}
points=${2:-10000000}
data=${BENCH_DATA:-/tmp/scandiff-bench}
mkdir -p "$data"
cli="$build/app/cli/scandiff-cli"
make_scan="$build/bench/scandiff-make-scan"
runs=${RUNS:-3}

for ext in ply las; do
  [ -f "$data/scan.$ext" ] || "$make_scan" "$points" "$data/scan.$ext"
done

timed() { # label command...
  local label=$1; shift
  /usr/bin/time -f "$label %e s %M KB" "$@" > /dev/null 2> >(tail -n 1 >&2)
}

echo "machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GiB", $2/1048576}' /proc/meminfo), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
for ext in ply las; do
  # Warm the page cache once so every run reads from memory, not disk.
  cat "$data/scan.$ext" > /dev/null
  for i in $(seq "$runs"); do
    timed "scandiff read.$ext" "$cli" info "$data/scan.$ext"
    if command -v CloudCompare > /dev/null; then
      QT_QPA_PLATFORM=offscreen timed "CloudCompare read.$ext" \
        CloudCompare -SILENT -NO_TIMESTAMP -AUTO_SAVE OFF -O "$data/scan.$ext" || true
    fi
  done
done
