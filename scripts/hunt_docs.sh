#!/usr/bin/env bash
# The figures of docs/hunt.md: `cullide hunt` on every built-in scene at the papers' resolution
# (GL-exact CULLIDE at 1024 x 1024, D24), and the axis-aligned room generator across methods,
# resolutions and depth formats. Writes docs/data/hunt_scenes.csv, docs/data/hunt_room.csv, the two
# SVG figures docs/img/hunt_room_*.svg (scripts/hunt_figures.py) and the
# findings under $OUT (default /tmp/cullide-hunt-docs). Budgets are case counts, not seconds, so the
# counts (not the times) are the same on every machine. Run from the repository root after a build:
#   bash scripts/hunt_docs.sh [CASES_PER_SCENE]
set -euo pipefail
CULLIDE=${CULLIDE:-build/bin/cullide}
OUT=${OUT:-/tmp/cullide-hunt-docs}
CASES=${1:-6}
mkdir -p "$OUT" docs/data
echo "load: $(uptime)" >&2

# One CSV row per source of a hunt's summary.json: method,resolution,depth,source,cases,failing,true,missed.
rows() {
  python3 - "$1" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
for src in s["sources"]:
    if src["cases"] == 0:
        continue
    f = s["findings"][0] if s["findings"] else None
    shrunk = f"{f['objects_before']}/{f['triangles_before']} -> {f['objects']}/{f['triangles']} ({f['reason']})" if f else ""
    print(",".join(str(x) for x in [s["method"], s["resolution"], s["depth_format"], src["name"], src["cases"],
                                    src["failing_cases"], src["true_pairs"], src["missed_pairs"], s["seconds"],
                                    '"' + shrunk + '"']))
PY
}

echo "method,resolution,depth,source,cases,failing,true_pairs,missed_pairs,seconds,first_finding" > docs/data/hunt_scenes.csv
for scene in cylinders tori bunny-dragon breaking leaves cloth; do
  "$CULLIDE" hunt --method cullide --scene "$scene" --cases "$CASES" --max-findings 1 --shrink-checks 300 \
    --no-progress --out "$OUT/scene-$scene" > "$OUT/scene-$scene.log"
  rows "$OUT/scene-$scene/summary.json" >> docs/data/hunt_scenes.csv
done
# Cloth's own pairs are self-collisions, which only Quick-CULLIDE reports.
"$CULLIDE" hunt --method qcullide-gl --self --scene cloth --cases "$CASES" --max-findings 1 --shrink-checks 300 \
  --no-progress --out "$OUT/scene-cloth-self" > "$OUT/scene-cloth-self.log"
rows "$OUT/scene-cloth-self/summary.json" >> docs/data/hunt_scenes.csv

echo "method,resolution,depth,source,cases,failing,true_pairs,missed_pairs,seconds,first_finding" > docs/data/hunt_room.csv
for method in cullide qcullide-gl rcullide-offset rcullide qcullide; do
  for res in 64 256 1024 2048; do
    cases=40; [ "$res" = 2048 ] && cases=20
    for depth in d24 d32f; do
      dir="$OUT/room-$method-$res-$depth"
      "$CULLIDE" hunt --method "$method" --resolution "$res" --depth-format "$depth" --generators room \
        --cases "$cases" --max-findings 1 --shrink-checks 0 --no-progress --out "$dir" > "$dir.log" || true
      rows "$dir/summary.json" >> docs/data/hunt_room.csv
    done
  done
done
# The room figures: one room frame as generated, and the same finding shrunk.
"$CULLIDE" hunt --method cullide --generators room --cases 1 --shrink-checks 0 --no-progress \
  --out "$OUT/room-figure-full" > /dev/null
"$CULLIDE" hunt --method cullide --generators room --cases 1 --no-progress --out "$OUT/room-figure-shrunk" > /dev/null
python3 scripts/hunt_figures.py views "$OUT/room-figure-full/finding-001" docs/img/hunt_room_frame.svg \
  "A room frame (generator room, case 0): every true pair is missed by cullide at 1024 px"
python3 scripts/hunt_figures.py views "$OUT/room-figure-shrunk/finding-001" docs/img/hunt_room_shrunk.svg \
  "Shrunk: one wall triangle (y = -1) crossed by one mover triangle"
echo "load: $(uptime)" >&2
