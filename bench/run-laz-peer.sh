#!/usr/bin/env bash
# scandiff's LAZ against laz-perf, an independent LASzip-compatible decoder
# (github.com/hobuinc/laz-perf, Apache-2.0; npm package `laz-perf`, WebAssembly,
# run by Node.js). Debian 12 packages no LAZ tool, so this is the peer the
# machine can run. Two things, results in docs/benchmarks.md and docs/laz.md:
#  1. interoperability: random LAZ files scandiff writes (laz-peer-sweep.py:
#     point formats 6-8, any LAS 1.4 attributes, 0-5 Extra Bytes fields, up to
#     120,000 points, scanner channels fixed, point by point, in runs or from
#     halfway) are decoded by laz-perf, and its records must equal byte for
#     byte those of the LAS file scandiff writes from the same points;
#  2. speed: each given LAZ file read by scandiff (`info`, both cores, and
#     pinned to one core) and decoded by laz-perf (one thread), in turn.
# Usage: bench/run-laz-peer.sh BUILD_DIR [FILE.laz...]
# The package is fetched once with `npm pack` into ${LAZPERF_CACHE:-~/.cache/scandiff/laz-perf}.
# Needs node and npm (Debian: nodejs, npm), python3 and /usr/bin/time (Debian: time).
set -euo pipefail
build=${1:?usage: bench/run-laz-peer.sh BUILD_DIR [FILE.laz...]}
shift
cli="$build/app/cli/scandiff-cli"
here=$(cd "$(dirname "$0")" && pwd)
[ -x "$cli" ] || { echo "no $cli: give the build directory first" >&2; exit 1; }
for tool in node npm python3 /usr/bin/time; do
  command -v "$tool" > /dev/null || { echo "needs $tool (Debian packages nodejs, npm, python3, time)" >&2; exit 1; }
done
cache=${LAZPERF_CACHE:-$HOME/.cache/scandiff/laz-perf}
version=0.0.7
export LAZPERF_DIR="$cache/package"

if [ ! -f "$LAZPERF_DIR/lib/node/index.js" ]; then
  mkdir -p "$cache"
  (cd "$cache" && npm pack --silent "laz-perf@$version" > /dev/null && tar xzf "laz-perf-$version.tgz")
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "== interoperability: laz-perf $version decodes scandiff's LAZ (seeds ${SWEEP_SEEDS:-0 24})"
# shellcheck disable=SC2086 # two numbers
python3 "$here/laz-peer-sweep.py" "$cli" "$work" ${SWEEP_SEEDS:-0 24}

echo "== speed (wall seconds, peak resident KB)"
for laz in "$@"; do
  echo "$laz"
  cat "$laz" > /dev/null # from the page cache for every run
  /usr/bin/time -f "scandiff info, 2 cores: %e s %M KB" "$cli" info "$laz" > /dev/null
  /usr/bin/time -f "scandiff info, 1 core: %e s %M KB" taskset -c 0 "$cli" info "$laz" > /dev/null
  /usr/bin/time -f "laz-perf, 1 thread: %e s %M KB" node "$here/laz-perf-decode.mjs" "$laz" > /dev/null
done
