#!/usr/bin/env bash
# Installs the Debian 12 packages cullide needs, only those missing (so a second run does nothing).
# usage: scripts/deps.sh run|test|fuzz|bench
#   run   what the library and the CLI need (oneTBB; the build tools)
#   test  + the test and benchmark dependencies and the oracles (Eigen for the Eigen front door,
#         doctest, GMP, OSMesa, EGL with Mesa's software device, Vulkan with lavapipe and glslang,
#         Embree, Benchmark)
#   fuzz  + clang with libFuzzer
#   bench + the peers of peers_bench (FCL, Bullet, CGAL) and matplotlib for scripts/plots.py and
#         scripts/plot_spatialhash.py (FCL and Bullet are also spatialhash_bench's peers)
#         (benchmark-only: never dependencies of the libraries)
set -euo pipefail

want=(cmake ninja-build g++ pkg-config libtbb-dev)
case "${1:-run}" in
  run) ;;
  test) want+=(libeigen3-dev doctest-dev libgmp-dev libosmesa6-dev libegl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri libvulkan-dev glslang-tools mesa-vulkan-drivers libembree-dev libbenchmark-dev) ;;
  fuzz) want+=(libeigen3-dev doctest-dev libgmp-dev libosmesa6-dev libegl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri libvulkan-dev glslang-tools mesa-vulkan-drivers libembree-dev libbenchmark-dev clang libclang-rt-14-dev) ;;
  bench) want+=(libeigen3-dev doctest-dev libgmp-dev libosmesa6-dev libegl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri libvulkan-dev glslang-tools mesa-vulkan-drivers libembree-dev libbenchmark-dev libfcl-dev libbullet-dev
               libcgal-dev python3-matplotlib) ;;
  *) echo "usage: $0 run|test|fuzz|bench" >&2; exit 2 ;;
esac

missing=()
for p in "${want[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "cullide: installing missing packages: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "cullide: these packages are missing and installing them needs root: ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
