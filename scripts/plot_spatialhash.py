#!/usr/bin/python3
"""Table data and figure of docs/spatialhash.md from spatialhash_bench's JSON output.

usage:
  scripts/plot_spatialhash.py csv BENCH.json [BENCH2.json ...] > docs/data/spatialhash_bench.csv
      one row per (method, scene, n, threads): medians over the repetitions of wall and CPU time
      per frame (ms), the repetition count and the pair count of frame 0
  scripts/plot_spatialhash.py plot docs/data/spatialhash_bench.csv docs/img/spatialhash_bench.png [wall|cpu]
      log-log objects vs time per frame, one panel per scene (uniform, clustered): wall time
      (default; the 2-core comparison on a quiet machine) or process CPU time (total work: the
      steadier figure on a loaded machine, where only the 1-thread lines compare like for like)
  scripts/plot_spatialhash.py table docs/data/spatialhash_bench.csv
      the Markdown table of docs/spatialhash.md (time, ratio to the best peer, 1 -> 2 thread scaling)

Needs Debian's python3-matplotlib for `plot` (scripts/deps.sh bench, where that mode exists);
`csv` and `table` need only the standard library. Run with Debian's /usr/bin/python3.
"""
import csv
import json
import re
import statistics
import sys
from collections import defaultdict

SCENES = {0: "uniform", 1: "clustered", 2: "giants"}
# Benchmark name prefix -> (method label, ours?)
METHODS = {
    "bm_ours/spatial_hash/": ("SpatialHash", True),
    "bm_ours/spatial_hash_fresh/": ("SpatialHash (no workspace)", True),
    "bm_ours/sweep_and_prune/": ("SweepAndPrune", True),
    "bm_ours/brute_force/": ("BruteForce", True),
    "bm_fcl/fcl_dynamic_aabb_tree/": ("FCL DynamicAABBTree", False),
    "bm_fcl/fcl_spatial_hashing/": ("FCL SpatialHashing", False),
    "bm_fcl/fcl_sap/": ("FCL SaP", False),
    "bm_bullet/bullet_dbvt/": ("Bullet dbvt", False),
    "bm_bullet/bullet_axis_sweep_32/": ("Bullet 32-bit sweep", False),
}
NAME = re.compile(r"n:(\d+)/scene:(\d+)/threads:(\d+)")
FIELDS = ["method", "peer", "scene", "n", "threads", "wall_ms", "cpu_ms", "reps", "pairs_f0"]


def to_ms(value, unit):
    return value * {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[unit]


def cmd_csv(paths):
    runs = defaultdict(list)
    pairs = {}
    for path in paths:
        with open(path) as f:
            data = json.load(f)
        for b in data["benchmarks"]:
            if b.get("run_type", "iteration") != "iteration" or b.get("error_occurred"):
                continue
            prefix = next((p for p in METHODS if b["name"].startswith(p)), None)
            m = NAME.search(b["name"])
            if prefix is None or m is None:
                continue
            key = (prefix, int(m.group(2)), int(m.group(1)), int(m.group(3)))
            runs[key].append((to_ms(b["real_time"], b["time_unit"]), to_ms(b["cpu_time"], b["time_unit"])))
            pairs[key] = int(b.get("pairs_f0", 0))
    out = csv.writer(sys.stdout, lineterminator="\n")
    out.writerow(FIELDS)
    for key in sorted(runs, key=lambda k: (list(METHODS).index(k[0]), k[1], k[2], k[3])):
        prefix, scene, n, threads = key
        label, ours = METHODS[prefix]
        wall = statistics.median(r[0] for r in runs[key])
        cpu = statistics.median(r[1] for r in runs[key])
        out.writerow([label, 0 if ours else 1, SCENES.get(scene, scene), n, threads, f"{wall:.4g}", f"{cpu:.4g}",
                      len(runs[key]), pairs[key]])


def read_rows(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["n"] = int(r["n"])
        r["threads"] = int(r["threads"])
        r["wall_ms"] = float(r["wall_ms"])
        r["cpu_ms"] = float(r["cpu_ms"])
        r["peer"] = r["peer"] == "1"
    return rows


def cmd_plot(csv_path, png_path, metric="wall"):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = read_rows(csv_path)
    scenes = [s for s in ("uniform", "clustered") if any(r["scene"] == s for r in rows)]
    fig, axes = plt.subplots(1, len(scenes), figsize=(6.2 * len(scenes), 4.8), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        series = defaultdict(list)
        for r in rows:
            if r["scene"] != scene or r["method"] == "SpatialHash (no workspace)":
                continue
            label = r["method"] if r["peer"] else f'{r["method"]} t={r["threads"]}'
            if metric == "cpu" and not r["peer"] and r["threads"] != 1:
                continue  # process CPU of 2 threads is total work, not a time per frame
            series[label].append((r["n"], r[f"{metric}_ms"]))
        for label in sorted(series, key=lambda s: (not s.startswith("SpatialHash"), s)):
            pts = sorted(series[label])
            ours = not any(label.startswith(p) for p in ("FCL", "Bullet"))
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o" if ours else "s",
                    linestyle="-" if ours else "--", linewidth=2.2 if label.startswith("SpatialHash") else 1.2,
                    label=label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("objects (moving spheres, their AABBs)")
        ax.set_ylabel(("wall" if metric == "wall" else "process CPU") + " time per frame, ms (median)")
        ax.set_title(f"{scene} scene")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("spatialhash broad phase vs peers (tests/bench/spatialhash_bench.cpp)")
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)


def cmd_table(csv_path):
    rows = read_rows(csv_path)
    by = {(r["method"], r["scene"], r["n"], r["threads"]): r for r in rows}
    print("| n | scene | pairs | SpatialHash t=1 wall / CPU | t=2 wall | 1->2 speed-up | best peer (CPU) | its wall / CPU "
          "| ratio t=2 wall / peer wall | ratio t=1 CPU / peer CPU | SweepAndPrune t=1 CPU |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    keys = sorted({(r["scene"], r["n"]) for r in rows}, key=lambda k: (k[1], k[0] != "uniform"))

    def fmt(v):
        return f"{v:.3g}" if v < 1000 else f"{v:,.0f}"

    for scene, n in keys:
        one = by.get(("SpatialHash", scene, n, 1))
        two = by.get(("SpatialHash", scene, n, 2))
        peers = [r for r in rows if r["peer"] and r["scene"] == scene and r["n"] == n]
        best = min(peers, key=lambda r: r["cpu_ms"]) if peers else None
        sap = by.get(("SweepAndPrune", scene, n, 1))
        cells = [f"{n:,}", scene, f'{int(one["pairs_f0"]):,}' if one else "-",
                 f'{fmt(one["wall_ms"])} / {fmt(one["cpu_ms"])}' if one else "-",
                 fmt(two["wall_ms"]) if two else "-",
                 f'{one["wall_ms"] / two["wall_ms"]:.2f}x' if one and two else "-",
                 best["method"] if best else "-",
                 f'{fmt(best["wall_ms"])} / {fmt(best["cpu_ms"])}' if best else "-",
                 f'{two["wall_ms"] / best["wall_ms"]:.2f}' if two and best else "-",
                 f'{one["cpu_ms"] / best["cpu_ms"]:.2f}' if one and best else "-",
                 fmt(sap["cpu_ms"]) if sap else "-"]
        print("| " + " | ".join(cells) + " |")


def main(argv):
    if len(argv) >= 3 and argv[1] == "csv":
        cmd_csv(argv[2:])
    elif len(argv) in (4, 5) and argv[1] == "plot" and (len(argv) == 4 or argv[4] in ("wall", "cpu")):
        cmd_plot(argv[2], argv[3], argv[4] if len(argv) == 5 else "wall")
    elif len(argv) == 3 and argv[1] == "table":
        cmd_table(argv[2])
    else:
        sys.stderr.write(__doc__)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
