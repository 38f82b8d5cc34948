#!/usr/bin/env bash
# ThreadSanitizer on the threaded code, with a oneTBB built for it.
#
# Debian's libtbb12 is not instrumented: the joins of parallel_for (the wait inside libtbb.so) are then
# invisible to TSan, and every parallel region reports false races on our own data (measured: about a
# thousand reports from the four thread-count tests, none real). A build without TBB runs the serial
# executor and has no threads to check. So this script builds Debian's own oneTBB source (apt-get source
# onetbb, the same 2021.8.0 as libtbb-dev) with TBB_SANITIZE=thread, once, into build-tsan/tbb, and
# builds cullide against it (docs/reliability.md, "ThreadSanitizer").
# usage: scripts/tsan.sh [short|full]
#   short (default, CI): the programs that run 1, 2, 3 and 8 threads (raster tiles, spatial hash, ground
#         truth, golden digests), their thread-count test cases only; and the exact-bounds visibility
#         passes that split one target between threads (the fused pass's runs, Quick-CULLIDE's
#         windowed passes), against their recorded forms; and the spread-schedule cases, where
#         threads of their own must run items (raster/detail/parallel.h, spatialhash's executor),
#         every pipeline method too; and the fast clear's random sequences (a target's record
#         across calls at 1-3 threads)
#   full  every library and unit test, all unit tests
#   CULLIDE_TSAN_BUILD  build folder (default build-tsan)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/deps.sh test
build="${CULLIDE_TSAN_BUILD:-$root/build-tsan}"
mode="${1:-short}"
case "$mode" in short|full) ;; *) echo "usage: $0 [short|full]" >&2; exit 2 ;; esac

# 1. oneTBB with ThreadSanitizer (about 3 minutes on 2 cores, once).
tbb="$build/tbb"
if [ ! -f "$tbb/install/lib/cmake/TBB/TBBConfig.cmake" ]; then
  mkdir -p "$tbb"
  if [ ! -d "$tbb/src" ]; then
    if ! apt-cache showsrc onetbb >/dev/null 2>&1 || [ -z "$(apt-cache showsrc onetbb 2>/dev/null)" ]; then
      if [ "$(id -u)" -ne 0 ]; then
        echo "cullide: the onetbb source package is needed and adding a deb-src entry needs root" >&2
        exit 1
      fi
      # Source entries mirror the binary ones this machine already uses (deb822 or one-line form).
      if [ -f /etc/apt/sources.list.d/debian.sources ]; then
        sed 's/^Types: deb$/Types: deb-src/' /etc/apt/sources.list.d/debian.sources \
          >/etc/apt/sources.list.d/cullide-tbb-src.sources
      elif [ -f /etc/apt/sources.list ]; then
        grep '^deb ' /etc/apt/sources.list | sed 's/^deb /deb-src /' >/etc/apt/sources.list.d/cullide-tbb-src.list
      else
        echo "cullide: no apt sources found to derive a deb-src entry from" >&2
        exit 1
      fi
      apt-get update -qq
    fi
    command -v dpkg-source >/dev/null || { export DEBIAN_FRONTEND=noninteractive; apt-get install -y -qq dpkg-dev >/dev/null; }
    (cd "$tbb" && apt-get source -qq onetbb >/dev/null 2>&1)
    mv "$tbb"/onetbb-*/ "$tbb/src"
  fi
  cmake -S "$tbb/src" -B "$tbb/build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTBB_SANITIZE=thread \
    -DTBB_TEST=OFF -DTBB_EXAMPLES=OFF -DTBBMALLOC_BUILD=OFF -DTBB_STRICT=OFF \
    -DCMAKE_INSTALL_PREFIX="$tbb/install" >/dev/null
  cmake --build "$tbb/build" -j"$(nproc)"
  cmake --install "$tbb/build" >/dev/null
fi

# 2. cullide with -fsanitize=thread against that oneTBB (a cache made against another TBB is redone).
tbb_dir="$tbb/install/lib/cmake/TBB"
if [ -f "$build/CMakeCache.txt" ] && ! grep -q "^TBB_DIR:[A-Z]*=$tbb_dir\$" "$build/CMakeCache.txt"; then
  rm -f "$build/CMakeCache.txt"
fi
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCULLIDE_WERROR=ON \
    -DCULLIDE_SANITIZE=thread -DCULLIDE_WITH_OSMESA=OFF -DCULLIDE_WITH_EGL=OFF -DCULLIDE_WITH_VULKAN=OFF -DCULLIDE_WITH_EMBREE=OFF \
    -DCULLIDE_BUILD_BENCHMARKS=OFF -DTBB_DIR="$tbb_dir" >/dev/null
fi
grep -q "^TBB_DIR:[A-Z]*=$tbb_dir\$" "$build/CMakeCache.txt" || {
  echo "cullide: $build did not pick up the instrumented oneTBB in $tbb_dir" >&2
  exit 1
}
if [ "$mode" = short ]; then
  cmake --build "$build" -j"$(nproc)" --target raster_threads_test spatialhash_api_test ground_truth_test \
    golden_digest_test raster_visibility_test quick_cullide_test fused_visibility_test raster_parallel_test spatialhash_stages_test \
    raster_simd_test cullide_pipeline_test
  select=(-R 'for 1, 2, 3 and 8 threads|are identical for 1, 2, 3 and 8|same for 1, 2, 3 and 8|Repeated runs|golden digests:|split between threads|WindowedPasses .each|native windowed passes|Fused and recorded R-CULLIDE|spread schedule|The fast clear: any sequence')
else
  cmake --build "$build" -j"$(nproc)"
  select=(-L unit -LE slow)
fi
# halt_on_error: the first report fails the test; the big random sweeps run a tenth of their cases.
export TSAN_OPTIONS="suppressions=$root/tests/reliability/tsan.supp halt_on_error=1 second_deadlock_stack=1"
CULLIDE_TRITRI_CASES="${CULLIDE_TRITRI_CASES:-100000}" CULLIDE_RELIABILITY_QUICK="${CULLIDE_RELIABILITY_QUICK:-1}" \
  ctest --test-dir "$build" --output-on-failure -j"$(nproc)" "${select[@]}"
