#!/usr/bin/env bash
# Fuzzes the readers: scripts/fuzz.sh [SECONDS] [EXTENSION ...]
# Builds the libFuzzer harnesses (clang, AddressSanitizer, UndefinedBehaviorSanitizer)
# in build-fuzz/, then runs each for SECONDS (default 1800) from the committed corpus
# (tests/fuzz/corpus/EXT plus the reproducers of tests/data/fuzz-found). Limits: 1 s
# per input, 1 GB of memory. New interesting inputs go to build-fuzz/corpus/EXT (copy
# the small ones into tests/fuzz/corpus/EXT); a crash, leak, timeout or excess
# allocation is written to build-fuzz/artifacts/ and ends that run with a non-zero code.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-1800}
shift || true
extensions=("$@")
[ ${#extensions[@]} -eq 0 ] && extensions=(ply pcd las laz xyz obj stl off dxf e57)
build=${FUZZ_BUILD_DIR:-build-fuzz}

./scripts/install-deps.sh fuzz
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 \
  -DCMAKE_CXX_COMPILER=clang++-14 -DSCANDIFF_FUZZ=ON -DSCANDIFF_BUILD_GUI=OFF -DSCANDIFF_BUILD_BENCH=OFF >/dev/null
targets=()
for e in "${extensions[@]}"; do targets+=("scandiff-fuzz-$e"); done
cmake --build "$build" --target "${targets[@]}"

status=0
for e in "${extensions[@]}"; do
  corpus="$build/corpus/$e"
  mkdir -p "$corpus" "$build/artifacts"
  cp -n tests/fuzz/corpus/"$e"/* "$corpus"/ 2>/dev/null || true
  cp -n tests/data/fuzz-found/*."$e" "$corpus"/ 2>/dev/null || true
  echo "fuzz: .$e for $seconds s"
  "$build/tests/fuzz/scandiff-fuzz-$e" "$corpus" -max_total_time="$seconds" -timeout=1 -rss_limit_mb=1024 \
    -malloc_limit_mb=1024 -max_len=65536 -print_final_stats=1 -artifact_prefix="$build/artifacts/$e-" \
    2>&1 | tail -20 || status=1
done
exit $status
