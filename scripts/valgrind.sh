#!/usr/bin/env bash
# Valgrind memcheck over the unit tests and the CLI (docs/reliability.md, "Valgrind").
#
# Uses the embedded configuration (no TBB, OSMesa or Embree: the serial executor, so no thread-pool
# noise and nothing outside the project's own code in the reports), in build-embedded unless
# CULLIDE_VALGRIND_BUILD names another plain (unsanitized) build. Every test case that ctest lists
# (`-L unit -LE slow`, each doctest case on its own) runs under
#   valgrind --tool=memcheck --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect
# so an invalid read/write, a use of uninitialised memory or a definite/indirect leak fails it; then
# the CLI runs two frames of every method on a small scene.
#
# usage: scripts/valgrind.sh [short|reliability|full]
#   short:       the raster and spatial hash golden digests, then the CLI (every method, whole pipeline)
#   reliability: the golden digests (every scene x method) and the hard cases, then the CLI
#   full:        every unit test case, then the CLI
# Memcheck runs code 20-50x slower: on a quiet 2-core machine short takes minutes, reliability about
# half an hour, full hours. --track-origins is off (it doubles the time); CULLIDE_VALGRIND_ORIGINS=1
# turns it on to find where an uninitialised value came from.
# CULLIDE_RELIABILITY_QUICK=1 is set (as for qemu and TSan: the O(n^2) twins are left to native runs).
set -euo pipefail
mode="${1:-short}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
if ! command -v valgrind >/dev/null; then
  [ "$(id -u)" -eq 0 ] || { echo "valgrind.sh: valgrind is not installed (apt-get install valgrind, as root)" >&2; exit 2; }
  DEBIAN_FRONTEND=noninteractive apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends valgrind >/dev/null
fi
build="${CULLIDE_VALGRIND_BUILD:-$root/build-embedded}"
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCULLIDE_WERROR=ON \
    -DCULLIDE_WITH_TBB=OFF -DCULLIDE_WITH_OSMESA=OFF -DCULLIDE_WITH_EGL=OFF -DCULLIDE_WITH_VULKAN=OFF -DCULLIDE_WITH_EMBREE=OFF -DCULLIDE_BUILD_BENCHMARKS=OFF >/dev/null
fi
case "$mode" in
  short) regex='golden digests: (raster|spatial)'; targets=(golden_digest_test cullide_cli) ;;
  reliability) regex='golden digests|hard cases'; targets=(golden_digest_test hard_cases_test cullide_cli) ;;
  full) regex=''; targets=() ;;
  *) echo "usage: $0 [short|reliability|full]" >&2; exit 2 ;;
esac
cmake --build "$build" -j"$(nproc)" ${targets[@]:+--target "${targets[@]}"}
export CULLIDE_RELIABILITY_QUICK=1
log="$build/valgrind"
rm -rf "$log"
mkdir -p "$log"
vg=(valgrind --tool=memcheck --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect
    --show-leak-kinds=definite,indirect --num-callers=30)
[ "${CULLIDE_VALGRIND_ORIGINS:-0}" = 1 ] && vg+=(--track-origins=yes)

# The test commands, exactly as ctest would run them (one line per case: NUL-separated argv).
list="$log/tests.txt"
ctest --test-dir "$build" -N -L unit -LE slow ${regex:+-R "$regex"} --show-only=json-v1 | python3 -c '
import json, sys
for t in json.load(sys.stdin)["tests"]:
    cmd = t.get("command")
    if not cmd:
        continue
    wd = next((p["value"] for p in t.get("properties", []) if p["name"] == "WORKING_DIRECTORY"), ".")
    print("\x1f".join([t["name"], wd] + cmd))
' >"$list"
total=$(wc -l <"$list")
[ "$total" -gt 0 ] || { echo "valgrind.sh: ctest listed no tests in $build" >&2; exit 1; }
echo "valgrind.sh: $total test cases under memcheck ($mode), logs in $log"
start=$SECONDS
failed=0
n=0
while IFS=$'\x1f' read -r -a entry; do
  n=$((n + 1))
  name="${entry[0]}"; wd="${entry[1]}"; cmd=("${entry[@]:2}")
  out="$log/$(printf '%04d' "$n").log"
  if ! (cd "$wd" && "${vg[@]}" --log-file="$out.vg" "${cmd[@]}" >"$out" 2>&1); then
    echo "FAILED: $name (see $out and $out.vg)"; failed=$((failed + 1))
  fi
done <"$list"

# The CLI: two frames of every method (the names its error message lists) on a small built-in scene.
cli="$build/bin/cullide"
methods=$(python3 - "$cli" <<'EOF'
import subprocess, sys
r = subprocess.run([sys.argv[1], "run", "--method", "no-such-method", "--frames", "1"], capture_output=True, text=True)
text = r.stdout + r.stderr
# The error lists the valid names (pipeline.h: parse_method).
import re
m = re.search(r"\(valid: ([^)]*)\)", text)
print(" ".join(m.group(1).replace(",", " ").split()) if m else "exact")
EOF
)
for method in $methods; do
  n=$((n + 1)); total=$((total + 1))
  out="$log/cli-$method.log"
  if ! "${vg[@]}" --log-file="$out.vg" "$cli" run cylinders --scale 0.05 --frames 2 --method "$method" \
      --resolution 64 --mesh-dir "" >"$out" 2>&1; then
    echo "FAILED: cli --method $method (see $out and $out.vg)"; failed=$((failed + 1))
  fi
done
errors=$( (grep -h "ERROR SUMMARY" "$log"/*.vg || true) | awk '{s += $4} END {print s + 0}')
# No leak lines at all when every block was freed ("All heap blocks were freed").
definite=$( (grep -h "definitely lost:" "$log"/*.vg || true) | awk '{gsub(",", "", $4); s += $4} END {print s + 0}')
indirect=$( (grep -h "indirectly lost:" "$log"/*.vg || true) | awk '{gsub(",", "", $4); s += $4} END {print s + 0}')
reports=$(ls "$log"/*.vg | wc -l)
[ "$reports" -eq "$total" ] || { echo "valgrind.sh: $reports memcheck reports for $total runs" >&2; failed=$((failed + 1)); }
echo "valgrind.sh: $total runs ($mode; methods: $methods), $failed failed; memcheck errors $errors," \
  "definitely lost $definite bytes, indirectly lost $indirect bytes; $((SECONDS - start)) s"
[ "$failed" -eq 0 ]
