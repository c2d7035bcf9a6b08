#!/usr/bin/env bash
# scandiff's LAZ against laz-perf, an independent LASzip-compatible decoder
# (github.com/hobuinc/laz-perf, Apache-2.0; npm package `laz-perf`, WebAssembly,
# run by Node.js). Debian 12 packages no LAZ tool, so this is the peer the
# machine can run. Two things, results in docs/benchmarks.md and docs/laz.md:
#  1. interoperability: LAZ files scandiff writes in point formats 6, 7 (with
#     an Extra Bytes field) and 8 are decoded by laz-perf, and its records
#     must equal byte for byte those of the LAS file scandiff writes from the
#     same points;
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

# Where a LAS file's point records start (the header's "offset to point data").
records_of() { tail -c +$(($(od -An -tu4 -j96 -N4 "$1") + 1)) "$1"; }

echo "== interoperability: laz-perf $version decodes scandiff's LAZ"
python3 - "$work" <<'PY'
import random, sys
random.seed(5)
# Four scanner channels, point by point: the colour, NIR and Extra Bytes
# coders then switch context at almost every point (docs/laz.md).
columns = {'f6': 'x,y,z,intensity,gps_time,scanner_channel', 'f7': 'x,y,z,r,g,b,intensity,height,scanner_channel',
           'f8': 'x,y,z,r,g,b,nir,classification,amplitude,scanner_channel'}
for name, cols in columns.items():
    with open(f'{sys.argv[1]}/{name}.txt', 'w') as out:
        x = 651000.0
        for i in range(200000):
            x += random.uniform(0, 0.05)
            row = [f'{x:.3f}', f'{6862000 + random.uniform(0, 300):.3f}', f'{random.uniform(100, 140):.3f}']
            for c in cols.split(',')[3:]:
                row.append({'r': lambda: str(random.randrange(256)), 'g': lambda: str(random.randrange(256)),
                            'b': lambda: str(random.randrange(256)), 'nir': lambda: str(random.randrange(65536)),
                            'intensity': lambda: str(random.randrange(4000)),
                            'gps_time': lambda: f'{300000 + i * 1e-5:.6f}',
                            'classification': lambda: str(random.choice([2, 3, 5, 6])),
                            'height': lambda: f'{random.uniform(-5, 5):.4f}',
                            'amplitude': lambda: str(random.randrange(300)),
                            'scanner_channel': lambda: str(random.randrange(4))}[c]())
            out.write(' '.join(row) + '\n')
    open(f'{sys.argv[1]}/{name}.columns', 'w').write(cols)
PY
for name in f6 f7 f8; do
  columns=$(cat "$work/$name.columns")
  for ext in las laz; do
    "$cli" convert --columns "$columns" --separator space "$work/$name.txt" "$work/$name.$ext" > /dev/null
  done
  node "$here/laz-perf-decode.mjs" "$work/$name.laz" "$work/$name.records"
  if records_of "$work/$name.las" | cmp -s - "$work/$name.records"; then
    echo "$name ($columns): every record equals the LAS twin's"
  else
    echo "$name ($columns): laz-perf's records DIFFER from the LAS twin's" >&2
    exit 1
  fi
done

echo "== speed (wall seconds, peak resident KB)"
for laz in "$@"; do
  echo "$laz"
  cat "$laz" > /dev/null # from the page cache for every run
  /usr/bin/time -f "scandiff info, 2 cores: %e s %M KB" "$cli" info "$laz" > /dev/null
  /usr/bin/time -f "scandiff info, 1 core: %e s %M KB" taskset -c 0 "$cli" info "$laz" > /dev/null
  /usr/bin/time -f "laz-perf, 1 thread: %e s %M KB" node "$here/laz-perf-decode.mjs" "$laz" > /dev/null
done
