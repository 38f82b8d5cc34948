#!/usr/bin/env bash
# Builds the libFuzzer targets with clang and runs each for SECONDS (default 60) over a copy of its
# checked-in seed corpus (fuzz/corpus/<target>/). A finding fails the run and leaves its input in
# build-fuzz/findings/.
# usage: scripts/fuzz.sh [SECONDS]
set -euo pipefail
seconds="${1:-60}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/deps.sh fuzz
build="$root/build-fuzz"
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
    -DCMAKE_CXX_COMPILER=clang++ -DCULLIDE_BUILD_FUZZERS=ON -DCULLIDE_BUILD_TESTS=OFF \
    -DCULLIDE_BUILD_BENCHMARKS=OFF -DCULLIDE_WERROR=ON >/dev/null
fi
cmake --build "$build" -j"$(nproc)"
mkdir -p "$build/findings"
export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp"
status=0
for exe in "$build"/bin/*_fuzz; do
  [ -x "$exe" ] || continue
  name="$(basename "$exe" _fuzz)"
  work="$build/corpus-$name"
  mkdir -p "$work"
  [ -d "fuzz/corpus/$name" ] && cp -n fuzz/corpus/"$name"/* "$work"/ 2>/dev/null || true
  echo "--- $name: ${seconds} s"
  if ! "$exe" -max_total_time="$seconds" -print_final_stats=1 -artifact_prefix="$build/findings/$name-" \
      "$work" 2>"$build/$name.log"; then
    echo "FINDING in $name (see $build/$name.log and $build/findings/)"; tail -40 "$build/$name.log"; status=1
  fi
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$build/$name.log" || true
done
exit $status
