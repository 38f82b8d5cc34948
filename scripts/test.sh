#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds everything (RelWithDebInfo, warnings as
# errors, TBB + the OSMesa and Embree oracles) and runs every test but the `slow` ones.
# usage: scripts/test.sh [extra ctest arguments...]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/deps.sh test
build="$root/build"
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCULLIDE_WERROR=ON >/dev/null
fi
cmake --build "$build" -j"$(nproc)"
export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp"
ctest --test-dir "$build" --output-on-failure -LE slow -j"$(nproc)" "$@"
