#!/usr/bin/env python3
"""Figures of docs/results.md from the CSVs of `cullide bench`, `cullide sweep` and peers_bench.

usage:
  scripts/plots.py figures DATA_DIR IMG_DIR     every figure whose CSV is in DATA_DIR
  scripts/plots.py tables DATA_DIR              the markdown tables of docs/results.md, on stdout
  scripts/plots.py goals GOALS_DIR              the goal tables of issues #16 and #17 from the files
                                                of `scripts/results.sh --goals`, on stdout
  scripts/plots.py bunnies-input MESH_DIR OUT   writes OUT/bunny_a.obj, OUT/bunny_b.obj: two
                                                interpenetrating bunnies (a stand-in blob when
                                                MESH_DIR has no stanford-bunny.obj)
  scripts/plots.py bunnies OUT PAIRS_LOW PAIRS_REF IMG   the two-bunnies figure from the pair files
                                                of `cullide run --pairs` (cullide at low resolution,
                                                rcullide)

Needs Debian's python3-matplotlib (scripts/deps.sh bench). Writes PNG files; never changes the CSVs.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

METHOD_STYLE = {
    "exact": ("black", "o"),
    "cullide": ("tab:red", "s"),
    "rcullide": ("tab:blue", "^"),
    "rcullide-offset": ("tab:green", "v"),
    "qcullide": ("tab:orange", "D"),
    "qcullide-gl": ("tab:purple", "P"),
    "auto": ("tab:cyan", "*"),
}


def style(method):
    return METHOD_STYLE.get(method, ("tab:gray", "x"))


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def fnum(row, key, default=0.0):
    v = row.get(key, "")
    try:
        return float(v)
    except (TypeError, ValueError):
        return default


def by(rows, key):
    out = {}
    for r in rows:
        out.setdefault(r[key], []).append(r)
    return out


def load_note(rows):
    loads = [fnum(r, "load", -1) for r in rows if fnum(r, "load", -1) >= 0]
    if not loads:
        return ""
    return f"load average {min(loads):.1f}-{max(loads):.1f} on {os.cpu_count()} cores"


def size_vs_time(rows, xkey, xlabel, title, img):
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for method, rs in by(rows, "method").items():
        rs = sorted(rs, key=lambda r: fnum(r, xkey))
        x = [fnum(r, xkey) for r in rs]
        y = [fnum(r, "ms_mean") for r in rs]
        lo = [max(0.0, fnum(r, "ms_mean") - fnum(r, "ms_min")) for r in rs]
        hi = [max(0.0, fnum(r, "ms_max") - fnum(r, "ms_mean")) for r in rs]
        c, m = style(method)
        label = method + ("" if method == "exact" else f" ({rs[0].get('resolution', '')} px)")
        ax.errorbar(x, y, yerr=[lo, hi], color=c, marker=m, capsize=3, label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("ms per frame (mean; bars: min-max)")
    ax.set_title(title + "\n" + load_note(rows), fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(img, dpi=110)
    plt.close(fig)


def sweep_figures(rows, img_dir):
    scenes = list(by(rows, "scene").keys())
    # Resolution vs time, d24 (or the only depth format), one panel per scene.
    fmt = "d24" if any(r["depth_format"] == "d24" for r in rows) else rows[0]["depth_format"]
    n = len(scenes)
    cols = min(3, n)
    nrows = (n + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols, 3.6 * nrows), squeeze=False)
    for i, scene in enumerate(scenes):
        ax = axes[i // cols][i % cols]
        srows = [r for r in rows if r["scene"] == scene]
        for method, rs in by([r for r in srows if r["depth_format"] in (fmt, "")], "method").items():
            if method == "exact":
                ax.axhline(fnum(rs[0], "ms_mean"), color="black", ls="--", lw=1, label="exact")
                continue
            rs = sorted(rs, key=lambda r: fnum(r, "resolution"))
            c, m = style(method)
            ax.plot([fnum(r, "resolution") for r in rs], [fnum(r, "ms_mean") for r in rs], color=c, marker=m,
                    label=method)
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_title(f"{scene} ({int(fnum(srows[0], 'triangles'))} triangles)", fontsize=9)
        ax.set_xlabel("resolution (pixels per side)")
        ax.set_ylabel("ms per frame")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    for j in range(n, nrows * cols):
        axes[j // cols][j % cols].axis("off")
    fig.suptitle(f"resolution vs time ({fmt}); {load_note(rows)}", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(img_dir, "resolution_vs_time.png"), dpi=100)
    plt.close(fig)

    # Error vs time: per scene, false negatives and false positives per frame against ms per frame,
    # one curve per method (its points are the resolutions, every depth format).
    cols = min(3, n)
    grid_rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(2 * grid_rows, cols, figsize=(5.0 * cols, 3.6 * 2 * grid_rows), squeeze=False)
    for j in range(n, grid_rows * cols):
        axes[j // cols][j % cols].axis("off")
        axes[grid_rows + j // cols][j % cols].axis("off")
    for i, scene in enumerate(scenes):
        srows = [r for r in rows if r["scene"] == scene]
        for k, (key, label) in enumerate([("false_negatives", "false negatives / frame\n(missed colliding pairs)"),
                                          ("false_positives", "PCS false positives / frame\n(candidate pairs not colliding)")]):
            ax = axes[k * grid_rows + i // cols][i % cols]
            for (method, dfmt), rs in sorted(by_pair(srows, "method", "depth_format").items()):
                rs = sorted(rs, key=lambda r: fnum(r, "resolution"))
                c, m = style(method)
                frames = [max(1.0, fnum(r, "frames", 1)) for r in rs]
                x = [fnum(r, "ms_mean") for r in rs]
                y = [fnum(r, key) / f for r, f in zip(rs, frames)]
                ls = {"d16": ":", "d24": "-", "d32f": "--"}.get(dfmt, "-")
                lab = method if method == "exact" else f"{method} {dfmt}"
                ax.plot(x, y, color=c, marker=m, ls=ls, label=lab, ms=4)
                if method != "exact" and dfmt == fmt:
                    for r, xx, yy in zip(rs, x, y):
                        ax.annotate(r["resolution"], (xx, yy), fontsize=6, alpha=0.7)
            ax.set_xscale("log")
            ax.set_yscale("symlog", linthresh=1)
            ax.set_ylim(bottom=0)
            ax.set_xlabel("ms per frame")
            ax.set_ylabel(label, fontsize=8)
            truth = fnum(srows[0], "truth_pairs") / max(1.0, fnum(srows[0], "frames", 1))
            ax.set_title(f"{scene} (scale {srows[0]['scale']}, {truth:.0f} colliding pairs / frame)", fontsize=9)
            ax.grid(True, which="both", alpha=0.3)
            if i == 0:
                ax.legend(fontsize=6)
    fig.suptitle("error vs time (labels: resolution); " + load_note(rows), fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(img_dir, "error_vs_time.png"), dpi=100)
    plt.close(fig)


def by_pair(rows, k1, k2):
    out = {}
    for r in rows:
        out.setdefault((r[k1], r[k2]), []).append(r)
    return out


def peers_figure(rows, img):
    scenes = list(by(rows, "scene").keys())
    names = []
    for r in rows:
        if r["peer"] not in names:
            names.append(r["peer"])
    fig, ax = plt.subplots(figsize=(max(7.0, 1.6 * len(scenes) + 3), 4.8))
    width = 0.8 / max(1, len(names))
    cmap = plt.get_cmap("tab10")
    for j, name in enumerate(names):
        xs, ys, hatches = [], [], []
        for i, scene in enumerate(scenes):
            for r in rows:
                if r["scene"] == scene and r["peer"] == name:
                    xs.append(i + (j - len(names) / 2 + 0.5) * width)
                    ys.append(max(1e-3, fnum(r, "frame_ms")))
                    hatches.append("" if r["exact"] == "yes" else "//")
        bars = ax.bar(xs, ys, width, label=name, color=cmap(j % 10))
        for b, h in zip(bars, hatches):
            b.set_hatch(h)
    ax.set_xticks(range(len(scenes)))
    def tick(scene):
        r = next(r for r in rows if r["scene"] == scene)
        return f"{scene} (scale {r['scale']})\n{int(fnum(r, 'triangles'))} tris"

    ax.set_xticklabels([tick(s) for s in scenes], fontsize=8)
    ax.set_yscale("log")
    ax.set_ylabel("ms per frame (peers: deforming, best of refit / rebuild)")
    ax.set_title("cullide methods and peers, same frames (hatched: not exact); " + load_note(rows), fontsize=9)
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(img, dpi=100)
    plt.close(fig)


def figures(data_dir, img_dir):
    os.makedirs(img_dir, exist_ok=True)
    made = []
    p = os.path.join(data_dir, "bench_objects.csv")
    if os.path.exists(p):
        size_vs_time(read_csv(p), "objects", "objects (deforming cylinders, 200 triangles each)",
                     "number of objects vs time", os.path.join(img_dir, "objects_vs_time.png"))
        made.append("objects_vs_time.png")
    p = os.path.join(data_dir, "bench_triangles.csv")
    if os.path.exists(p):
        size_vs_time(read_csv(p), "triangles", "triangles (6 deforming tori)", "number of triangles vs time",
                     os.path.join(img_dir, "triangles_vs_time.png"))
        made.append("triangles_vs_time.png")
    p = os.path.join(data_dir, "sweep.csv")
    if os.path.exists(p):
        sweep_figures(read_csv(p), img_dir)
        made += ["resolution_vs_time.png", "error_vs_time.png"]
    p = os.path.join(data_dir, "peers.csv")
    if os.path.exists(p):
        peers_figure(read_csv(p), os.path.join(img_dir, "peers.png"))
        made.append("peers.png")
    print("plots.py: wrote " + ", ".join(made) if made else "plots.py: no CSV found in " + data_dir)


# ---- the two-bunnies figure -------------------------------------------------------------------

def read_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append(tuple(float(t) for t in line.split()[1:4]))
            elif line.startswith("f "):
                idx = [int(t.split("/")[0]) for t in line.split()[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    faces.append((idx[0], idx[k], idx[k + 1]))
    return verts, faces


def stand_in_blob(n=120):
    verts, faces = [], []
    for i in range(n + 1):
        th = math.pi * i / n
        for j in range(2 * n):
            ph = 2 * math.pi * j / (2 * n)
            r = 0.08 * (1 + 0.15 * math.sin(5 * th) * math.cos(3 * ph))
            verts.append((r * math.sin(th) * math.cos(ph), r * math.cos(th) + 0.1, r * math.sin(th) * math.sin(ph)))
    for i in range(n):
        for j in range(2 * n):
            a, b = i * 2 * n + j, i * 2 * n + (j + 1) % (2 * n)
            c, d = a + 2 * n, b + 2 * n
            if i > 0:
                faces.append((a, b, c))
            if i < n - 1:
                faces.append((b, d, c))
    return verts, faces


def write_obj(path, verts, faces):
    with open(path, "w") as f:
        for v in verts:
            f.write("v %.9g %.9g %.9g\n" % v)
        for t in faces:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def bunnies_input(mesh_dir, out):
    os.makedirs(out, exist_ok=True)
    src = os.path.join(mesh_dir, "stanford-bunny.obj")
    if os.path.exists(src):
        verts, faces = read_obj(src)
        what = src
    else:
        verts, faces = stand_in_blob()
        what = "stand-in blob (no stanford-bunny.obj in " + mesh_dir + ")"
    # The second bunny: turned 40 degrees about the vertical (y) axis and moved by a third of the
    # bunny's width, so the two bodies interpenetrate along a long closed curve.
    xs = [v[0] for v in verts]
    w = max(xs) - min(xs)
    c, s = math.cos(math.radians(40)), math.sin(math.radians(40))
    cx = sum(xs) / len(xs)
    cz = sum(v[2] for v in verts) / len(verts)
    moved = []
    for x, y, z in verts:
        x, z = x - cx, z - cz
        moved.append((c * x + s * z + cx + w / 3, y + 0.01 * w, -s * x + c * z + cz + 0.05 * w))
    write_obj(os.path.join(out, "bunny_a.obj"), verts, faces)
    write_obj(os.path.join(out, "bunny_b.obj"), moved, faces)
    with open(os.path.join(out, "source.txt"), "w") as f:
        f.write(what + "\n")
    print("plots.py: two bunnies from " + what)


def read_pairs(path):
    pairs = set()
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            pairs.add((int(r["object_a"]), int(r["triangle_a"]), int(r["object_b"]), int(r["triangle_b"])))
    return pairs


def bunnies(out, low_path, ref_path, img):
    va, fa = read_obj(os.path.join(out, "bunny_a.obj"))
    vb, fb = read_obj(os.path.join(out, "bunny_b.obj"))
    with open(os.path.join(out, "source.txt")) as f:
        source = f.read().strip()
    low, ref = read_pairs(low_path), read_pairs(ref_path)
    label_low = os.path.basename(low_path).replace("pairs_", "").replace(".csv", "")

    def centroid(v, f, t):
        a, b, c = (v[i] for i in f[t])
        return ((a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3)

    def tris_of(pairs):
        ta = {p[1] for p in pairs}
        return [centroid(va, fa, t) for t in ta]

    found = tris_of(low & ref)
    missed = tris_of(ref - low)
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.2))
    # Silhouettes: a subsample of both bunnies' vertices, front view (x, y).
    step = max(1, len(va) // 6000)
    for ax, title in zip(axes, ["rcullide (never misses)", f"cullide at {label_low}"]):
        ax.scatter([v[0] for v in va[::step]], [v[1] for v in va[::step]], s=0.3, color="0.8")
        ax.scatter([v[0] for v in vb[::step]], [v[1] for v in vb[::step]], s=0.3, color="0.88")
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(title, fontsize=10)
    allref = tris_of(ref)
    axes[0].scatter([p[0] for p in allref], [p[1] for p in allref], s=2, color="tab:blue",
                    label=f"{len(ref)} colliding pairs")
    axes[1].scatter([p[0] for p in found], [p[1] for p in found], s=2, color="tab:blue",
                    label=f"found: {len(low & ref)} pairs")
    axes[1].scatter([p[0] for p in missed], [p[1] for p in missed], s=4, color="tab:red",
                    label=f"missed: {len(ref - low)} pairs")
    for ax in axes:
        ax.legend(fontsize=8, loc="lower left", markerscale=4)
    fig.suptitle("two interpenetrating bunnies: intersection curve (first bunny's triangles of the colliding "
                 "pairs)\n" + source, fontsize=9)
    fig.tight_layout()
    fig.savefig(img, dpi=110)
    plt.close(fig)
    print(f"plots.py: bunnies: rcullide {len(ref)} pairs, cullide {len(low)} ({len(ref - low)} missed)")


# ---- markdown tables ---------------------------------------------------------------------------

def fmt_ms(x):
    return f"{x:.3g}" if x < 100 else f"{x:.0f}"


def tables(data_dir):
    """Prints the markdown tables of docs/results.md from the CSVs (results.sh writes them to
    docs/data/tables.md)."""
    out = []
    p = os.path.join(data_dir, "bench_scenes.csv")
    if os.path.exists(p):
        rows = read_csv(p)
        out.append("### Scenes: every method, same frames (`cullide bench`)\n")
        out.append("| scene | scale | objects | triangles | method | resolution | ms / frame (median) | min-max | fps | pairs / frame | misses / frame | check |")
        out.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            fr = max(1.0, fnum(r, "frames", 1))
            scene = r["scene"] + (" (self)" if r.get("self") == "1" else "")
            out.append(f"| {scene} | {r['scale']} | {fnum(r, 'objects'):.0f} | {fnum(r, 'triangles'):.0f} | {r['method']} | "
                       f"{r['resolution'] or '-'} | {fmt_ms(fnum(r, 'ms_median'))} | {fmt_ms(fnum(r, 'ms_min'))}-{fmt_ms(fnum(r, 'ms_max'))} | "
                       f"{1000.0 / max(1e-9, fnum(r, 'ms_median')):.1f} | {fnum(r, 'truth_pairs') / fr:.0f} | "
                       f"{fnum(r, 'false_negatives') / fr:.1f} | {r['check']} |")
        out.append("")
    p = os.path.join(data_dir, "peers.csv")
    if os.path.exists(p):
        rows = read_csv(p)
        out.append("### Peers side by side (`peers_bench`), ms per frame (medians)\n")
        out.append("| scene | scale | triangles | method / peer | build | refit | query (rigid) | deforming frame | pairs / truth | result |")
        out.append("|---|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            ours = r["build_ms"] == ""
            res = "exact" if r["exact"] == "yes" else (
                f"**not exact**: {r['misses']} missed, {r['extra']} extra" +
                ("" if ours else f" (after refit {r['refit_misses']} / {r['refit_extra']})"))
            refit = "-" if ours else fmt_ms(fnum(r, "refit_ms")) + (" (rebuild)" if r["refit_is_rebuild"] == "1" else "")
            out.append(f"| {r['scene']} | {r['scale']} | {fnum(r, 'triangles'):.0f} | {r['peer']} | "
                       f"{'-' if ours else fmt_ms(fnum(r, 'build_ms'))} | {refit} | "
                       f"{'-' if ours else fmt_ms(fnum(r, 'query_ms'))} | {fmt_ms(fnum(r, 'frame_ms'))} | "
                       f"{r['pairs']} / {r['truth_pairs']} | {res} |")
        out.append("")
        # Goals: the never-miss default (auto) at or below 0.5x the fastest exact peer of each scene
        # (issue #16), and rcullide at or below it.
        out.append("### Goal: the default (auto) at or below 0.5x, rcullide at or below 1x the best exact peer (deforming frames)\n")
        out.append("| scene | method (resolution) ms | best exact peer | its ms | method / peer | goal | exact (ground truth) ms | reached |")
        out.append("|---|---|---|---|---|---|---|---|")
        for scene, rs in by(rows, "scene").items():
            gt = [r for r in rs if r["peer"] == "exact"]
            peers = [r for r in rs if r["build_ms"] != "" and r["exact"] == "yes"]
            if not peers:
                continue
            best = min(peers, key=lambda r: fnum(r, "frame_ms"))
            for method, goal in (("auto", 0.5), ("rcullide", 1.0)):
                rc = [r for r in rs if r["peer"].split("@")[0] == method]
                if not rc:
                    continue
                ratio = fnum(rc[0], "frame_ms") / max(1e-9, fnum(best, "frame_ms"))
                ok = "yes" if ratio <= goal and rc[0]["exact"] == "yes" else "no"
                out.append(f"| {scene} | {rc[0]['peer']}: {fmt_ms(fnum(rc[0], 'frame_ms'))} | {best['peer']} | {fmt_ms(fnum(best, 'frame_ms'))} | "
                           f"{ratio:.1f}x | <= {goal}x | {fmt_ms(fnum(gt[0], 'frame_ms')) if gt else '-'} | {ok} |")
        out.append("")
    p = os.path.join(data_dir, "sweep.csv")
    if os.path.exists(p):
        rows = read_csv(p)
        out.append("### Goal: cullide at the resolution where its misses reach zero (`cullide sweep`, d24)\n")
        out.append("| scene | scale | colliding pairs / frame | misses / frame at each resolution | first resolution with 0 misses | ms / frame there | rcullide ms at that resolution |")
        out.append("|---|---|---|---|---|---|---|")
        for scene, rs in by(rows, "scene").items():
            cu = sorted([r for r in rs if r["method"] == "cullide" and r["depth_format"] == "d24"],
                        key=lambda r: fnum(r, "resolution"))
            if not cu:
                continue
            fr = max(1.0, fnum(cu[0], "frames", 1))
            misses = ", ".join(f"{r['resolution']}: {fnum(r, 'false_negatives') / fr:.0f}" for r in cu)
            zero = [r for r in cu if fnum(r, "false_negatives") == 0]
            if zero:
                z = zero[0]
                rc = [r for r in rs if r["method"] == "rcullide" and r["depth_format"] == "d24" and r["resolution"] == z["resolution"]]
                out.append(f"| {scene} | {cu[0]['scale']} | {fnum(cu[0], 'truth_pairs') / fr:.0f} | {misses} | {z['resolution']} | "
                           f"{fmt_ms(fnum(z, 'ms_mean'))} | {fmt_ms(fnum(rc[0], 'ms_mean')) if rc else '-'} |")
            else:
                out.append(f"| {scene} | {cu[0]['scale']} | {fnum(cu[0], 'truth_pairs') / fr:.0f} | {misses} | not reached (max {cu[-1]['resolution']}) | - | - |")
        out.append("")
    print("\n".join(out))


# ---- goal tables of the speed issues (scripts/results.sh --goals) --------------------------------

def load_lines(goals_dir):
    p = os.path.join(goals_dir, "load.txt")
    return open(p).read().strip().splitlines() if os.path.exists(p) else []


def ratio_range(values):
    return f"{min(values):.2f}-{max(values):.2f}x" if values else "-"


def goals(goals_dir):
    """Prints the goal tables of issues #16 and #17 from peers.csv, threads.csv, self.csv,
    pipeline_bench.json and raster_bench.json (each written by one run of scripts/results.sh
    --goals); 'yes' / 'no' says whether each row reaches its goal."""
    import json
    out = []
    loads = load_lines(goals_dir)
    if loads:
        out.append("Runs (`scripts/results.sh --goals`; the load average before each run):\n")
        out.extend(f"    {line}" for line in loads)
        out.append("")
    yes = lambda ok: "yes" if ok else "**no**"
    # #16, peers side by side at 2 threads.
    p = os.path.join(goals_dir, "peers.csv")
    if os.path.exists(p):
        rows = read_csv(p)
        out.append("### Issue #16: never-miss methods against the best exact peer (`peers_bench`, 2 threads, ms per deforming frame)\n")
        out.append("| scene | best exact peer ms | exact ms (/ peer, goal <= 1x) | auto ms (/ peer, goal <= 0.5x) | rcullide ms (/ exact, goal < 1x where boxes are loose) | qcullide ms |")
        out.append("|---|---|---|---|---|---|")
        summary = {"exact": [], "auto": [], "rcullide": []}
        for scene, rs in by(rows, "scene").items():
            peers = [r for r in rs if r["build_ms"] != "" and r["exact"] == "yes"]
            mine = {r["peer"].split("@")[0]: r for r in rs if r["build_ms"] == ""}
            if not peers or "exact" not in mine:
                continue
            best = min(peers, key=lambda r: fnum(r, "frame_ms"))
            bms = fnum(best, "frame_ms")
            ex = fnum(mine["exact"], "frame_ms")
            cells = [f"{best['peer']} {fmt_ms(bms)}", f"{fmt_ms(ex)} ({ex / bms:.2f}x, {yes(ex <= bms and mine['exact']['exact'] == 'yes')})"]
            summary["exact"].append(ex <= bms)
            if "auto" in mine:
                a = fnum(mine["auto"], "frame_ms")
                ok = a <= 0.5 * bms and mine["auto"]["exact"] == "yes"
                summary["auto"].append(ok)
                cells.append(f"{fmt_ms(a)} ({a / bms:.2f}x, {yes(ok)})")
            else:
                cells.append("-")
            if "rcullide" in mine:
                rc = fnum(mine["rcullide"], "frame_ms")
                loose = scene in ("tori", "bunny-dragon", "breaking", "cloth")
                goal = ""
                if loose:
                    goal = f", {yes(rc < ex)}"
                    summary["rcullide"].append(rc < ex)
                if scene == "cylinders":
                    goal = f"; goal <= 1 ms: {yes(rc <= 1.0)}"
                cells.append(f"{fmt_ms(rc)} ({rc / ex:.2f}x{goal})")
            else:
                cells.append("-")
            cells.append(fmt_ms(fnum(mine["qcullide"], "frame_ms")) if "qcullide" in mine else "-")
            out.append(f"| {scene} | " + " | ".join(cells) + " |")
        out.append("")
        out.append("Reached on: " + ", ".join(f"{k} {sum(v)} of {len(v)} scenes" for k, v in summary.items() if v) + ".\n")
    # #16, 1 -> 2 threads.
    p = os.path.join(goals_dir, "threads.csv")
    if os.path.exists(p):
        rows = read_csv(p)
        out.append("### Issue #16: 1 -> 2 threads (`cullide bench --threads 1,2`, ms per frame, medians; goal >= 1.8x)\n")
        out.append("| scene | method | 1 thread | 2 threads | 2 / 1 | reached |")
        out.append("|---|---|---|---|---|---|")
        speedups = []
        for (scene, method), rs in by_pair(rows, "scene", "method").items():
            t = {r["threads"]: fnum(r, "ms_median") for r in rs}
            if "1" not in t or "2" not in t:
                continue
            sp = t["1"] / max(1e-9, t["2"])
            speedups.append(sp)
            out.append(f"| {scene} | {method} | {fmt_ms(t['1'])} | {fmt_ms(t['2'])} | {sp:.2f}x | {yes(sp >= 1.8)} |")
        out.append("")
        out.append(f"2 / 1: {ratio_range(speedups)}; >= 1.8x on {sum(x >= 1.8 for x in speedups)} of {len(speedups)} rows.\n")
    # #16, self-collision on the folded cloth.
    p = os.path.join(goals_dir, "self.csv")
    if os.path.exists(p):
        rows = read_csv(p)
        t = {(r["method"], r["threads"]): r for r in rows}
        if all(k in t for k in (("exact", "1"), ("exact", "2"), ("qcullide", "1"), ("qcullide", "2"))):
            ms = {k: fnum(v, "ms_median") for k, v in t.items()}
            out.append("### Issue #16: self-collision on the folded cloth (`cullide bench --self`, frames 55-56, ms per frame)\n")
            out.append("| threads | exact --self | qcullide --self | qcullide / exact (goal <= 0.5x) | exact tests, exact / qcullide |")
            out.append("|---|---|---|---|---|")
            for th in ("1", "2"):
                r = ms[("qcullide", th)] / ms[("exact", th)]
                out.append(f"| {th} | {fmt_ms(ms[('exact', th)])} | {fmt_ms(ms[('qcullide', th)])} | {r:.2f}x ({yes(r <= 0.5)}) | "
                           f"{t[('exact', th)]['exact_tests']} / {t[('qcullide', th)]['exact_tests']} |")
            sp = ms[("qcullide", "1")] / ms[("qcullide", "2")]
            out.append("")
            out.append(f"qcullide --self 1 -> 2 threads: {sp:.2f}x (goal >= 1.8x: {yes(sp >= 1.8)}).\n")
    # #17, the GL-exact passes on the emulator against OSMesa.
    p = os.path.join(goals_dir, "pipeline_bench.json")
    if os.path.exists(p):
        doc = json.load(open(p))
        t = {}
        for b in doc.get("benchmarks", []):
            parts = b["name"].split("/")  # pipeline/<scene>@<scale>/<method>/<device>/threads:N/...
            if len(parts) < 5 or b.get("run_type") != "iteration":
                continue
            t[(parts[1], parts[2], parts[3], parts[4])] = b["real_time"]
        keys = []
        for (scene, method, device, th) in t:
            if device == "osmesa" and (scene, method) not in keys:
                keys.append((scene, method))
        out.append("### Issue #17: GL-exact passes, emulator against OSMesa llvmpipe (`pipeline_bench`, ms per frame)\n")
        out.append(f"Load average in the benchmark's context: {doc.get('context', {}).get('load_avg', '?')}.\n")
        out.append("| scene / method | emulator 1 / 2 threads | 2 / 1 (goal >= 1.8x) | OSMesa | OSMesa / emulator at 2 threads (goal >= 20x) |")
        out.append("|---|---|---|---|---|")
        fast, scale = [], []
        for scene, method in keys:
            e1 = t.get((scene, method, "emulator", "threads:1"))
            e2 = t.get((scene, method, "emulator", "threads:2"))
            om = t.get((scene, method, "osmesa", "threads:2"))
            if e1 is None or e2 is None or om is None:
                continue
            sp, r = e1 / e2, om / e2
            fast.append(r)
            scale.append(sp)
            out.append(f"| {scene.split('@')[0]} / {method} | {fmt_ms(e1)} / {fmt_ms(e2)} | {sp:.2f}x ({yes(sp >= 1.8)}) | "
                       f"{fmt_ms(om)} | {r:.1f}x ({yes(r >= 20)}) |")
        out.append("")
        out.append(f"OSMesa / emulator {ratio_range(fast)}, 20x on {sum(x >= 20 for x in fast)} of {len(fast)} rows; "
                   f"1 -> 2 threads {ratio_range(scale)}, 1.8x on {sum(x >= 1.8 for x in scale)} of {len(scale)} rows.\n")
    # #17, fill rate against llvmpipe.
    p = os.path.join(goals_dir, "raster_bench.json")
    if os.path.exists(p):
        doc = json.load(open(p))
        t = {}
        for b in doc.get("benchmarks", []):
            parts = b["name"].split("/")  # run/<workload>/<size>/<threads>/<simd>/real_time
            if parts[0] != "run" or len(parts) < 5 or b.get("run_type") != "iteration":
                continue
            t.setdefault((parts[1], int(parts[2]), int(parts[3]), int(parts[4])), []).append(b["real_time"])
        reps = max((len(v) for v in t.values()), default=0)
        t = {k: sorted(v)[len(v) // 2] for k, v in t.items()}  # the median of the repetitions
        out.append("### Issue #17: raster throughput against OSMesa llvmpipe (`raster_bench`, ms per batch, "
                   f"median of {reps} repetitions)\n")
        out.append(f"Load average in the benchmark's context: {doc.get('context', {}).get('load_avg', '?')}. "
                   "Goals: LargeTris >= 2x, SmallTris >= 4x llvmpipe at 2 threads.\n")
        out.append("| workload | size | OSMesa | ours 1 thread (portable) | ours 2 threads | OSMesa / ours at 1 / 2 threads | 2 / 1 | goal |")
        out.append("|---|---|---|---|---|---|---|---|")
        workloads = []
        for (w, size, th, simd) in t:
            if w not in workloads:
                workloads.append(w)
        for w in workloads:
            for size in sorted({k[1] for k in t if k[0] == w}):
                one, two = t.get((w, size, 1, 1)), t.get((w, size, 2, 1))
                if one is None or two is None:
                    continue
                port = t.get((w, size, 1, 0))
                # OSMesa runs the plain workloads only; the clear variants compare with theirs.
                base = {"SmallTrisRestore": "SmallTris", "SmallTrisFullClear": "SmallTris",
                        "LargeTrisRestore": "LargeTris"}.get(w, w)
                om = t.get((base, size, 0, 1))
                goal = {"LargeTris": 2.0, "SmallTris": 4.0}.get(w)
                ratio = f"{om / one:.1f}x / {om / two:.1f}x" if om else "-"
                reached = (f">= {goal:g}x: {yes(om / two >= goal)}" if goal and om else "-")
                out.append(f"| {w} | {size}^2 | {fmt_ms(om) if om else '-'} | {fmt_ms(one)}" +
                           (f" ({fmt_ms(port)})" if port else "") + f" | {fmt_ms(two)} | {ratio} | {one / two:.2f}x | {reached} |")
        out.append("")
        out.append("OSMesa is llvmpipe with its own threads (the row's thread count does not apply to it); the "
                   "Restore and FullClear rows are compared with the OSMesa time of their workload.\n")
    print("\n".join(out))


def main(argv):
    if len(argv) >= 4 and argv[1] == "figures":
        figures(argv[2], argv[3])
    elif len(argv) >= 4 and argv[1] == "bunnies-input":
        bunnies_input(argv[2], argv[3])
    elif len(argv) >= 3 and argv[1] == "tables":
        tables(argv[2])
    elif len(argv) >= 3 and argv[1] == "goals":
        goals(argv[2])
    elif len(argv) >= 6 and argv[1] == "bunnies":
        bunnies(argv[2], argv[3], argv[4], argv[5])
    else:
        sys.stderr.write(__doc__)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
