#!/usr/bin/env bash
# Regenerates everything docs/results.md shows: the CSVs under docs/data/ and the figures under
# docs/img/, from `cullide bench`, `cullide sweep`, peers_bench and scripts/plots.py.
#
# usage: scripts/results.sh [--quick | --full | --goals] [--build-dir DIR] [--threads T] [--skip-build]
#   --quick   (default) small scales and few frames: a few minutes on 2 quiet cores
#   --full    the papers' scene sizes where the methods can afford it, more frames and resolutions
#             (hours while the visibility methods cost seconds per frame at scale 1)
#   --goals   only the speed issues' goal commands (#16: peers_bench at the papers' sizes, 1 -> 2
#             threads, self-collision; #17: pipeline_bench, raster_bench), each run once, into
#             docs/data/goals/ with the load before each, and their goal tables (goals.md; about
#             5 minutes on 2 cores; --threads does not apply: the goals fix their thread counts)
#   --build-dir DIR   where to build (default build-results); --skip-build uses it as it is
#   --threads T       worker threads of every method and peer (default 0 = all cores)
# Needs: cmake, ninja, g++; for the peers libfcl-dev, libbullet-dev, libembree-dev, libcgal-dev; for
# the figures python3-matplotlib (scripts/deps.sh bench installs them all). A step that fails is
# logged in docs/data/results.log and the script goes on; the exit status is the number of failed
# steps (0: everything regenerated).
set -uo pipefail
cd "$(dirname "$0")/.." || exit 2

mode=quick
build="build-results"
threads=0
skip_build=0
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) mode=quick ;;
    --full) mode=full ;;
    --goals) mode=goals ;;
    --build-dir) build="$2"; shift ;;
    --threads) threads="$2"; shift ;;
    --skip-build) skip_build=1 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "results.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done

data=docs/data
img=docs/img
mkdir -p "$data" "$img"
log="$data/results.log"
# --goals keeps its own log beside its data (the quick / full run's log stays as it is).
if [ "$mode" = goals ]; then mkdir -p "$data/goals"; log="$data/goals/results.log"; fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
mesh_dir=../shared/data/meshes

note() { echo "$*" | tee -a "$log"; }
step() {  # step NAME CMD...: runs, logs the command, its time and the load; a failure is counted
  local name="$1"; shift
  note "+ [$name] $*"
  local t0=$SECONDS
  "$@" >>"$log" 2>&1
  local rc=$?
  note "  [$name] exit $rc after $((SECONDS - t0)) s; $(uptime | sed 's/.*load/load/')"
  if [ $rc -ne 0 ]; then failures=$((failures + 1)); note "  [$name] FAILED (see above)"; fi
  return 0
}
# concat OUT IN...: CSV files with one header
concat() {
  local out="$1"; shift
  local first=1
  : >"$out.tmp"
  for f in "$@"; do
    [ -s "$f" ] || continue
    if [ $first -eq 1 ]; then cat "$f" >>"$out.tmp"; first=0; else tail -n +2 "$f" >>"$out.tmp"; fi
  done
  if [ $first -eq 0 ]; then mv "$out.tmp" "$out"; else rm -f "$out.tmp"; fi
}

: >"$log"
note "results.sh --$mode, $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) cores, $(uname -m), commit $(git rev-parse --short HEAD 2>/dev/null || echo '?')$(git diff --quiet 2>/dev/null || echo ' + local changes')"
note "load at start: $(uptime | sed 's/.*load/load/')"

if [ $skip_build -eq 0 ]; then
  step configure cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCULLIDE_BUILD_BENCHMARKS=ON
  step build cmake --build "$build" --target cullide_cli -j"$(nproc)"
  # peers_bench exists only when Google Benchmark was found; without it the peers table is skipped.
  if grep -q "peers_bench" "$build/build.ninja" 2>/dev/null; then
    step build-peers cmake --build "$build" --target peers_bench -j"$(nproc)"
  fi
  if [ "$mode" != quick ] && grep -q "pipeline_bench" "$build/build.ninja" 2>/dev/null; then
    step build-pipeline cmake --build "$build" --target pipeline_bench -j"$(nproc)"
  fi
  if [ "$mode" = goals ] && grep -q "raster_bench" "$build/build.ninja" 2>/dev/null; then
    step build-raster cmake --build "$build" --target raster_bench -j"$(nproc)"
  fi
fi
cli=$(find "$build" -name cullide -type f -perm -u+x | head -n1)
peers=$(find "$build" -name peers_bench -type f -perm -u+x | head -n1)
if [ -z "$cli" ]; then note "results.sh: no cullide binary under $build"; exit 1; fi

py=python3
for cand in /usr/bin/python3 python3; do
  if command -v "$cand" >/dev/null && "$cand" -c 'import matplotlib' 2>/dev/null; then py=$cand; break; fi
done

if [ "$mode" = goals ]; then
  # The goal commands of issues #16 and #17, verbatim but for the output files; each is one run,
  # and the load average before it is written beside its data (load.txt).
  goals="$data/goals"
  mkdir -p "$goals"
  : >"$goals/load.txt"
  at() { echo "$1: $(date -u '+%Y-%m-%d %H:%M UTC') $(uptime | sed 's/.*load/load/')" >>"$goals/load.txt"; }
  echo "commit $(git rev-parse --short HEAD 2>/dev/null || echo '?')$(git diff --quiet 2>/dev/null || echo ' + local changes'), $(nproc) cores, $(uname -m)" >>"$goals/load.txt"
  if [ -n "$peers" ]; then
    at peers
    step goal-peers "$peers" --scenes cylinders,tori,bunny-dragon,breaking,leaves,cloth --first-frame 30 \
      --frame-step 5 --frames 2 --reps 3 --threads 2 --peers fcl-aabb,bullet-gimpact-exact,embree-collide \
      --methods exact,rcullide,auto,qcullide --mesh-dir "$mesh_dir" --csv "$goals/peers.csv"
  else
    note "results.sh: peers_bench not built: no #16 peers goal"
  fi
  at threads
  step goal-threads "$cli" bench --scenes cylinders,tori,bunny-dragon,breaking,leaves,cloth --methods exact,auto,rcullide,qcullide --first-frame 30 \
    --frame-step 5 --frames 2 --threads 1,2 --reps 3 --mesh-dir "$mesh_dir" --no-progress --csv "$goals/threads.csv"
  at self
  step goal-self "$cli" bench --scenes cloth --methods exact,qcullide --self --first-frame 55 --frames 2 \
    --threads 1,2 --reps 9 --no-progress --csv "$goals/self.csv"
  pipeline=$(find "$build" -name pipeline_bench -type f -perm -u+x | head -n1)
  if [ -n "$pipeline" ]; then
    at pipeline
    step goal-pipeline "$pipeline" --scale=0.1,cylinders=1,leaves=1,cloth=1 --frames=2 --reps=2 \
      --benchmark_out="$goals/pipeline_bench.json" --benchmark_out_format=json
  else
    note "results.sh: pipeline_bench not built (OSMesa or Google Benchmark missing): no #17 pipeline goal"
  fi
  raster=$(find "$build" -name raster_bench -type f -perm -u+x | head -n1)
  if [ -n "$raster" ]; then
    at raster
    step goal-raster "$raster" --benchmark_filter='^run/' --benchmark_min_time=0.2 --benchmark_repetitions=3 \
      --benchmark_out="$goals/raster_bench.json" --benchmark_out_format=json
  else
    note "results.sh: raster_bench not built: no #17 fill-rate goal"
  fi
  at end
  "$py" scripts/plots.py goals "$goals" >"$goals/goals.md" 2>>"$log" || { failures=$((failures + 1)); note "  [goals] FAILED"; }
  note "load at end: $(uptime | sed 's/.*load/load/')"
  note "results.sh: done, $failures failed step(s); log in $log; tables in $goals/goals.md"
  exit "$failures"
fi

common=(--threads "$threads" --mesh-dir "$mesh_dir" --no-progress)
vis=exact,cullide,rcullide,rcullide-offset
if [ "$mode" = quick ]; then
  obj_scales=0.05,0.1,0.25,0.5,1;  tri_scales=0.01,0.03,0.1,0.3;  size_frames=2
  sweep_res=32,64,128,256,512,1024; sweep_frames=1
  peers_frames=2; scene_frames=2; scene_warmup=0; scene_reps=2
else
  obj_scales=0.05,0.1,0.25,0.5,1,2; tri_scales=0.01,0.03,0.1,0.3,1; size_frames=5
  sweep_res=32,64,128,256,512,1024,2048,4096; sweep_frames=2
  peers_frames=3; scene_frames=3; scene_warmup=1; scene_reps=3
fi

# Frames where each scene has collisions (docs/scenes.md): bunny-dragon interpenetrates around
# frame 30, the broken pieces still touch in frames 25-36, the cloth's ball pokes through it in
# frames 19-34.
first_frame() { case "$1" in bunny-dragon) echo 25 ;; breaking) echo 26 ;; cloth) echo 20 ;; *) echo 0 ;; esac; }
# Sweep scale per scene: small enough that every resolution of every method stays within seconds.
sweep_scale() {
  if [ "$mode" = full ]; then
    case "$1" in cylinders|leaves|cloth) echo 1 ;; *) echo 0.25 ;; esac
  else
    case "$1" in cylinders|leaves|cloth) echo 0.25 ;; tori) echo 0.03 ;; bunny-dragon) echo 0.1 ;; *) echo 0.05 ;; esac
  fi
}
# Scale of the per-scene table and the peers: the papers' sizes, except where the visibility
# methods still cost tens of seconds per frame (quick mode).
scene_scale() {
  if [ "$mode" = full ]; then echo 1; else
    case "$1" in cylinders|leaves|cloth) echo 1 ;; *) echo 0.1 ;; esac
  fi
}
scenes=(cylinders tori bunny-dragon breaking leaves cloth)

# Every visibility method runs at its own default resolution (rcullide 32, the others 1024) except in
# the sweep.
# 1. number of objects vs time (cylinders) and number of triangles vs time (tori).
step objects "$cli" bench --scenes cylinders --scales "$obj_scales" --methods "$vis" \
  --frames "$size_frames" --warmup 0 --reps 1 "${common[@]}" --csv "$data/bench_objects.csv"
step triangles "$cli" bench --scenes tori --scales "$tri_scales" --methods "$vis" \
  --frames "$size_frames" --warmup 0 --reps 1 "${common[@]}" --csv "$data/bench_triangles.csv"

# 2. the sweep: resolution x depth format x method, per scene (one scale per scene).
parts=()
for s in "${scenes[@]}"; do
  fmts=d24
  # The depth format changed no count at these scales (docs/results.md): all three on cylinders only.
  if [ "$s" = cylinders ]; then fmts=d16,d24,d32f; fi
  step "sweep-$s" "$cli" sweep --scenes "$s" --scales "$(sweep_scale "$s")" --methods "$vis" \
    --resolutions "$sweep_res" --depth-formats "$fmts" --frames "$sweep_frames" --first-frame "$(first_frame "$s")" \
    --frame-step 5 "${common[@]}" --csv "$tmp/sweep_$s.csv"
  parts+=("$tmp/sweep_$s.csv")
done
concat "$data/sweep.csv" "${parts[@]}"

# 3. the papers' scenes: every method on each scene, timed with repetitions (bench checks the pairs).
parts=()
for s in "${scenes[@]}"; do
  step "scene-$s" "$cli" bench --scenes "$s" --scales "$(scene_scale "$s")" --methods "$vis" \
    --frames "$scene_frames" --first-frame "$(first_frame "$s")" --frame-step 5 --warmup "$scene_warmup" --reps "$scene_reps" \
    "${common[@]}" --csv "$tmp/scene_$s.csv"
  parts+=("$tmp/scene_$s.csv")
done
# Cloth self-collision (--self: exact and Quick-CULLIDE; CULLIDE and R-CULLIDE do not test an object
# against itself), frames 55-65 where the flap dips through the base.
step scene-cloth-self "$cli" bench --scenes cloth --scales 1 --self --methods exact,qcullide --frames "$scene_frames" \
  --first-frame 55 --frame-step 5 --warmup "$scene_warmup" --reps "$scene_reps" "${common[@]}" --csv "$tmp/scene_cloth_self.csv"
parts+=("$tmp/scene_cloth_self.csv")
# The ground truth alone at full size (it is fast enough in both modes).
step scenes-exact "$cli" bench --scenes all --scales 1 --methods exact --frames "$scene_frames" --first-frame 30 \
  --warmup 1 --reps 3 "${common[@]}" --csv "$tmp/scene_exact_full.csv"
parts+=("$tmp/scene_exact_full.csv")
concat "$data/bench_scenes.csv" "${parts[@]}"

# 4. peers side by side on the same frames.
if [ -n "$peers" ]; then
  parts=()
  for s in "${scenes[@]}"; do
    step "peers-$s" "$peers" --scenes "$s" --scales "$(scene_scale "$s")" --frames "$peers_frames" \
      --first-frame "$(first_frame "$s")" --frame-step 5 --reps 3 --threads "$threads" \
      --methods exact,auto,cullide,rcullide,rcullide-offset --mesh-dir "$mesh_dir" --csv "$tmp/peers_$s.csv"
    parts+=("$tmp/peers_$s.csv")
  done
  concat "$data/peers.csv" "${parts[@]}"
else
  note "results.sh: peers_bench not built (Google Benchmark missing?): no peers table"
fi

# 4b. (--full) the same passes on OSMesa llvmpipe against the emulator (docs/results.md).
pipeline=$(find "$build" -name pipeline_bench -type f -perm -u+x | head -n1)
if [ "$mode" = full ] && [ -n "$pipeline" ]; then
  step pipeline "$pipeline" --scale=0.1,cylinders=1,leaves=1,cloth=1 --frames=2 --reps=2 \
    --benchmark_out="$data/pipeline_bench.json" --benchmark_out_format=json
fi

# 5. the two-bunnies figure: cullide at a low resolution against rcullide.
step bunnies-input "$py" scripts/plots.py bunnies-input "$mesh_dir" "$tmp/bunnies"
low_res=512
step bunnies-cullide "$cli" run "$tmp/bunnies/bunny_a.obj" "$tmp/bunnies/bunny_b.obj" --method cullide \
  --resolution "$low_res" --threads "$threads" --pairs "$tmp/pairs_${low_res}px.csv"
step bunnies-rcullide "$cli" run "$tmp/bunnies/bunny_a.obj" "$tmp/bunnies/bunny_b.obj" --method rcullide \
  --resolution 128 --threads "$threads" --pairs "$tmp/pairs_rcullide.csv"
step bunnies-plot "$py" scripts/plots.py bunnies "$tmp/bunnies" "$tmp/pairs_${low_res}px.csv" \
  "$tmp/pairs_rcullide.csv" "$img/two_bunnies.png"
cp "$tmp/pairs_${low_res}px.csv" "$data/bunnies_cullide_${low_res}px.csv" 2>/dev/null
cp "$tmp/pairs_rcullide.csv" "$data/bunnies_rcullide.csv" 2>/dev/null

# 6. the figures.
step figures "$py" scripts/plots.py figures "$data" "$img"
"$py" scripts/plots.py tables "$data" >"$data/tables.md" 2>>"$log" || { failures=$((failures + 1)); note "  [tables] FAILED"; }

note "load at end: $(uptime | sed 's/.*load/load/')"
note "results.sh: done, $failures failed step(s); log in $log"
exit "$failures"
