#!/usr/bin/env bash
# The side-by-side benchmark of docs/spatialhash.md: the grid (1 and 2 threads, with a Workspace),
# its twins and the peers (FCL, Bullet; compiled in when found) at 1K-1M objects, uniform and
# clustered, repetitions interleaved at random; then the CSV, the figure and the table.
# usage: scripts/bench_spatialhash.sh [BUILD_DIR] [REPETITIONS]    (defaults: build, 3)
# Writes BUILD_DIR/spatialhash_bench.json, docs/data/spatialhash_bench.csv,
# docs/img/spatialhash_bench.png and prints the Markdown table. Needs scripts/deps.sh bench.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
reps="${2:-3}"
cmake --build "$build" --target spatialhash_bench
F='^bm_ours/spatial_hash/n:[0-9]+/scene:[01]/'
F+='|^bm_ours/spatial_hash_fresh/n:(100000|1000000)/scene:[01]/threads:1/'
F+='|^bm_ours/sweep_and_prune/n:(1000|10000|100000)/scene:[01]/'
F+='|^bm_ours/brute_force/n:(1000|10000)/scene:[01]/threads:1/'
F+='|^bm_fcl/fcl_dynamic_aabb_tree/n:[0-9]+/scene:[01]/'
F+='|^bm_fcl/fcl_(spatial_hashing|sap)/n:(1000|10000)/scene:[01]/'
F+='|^bm_bullet/bullet_dbvt/n:(1000|10000|100000)/scene:[01]/'
F+='|^bm_bullet/bullet_axis_sweep_32/n:(1000|10000)/scene:[01]/'
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
"$build/bin/spatialhash_bench" --benchmark_filter="$F" --benchmark_repetitions="$reps" \
  --benchmark_enable_random_interleaving=true \
  --benchmark_out="$build/spatialhash_bench.json" --benchmark_out_format=json
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
/usr/bin/python3 scripts/plot_spatialhash.py csv "$build/spatialhash_bench.json" > docs/data/spatialhash_bench.csv
/usr/bin/python3 scripts/plot_spatialhash.py plot docs/data/spatialhash_bench.csv docs/img/spatialhash_bench.png
/usr/bin/python3 scripts/plot_spatialhash.py table docs/data/spatialhash_bench.csv
