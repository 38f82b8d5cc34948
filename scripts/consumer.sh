#!/usr/bin/env bash
# Installs a configured build tree into a fresh prefix and builds tests/consumer (a downstream
# project) against the installed tree only: once with find_package(cullide CONFIG), and with
# --pkg-config also once with plain `c++ $(pkg-config --cflags --libs cullide)`. Runs what it built.
# usage: scripts/consumer.sh BUILD_DIR [--pkg-config]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$(cd "${1:?usage: $0 BUILD_DIR [--pkg-config]}" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/cullide-consumer.XXXXXX")"
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"

cmake --install "$build" --prefix "$prefix" >/dev/null
echo "consumer: installed $build into $prefix"

# CMake: the installed package only (the build tree is not on any search path).
cmake -S "$root/tests/consumer" -B "$work/cmake" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON >/dev/null
cmake --build "$work/cmake" >/dev/null
ctest --test-dir "$work/cmake" --output-on-failure

if [ "${2:-}" = "--pkg-config" ]; then
  pcdir="$(dirname "$(find "$prefix" -name cullide.pc | head -n 1)")"
  flags="$(PKG_CONFIG_PATH="$pcdir" pkg-config --cflags --libs cullide)"
  echo "consumer: pkg-config --cflags --libs cullide: $flags"
  # shellcheck disable=SC2086  # the flags are words
  c++ -std=c++20 -O2 "$root/tests/consumer/consumer_check.cpp" -o "$work/consumer_pc" $flags
  "$work/consumer_pc"
fi
