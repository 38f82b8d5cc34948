#!/usr/bin/env bash
# The main job: installs what is missing, builds the `cullide` CLI (Release) and runs
#   cullide run [ARGS...]      (default: the built-in `cylinders` scene, 10 frames)
# usage: scripts/run.sh [cullide run options...]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/deps.sh run
build="$root/build-release"
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCULLIDE_BUILD_TESTS=OFF \
    -DCULLIDE_BUILD_BENCHMARKS=OFF -DCULLIDE_STRICT_DEPS=ON -DCULLIDE_WITH_TBB=ON -DCULLIDE_WITH_EIGEN=OFF \
    -DCULLIDE_WITH_GMP=OFF -DCULLIDE_WITH_OSMESA=OFF -DCULLIDE_WITH_EGL=OFF -DCULLIDE_WITH_VULKAN=OFF -DCULLIDE_WITH_EMBREE=OFF >/dev/null
fi
if ! cmake --build "$build" --target cullide_cli -j"$(nproc)" > "$build/build.log" 2>&1; then
  cat "$build/build.log" >&2
  echo "cullide: the build failed (log above)" >&2
  exit 1
fi
# Relative scene paths are taken from where the user stood, not from the repo root.
cd "$OLDPWD" 2>/dev/null || true
exec "$build/bin/cullide" run "$@"
