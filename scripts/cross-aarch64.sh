#!/usr/bin/env bash
# The embedded target: cross-builds the libraries and their unit tests for aarch64 Linux with Debian's
# g++-aarch64-linux-gnu (no TBB, OSMesa, Embree or benchmarks; static binaries) and runs `ctest -L unit`
# under qemu-user. The golden digests of tests/reliability then prove x86-64 == aarch64 bit for bit.
# usage: scripts/cross-aarch64.sh [extra ctest arguments...]
#   CULLIDE_AARCH64_BUILD  build folder (default build-aarch64)
# Installs what is missing (needs root then): the cross compiler, qemu-user, and GMP for arm64 through
# Debian multiarch (dpkg --add-architecture arm64), for the rational-reference tests.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
build="${CULLIDE_AARCH64_BUILD:-$root/build-aarch64}"

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
want=(cmake ninja-build libeigen3-dev doctest-dev g++-aarch64-linux-gnu qemu-user libgmp-dev:arm64)
missing=()
for p in "${want[@]}"; do installed "$p" || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  echo "cullide: installing missing packages: ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "cullide: these packages are missing and installing them needs root: ${missing[*]}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    dpkg --add-architecture arm64
  fi
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchain-aarch64.cmake" \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCULLIDE_WERROR=ON \
    -DCULLIDE_WITH_TBB=OFF -DCULLIDE_WITH_OSMESA=OFF -DCULLIDE_WITH_EGL=OFF -DCULLIDE_WITH_VULKAN=OFF -DCULLIDE_WITH_EMBREE=OFF \
    -DCULLIDE_BUILD_BENCHMARKS=OFF >/dev/null
fi
# The configuration must really be the cross one (a stale host cache would test x86-64 instead).
grep -q '^CULLIDE_QEMU:.*qemu-aarch64' "$build/CMakeCache.txt" || {
  echo "cullide: $build is not an aarch64 cross build (no qemu emulator in its cache)" >&2
  exit 1
}
cmake --build "$build" -j"$(nproc)"
readelf -h "$build/bin/mesh_test" | grep -q 'Machine:.*AArch64' || {
  echo "cullide: $build/bin/mesh_test is not an aarch64 binary" >&2
  exit 1
}
# Under emulation everything is ~5-25x slower: the big random sweeps run a tenth of their cases, and
# the reliability suites leave their O(n^2) twins to the native run (the golden literals are the same).
# Known aarch64 failures, each an open portability bug listed in docs/reliability.md with its owner; the
# list is printed on every run and is to be emptied, never extended to make CI green. Set
# CULLIDE_AARCH64_KNOWN_FAILURES='' to run them anyway.
known="${CULLIDE_AARCH64_KNOWN_FAILURES-}"
exclude=()
if [ -n "$known" ]; then
  echo "cullide: KNOWN aarch64 failures, excluded (docs/reliability.md, open bugs): $known"
  exclude=(-E "$known")
fi
CULLIDE_TRITRI_CASES="${CULLIDE_TRITRI_CASES:-100000}" CULLIDE_RELIABILITY_QUICK="${CULLIDE_RELIABILITY_QUICK:-1}" \
  ctest --test-dir "$build" --output-on-failure -L unit -LE slow -j"$(nproc)" "${exclude[@]}" "$@"
