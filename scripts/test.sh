#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds everything (RelWithDebInfo, warnings as
# errors, TBB + the OSMesa, Vulkan and Embree oracles, every dependency switch explicit) and runs every test but the `slow` ones.
# usage: scripts/test.sh [extra ctest arguments...]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/deps.sh test
build="$root/build"
if [ ! -f "$build/CMakeCache.txt" ]; then
  # Every switch explicit, so the build is the same on every machine: the packages deps.sh installs
  # must all be found (STRICT), and the benchmark peers it does not install are off, whether or not
  # they happen to be here (.ci/run builds them hidden as well: the peers-hidden step).
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCULLIDE_WERROR=ON \
    -DCULLIDE_STRICT_DEPS=ON -DCULLIDE_WITH_TBB=ON -DCULLIDE_WITH_EIGEN=ON -DCULLIDE_WITH_GMP=ON \
    -DCULLIDE_WITH_OSMESA=ON -DCULLIDE_WITH_EGL=ON -DCULLIDE_WITH_VULKAN=ON -DCULLIDE_WITH_EMBREE=ON -DCULLIDE_BUILD_TESTS=ON -DCULLIDE_BUILD_BENCHMARKS=ON \
    -DCULLIDE_WITH_FCL=OFF -DCULLIDE_WITH_BULLET=OFF -DCULLIDE_WITH_CGAL=OFF >/dev/null
fi
cmake --build "$build" -j"$(nproc)"
export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp"
ctest --test-dir "$build" --output-on-failure -LE slow -j"$(nproc)" "$@"
