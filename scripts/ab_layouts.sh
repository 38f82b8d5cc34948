#!/bin/bash
# scripts/ab_layouts.sh: two builds of `cullide` side by side under ten process layouts.
#
# usage: scripts/ab_layouts.sh BASE_BINARY NEW_BINARY OUT.csv [cullide bench options...]
#
# A frame's time depends on where the process's initial stack lands, which moves with the size of
# the environment and of argv[0]: the same binary ran `exact --self` on the folded cloth at 3.5 ms a
# frame from one path and at 4.5 ms from another (docs/cullide.md, "Measuring a change"). So both
# binaries are copied to paths of the same length, and each runs `cullide bench` under ten
# environment sizes (a PADDING variable of 16 to 3,616 bytes), base then new for each size. OUT.csv
# gets one row per size, binary (a = base, b = new) and bench row; the summary printed at the end is
# min / median / max over the sizes and the ratio of the medians. Nothing here is timed but what
# `cullide bench` times.
set -euo pipefail
if [ $# -lt 3 ]; then
  sed -n '2,14p' "$0"
  exit 2
fi
base=$1
new=$2
out=$3
shift 3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/a" "$work/b"
cp "$base" "$work/a/cullide"
cp "$new" "$work/b/cullide"
echo "pad,binary,scene,scale,method,threads,ms_median,load" > "$out"
for k in 0 1 2 3 4 5 6 7 8 9; do
  pad=$(head -c $((k * 400 + 16)) /dev/zero | tr '\0' 'x')
  for v in a b; do
    env PADDING="$pad" "$work/$v/cullide" bench "$@" --no-progress --csv "$work/rows.csv" > /dev/null
    python3 - "$work/rows.csv" "$k" "$v" >> "$out" <<'EOF'
import csv, sys
for x in csv.DictReader(open(sys.argv[1])):
    print(f"{sys.argv[2]},{sys.argv[3]},{x['scene']},{x['scale']},{x['method']},{x['threads']},{x['ms_median']},{x['load']}")
EOF
  done
done
python3 - "$out" <<'EOF'
import collections, csv, statistics, sys
d = collections.defaultdict(list)
for x in csv.DictReader(open(sys.argv[1])):
    d[(x['scene'], x['scale'], x['method'], x['threads'], x['binary'])].append(float(x['ms_median']))
keys = []
for k in d:
    if k[:4] not in keys:
        keys.append(k[:4])
print("| scene | scale | method | threads | base ms min / median / max | new ms min / median / max | base / new (medians) |")
print("|---|---|---|---|---|---|---|")
for k in keys:
    a, b = d[k + ('a',)], d[k + ('b',)]
    f = lambda v: f"{min(v):.3f} / {statistics.median(v):.3f} / {max(v):.3f}"
    print(f"| {k[0]} | {k[1]} | {k[2]} | {k[3]} | {f(a)} | {f(b)} | {statistics.median(a) / statistics.median(b):.2f}x |")
EOF
