#!/usr/bin/env bash
# The libFuzzer targets (fuzz/), built with clang. Three modes:
#
#   scripts/fuzz.sh [SECONDS]
#       Smoke run (CI): each target for SECONDS (default 60) over a copy of its checked-in seed corpus
#       (fuzz/corpus/<target>/). A finding fails the run and leaves its input in build-fuzz/findings/.
#
#   scripts/fuzz.sh campaign [--budget S] [--jobs N] [--targets LIST] [--dir D] [--fast]
#                            [--ledger FILE] [--note TEXT] [--timeout S] [--prebuilt]
#       A campaign: every target (or LIST, comma separated) in turn, for an even share of a wall-clock
#       budget of S seconds (default 3600), each as N libFuzzer processes (-fork=N, default: every core)
#       over a corpus that persists between campaigns (D/corpus/<target>, seeded from fuzz/corpus/).
#       After each target the corpus is merged (minimized to what adds coverage, -merge=1). Findings
#       (crashes, sanitizer reports, property violations, timeouts, out-of-memory) are kept in
#       D/findings/ and make the exit status 1; the campaign goes on with the next target. Every
#       target's run is appended to the ledger (default fuzz/ledger.csv): date, commit, build, jobs,
#       seconds, executions, coverage, corpus size, findings, load average. --fast uses a
#       coverage-only build (no ASan/UBSan; every target still checks its own property against its
#       reference), several times faster; the default build has ASan + UBSan like CI's.
#       D defaults to build-fuzz/campaign (build-fuzz-fast/campaign with --fast).
#       --prebuilt runs the targets already in the build folder, with no deps.sh and no cmake: for a
#       machine without the toolchain (a lent machine with more cores, the binaries and libtbb
#       carried there). The ledger's commit is then CULLIDE_FUZZ_COMMIT where git is missing; the
#       binaries must have been built from it.
#
#   scripts/fuzz.sh ledger [FILE]
#       The ledger's totals per target (executions, seconds, runs, findings, last coverage), as the
#       Markdown table that docs/reliability.md quotes.
#
# A finding's input: reproduce with `build-fuzz/bin/<target>_fuzz FILE`; once fixed, add the
# minimized input (`<target>_fuzz -minimize_crash=1 -runs=10000 FILE`) to fuzz/corpus/<target>/ so
# that CI replays it.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

die() { echo "fuzz.sh: $*" >&2; exit 2; }

# ledger_table FILE: totals per target, Markdown.
ledger_table() {
  local file="$1"
  [ -f "$file" ] || die "no ledger at $file"
  awk -F, '
    NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
    /^#/ || NF < 5 { next }
    {
      t = $col["target"]
      if (!(t in runs)) order[++n] = t
      runs[t]++; execs[t] += $col["executions"]; secs[t] += $col["seconds"]
      finds[t] += $col["crashes"] + $col["timeouts"] + $col["ooms"]
      if ($col["cov"] != "") cov[t] = $col["cov"]
      last[t] = $col["date_utc"]
    }
    function group(x,   s, neg) {
      s = sprintf("%.0f", x); neg = ""
      while (length(s) > 3) { neg = "," substr(s, length(s) - 2) neg; s = substr(s, 1, length(s) - 3) }
      return s neg
    }
    END {
      print "| target | executions | wall seconds | runs | findings | last coverage (cov) | last run |"
      print "|---|---:|---:|---:|---:|---:|---|"
      for (i = 1; i <= n; ++i) {
        t = order[i]
        printf "| `%s` | %s | %s | %d | %d | %s | %s |\n", t, group(execs[t]), group(secs[t]), runs[t], finds[t], cov[t], last[t]
      }
    }' "$file"
}

# target_flags NAME: libFuzzer flags of one target, for every mode (docs/reliability.md, "Fuzzing
# throughput"). pipeline: entropic scheduling counts a feature as rare while seen fewer than 255
# times (the default threshold) and searches the rare list for every feature of every run; with the
# ~27,000 features of pipeline's corpus that bookkeeping was over half of its time. At 16 it ran
# 1.4x more inputs per CPU second and reached more coverage in the same time.
target_flags() {
  case "$1" in
    pipeline) echo "-entropic_feature_frequency_threshold=16" ;;
  esac
}

# build DIR SANITIZE: configure (once) and build the fuzz targets.
build_fuzzers() {
  local build="$1" sanitize="$2"
  bash scripts/deps.sh fuzz
  if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
      -DCMAKE_CXX_COMPILER=clang++ -DCULLIDE_BUILD_FUZZERS=ON -DCULLIDE_BUILD_TESTS=OFF \
      -DCULLIDE_BUILD_BENCHMARKS=OFF -DCULLIDE_WERROR=ON "-DCULLIDE_FUZZ_SANITIZE=$sanitize" >/dev/null
  fi
  cmake --build "$build" -j"$(nproc)"
}

smoke() {
  local seconds="${1:-60}"
  [[ "$seconds" =~ ^[0-9]+$ ]] && [ "$seconds" -ge 1 ] || die "SECONDS must be a positive integer, got '$seconds'"
  local build="$root/build-fuzz"
  build_fuzzers "$build" "address,undefined"
  mkdir -p "$build/findings"
  export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp"
  local status=0 exe name work
  for exe in "$build"/bin/*_fuzz; do
    [ -x "$exe" ] || continue
    name="$(basename "$exe" _fuzz)"
    work="$build/corpus-$name"
    mkdir -p "$work"
    [ -d "fuzz/corpus/$name" ] && cp -n fuzz/corpus/"$name"/* "$work"/ 2>/dev/null || true
    echo "--- $name: ${seconds} s"
    # shellcheck disable=SC2046  # the flags are words
    if ! "$exe" $(target_flags "$name") -max_total_time="$seconds" -print_final_stats=1 \
        -artifact_prefix="$build/findings/$name-" "$work" 2>"$build/$name.log"; then
      echo "FINDING in $name (see $build/$name.log and $build/findings/)"; tail -40 "$build/$name.log"; status=1
    fi
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$build/$name.log" || true
  done
  return $status
}

campaign() {
  local budget=3600 jobs targets="" dir="" fast=0 ledger="$root/fuzz/ledger.csv" note="" timeout=120 prebuilt=0
  jobs="$(nproc)"
  while [ $# -gt 0 ]; do
    case "$1" in
      --budget) budget="${2:?--budget needs seconds}"; shift 2 ;;
      --jobs) jobs="${2:?--jobs needs a count}"; shift 2 ;;
      --targets) targets="${2:?--targets needs a list}"; shift 2 ;;
      --dir) dir="${2:?--dir needs a directory}"; shift 2 ;;
      --fast) fast=1; shift ;;
      --ledger) ledger="${2:?--ledger needs a file}"; shift 2 ;;
      --note) note="${2:?--note needs text}"; shift 2 ;;
      --timeout) timeout="${2:?--timeout needs seconds}"; shift 2 ;;
      --prebuilt) prebuilt=1; shift ;;
      *) die "campaign: unknown option '$1' (see the usage at the top of scripts/fuzz.sh)" ;;
    esac
  done
  [[ "$budget" =~ ^[0-9]+$ ]] && [ "$budget" -ge 1 ] || die "--budget must be a positive integer of seconds, got '$budget'"
  [[ "$jobs" =~ ^[0-9]+$ ]] && [ "$jobs" -ge 1 ] && [ "$jobs" -le 1024 ] || die "--jobs must be an integer in 1..1024, got '$jobs'"
  [[ "$timeout" =~ ^[0-9]+$ ]] && [ "$timeout" -ge 1 ] || die "--timeout must be a positive integer of seconds, got '$timeout'"
  case "$note" in *,*|*\"*) die "--note must not contain commas or quotes (it is a CSV field)" ;; esac

  local build sanitize kind
  if [ "$fast" = 1 ]; then build="$root/build-fuzz-fast"; sanitize=""; kind="coverage-only"
  else build="$root/build-fuzz"; sanitize="address,undefined"; kind="asan-ubsan"; fi
  [ -n "$dir" ] || dir="$build/campaign"
  [ "$prebuilt" = 1 ] || build_fuzzers "$build" "$sanitize"

  local all=() exe name
  for exe in "$build"/bin/*_fuzz; do [ -x "$exe" ] && all+=("$(basename "$exe" _fuzz)"); done
  [ ${#all[@]} -gt 0 ] || die "no fuzz targets were built in $build/bin"
  local chosen=()
  if [ -n "$targets" ]; then
    IFS=, read -r -a chosen <<<"$targets"
    for name in "${chosen[@]}"; do
      [ -x "$build/bin/${name}_fuzz" ] || die "unknown target '$name' (built: ${all[*]})"
    done
  else
    chosen=("${all[@]}")
  fi
  local share=$(( budget / ${#chosen[@]} ))
  [ "$share" -ge 1 ] || die "--budget $budget is less than one second per target (${#chosen[@]} targets)"

  mkdir -p "$dir/findings" "$dir/logs" "$(dirname "$ledger")"
  [ -f "$ledger" ] || echo "date_utc,commit,target,build,jobs,seconds,executions,exec_per_s,cov,ft,corpus,crashes,timeouts,ooms,load_start,load_end,cores,note" >"$ledger"
  local commit
  commit="$(git rev-parse --short=12 HEAD 2>/dev/null || echo "${CULLIDE_FUZZ_COMMIT:-unknown}")"
  # Dirty means changed code: the ledger's own earlier rows (a campaign of several runs writes it)
  # do not count.
  local ledger_rel
  ledger_rel="$(realpath -m --relative-to="$root" "$ledger")"
  if [ -n "$(git status --porcelain --untracked-files=no -- . ":(exclude)$ledger_rel" 2>/dev/null)" ]; then
    commit="$commit+dirty"
  fi
  export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp"
  export ASAN_OPTIONS="${ASAN_OPTIONS:-}${ASAN_OPTIONS:+:}abort_on_error=0"

  local status=0 t
  echo "campaign: ${#chosen[@]} targets x ${share} s, $jobs jobs each, build $kind, state in $dir, ledger $ledger"
  for t in "${chosen[@]}"; do
    local corpus="$dir/corpus/$t" log="$dir/logs/$t-$(date -u +%Y%m%dT%H%M%SZ).log"
    mkdir -p "$corpus"
    [ -d "fuzz/corpus/$t" ] && cp -n fuzz/corpus/"$t"/* "$corpus"/ 2>/dev/null || true
    local load_start load_end start end
    load_start="$(cut -d' ' -f1 /proc/loadavg)"
    start="$(date +%s)"
    echo "--- $t: $share s on $jobs jobs (log $log)"
    # Fork mode: jobs child processes, each fuzzing for a while and handing its new inputs back to
    # the corpus; -ignore_crashes etc. keep the campaign going after a finding (the artifacts stay).
    # shellcheck disable=SC2046  # the flags are words
    "$build/bin/${t}_fuzz" $(target_flags "$t") -fork="$jobs" -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
      -timeout="$timeout" -max_total_time="$share" -print_final_stats=1 \
      -artifact_prefix="$dir/findings/$t-" "$corpus" >"$log" 2>&1 || true
    end="$(date +%s)"
    load_end="$(cut -d' ' -f1 /proc/loadavg)"
    # The last fork-mode status line: "#EXECS: cov: C ft: F corp: N exec/s: R oom/timeout/crash: O/T/X time: ..."
    local line execs cov ft corp ooms touts crashes secs rate
    line="$(grep -E '^#[0-9]+: cov: ' "$log" | tail -1 || true)"
    if [ -z "$line" ]; then
      echo "fuzz.sh: $t printed no fork-mode status line; see $log" >&2; tail -20 "$log" >&2; status=1; continue
    fi
    execs="$(sed -E 's/^#([0-9]+):.*/\1/' <<<"$line")"
    cov="$(sed -E 's/.* cov: ([0-9]+).*/\1/' <<<"$line")"
    ft="$(sed -E 's/.* ft: ([0-9]+).*/\1/' <<<"$line")"
    corp="$(sed -E 's/.* corp: ([0-9]+).*/\1/' <<<"$line")"
    IFS=/ read -r ooms touts crashes <<<"$(sed -E 's/.* oom\/timeout\/crash: ([0-9]+\/[0-9]+\/[0-9]+).*/\1/' <<<"$line")"
    secs=$(( end - start ))
    rate=$(( secs > 0 ? execs / secs : execs ))
    # Merge: keep only the inputs that add coverage, so the corpus stays small between campaigns.
    local merged="$dir/corpus/.merge-$t"
    rm -rf "$merged"; mkdir -p "$merged"
    if "$build/bin/${t}_fuzz" -merge=1 -timeout="$timeout" "$merged" "$corpus" >>"$log" 2>&1; then
      rm -rf "$corpus"; mv "$merged" "$corpus"
    else
      echo "fuzz.sh: merging $t's corpus failed (kept unmerged); see $log" >&2; rm -rf "$merged"
    fi
    corp="$(find "$corpus" -type f | wc -l)"
    echo "$(date -u +%Y-%m-%dT%H:%M:%SZ),$commit,$t,$kind,$jobs,$secs,$execs,$rate,$cov,$ft,$corp,$crashes,$touts,$ooms,$load_start,$load_end,$(nproc),$note" >>"$ledger"
    printf '    %s executions in %s s (%s/s), cov %s, corpus %s, crashes %s, timeouts %s, ooms %s\n' \
      "$execs" "$secs" "$rate" "$cov" "$corp" "$crashes" "$touts" "$ooms"
    if [ "$crashes" != 0 ] || [ "$touts" != 0 ] || [ "$ooms" != 0 ]; then
      echo "FINDING in $t: inputs in $dir/findings/ (prefix $t-), log $log"; status=1
    fi
  done
  echo "ledger totals ($ledger):"
  ledger_table "$ledger"
  return $status
}

case "${1:-}" in
  campaign) shift; campaign "$@" ;;
  ledger) shift; ledger_table "${1:-$root/fuzz/ledger.csv}" ;;
  -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//' ;;
  *) smoke "$@" ;;
esac
