#!/usr/bin/env python3
"""Figures of docs/hunt.md, as plain SVG (no plotting package needed).

usage:
  scripts/hunt_figures.py views FINDING_DIR OUT.svg TITLE   the finding's objects seen along x, y and z
                                                            (the axis views CULLIDE renders); the
                                                            triangles of missed pairs in red
  scripts/hunt_figures.py room DATA_CSV OUT.svg             share of true pairs missed on room frames,
                                                            per method and resolution (docs/data/hunt_room.csv)
"""
import csv
import glob
import os
import sys

COLOURS = ["#4c72b0", "#55a868", "#c44e52", "#8172b2", "#ccb974", "#64b5cd", "#8c8c8c", "#e377c2", "#17becf"]


def read_obj(path):
    verts, tris = [], []
    for line in open(path):
        p = line.split()
        if not p:
            continue
        if p[0] == "v":
            verts.append(tuple(float(x) for x in p[1:4]))
        elif p[0] == "f":
            tris.append(tuple(int(x.split("/")[0]) - 1 for x in p[1:4]))
    return [(verts[a], verts[b], verts[c]) for a, b, c in tris]


def views(finding, out, title):
    files = sorted(glob.glob(os.path.join(finding, "object_*.obj")), key=lambda f: int(f.split("_")[-1][:-4]))
    objects = [read_obj(f) for f in files]
    missed = set()
    with open(os.path.join(finding, "pairs.csv")) as f:
        for row in csv.DictReader(f):
            missed.add((int(row["object_a"]), int(row["triangle_a"])))
            missed.add((int(row["object_b"]), int(row["triangle_b"])))
    pts = [p for o in objects for t in o for p in t]
    lo = [min(p[k] for p in pts) for k in range(3)]
    hi = [max(p[k] for p in pts) for k in range(3)]
    size, pad, top = 260, 20, 40
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{3 * (size + pad) + pad}" height="{size + top + 2 * pad}" '
           f'font-family="sans-serif" font-size="13">',
           f'<rect width="100%" height="100%" fill="white"/>',
           f'<text x="{pad}" y="22" font-size="15">{title}</text>']
    for panel, axis in enumerate((0, 1, 2)):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        x0 = pad + panel * (size + pad)
        y0 = top
        span = max(hi[u] - lo[u], hi[v] - lo[v], 1e-300)

        def to_px(p):
            return (x0 + 10 + (p[u] - lo[u]) / span * (size - 20), y0 + size - 10 - (p[v] - lo[v]) / span * (size - 20))

        svg.append(f'<rect x="{x0}" y="{y0}" width="{size}" height="{size}" fill="none" stroke="#999"/>')
        svg.append(f'<text x="{x0 + 4}" y="{y0 + size + 16}">view along {"xyz"[axis]} '
                   f'(right {"xyz"[u]}, up {"xyz"[v]})</text>')
        for oi, obj in enumerate(objects):
            for ti, tri in enumerate(obj):
                red = (oi, ti) in missed
                colour = "#d62728" if red else COLOURS[oi % len(COLOURS)]
                poly = " ".join(f"{x:.2f},{y:.2f}" for x, y in map(to_px, tri))
                # An edge-on triangle is a segment here: drawn as a thick line so it can be seen.
                svg.append(f'<polygon points="{poly}" fill="{colour}" fill-opacity="{0.45 if red else 0.2}" '
                           f'stroke="{colour}" stroke-width="{2.5 if red else 1}"/>')
    svg.append("</svg>")
    with open(out, "w") as f:
        f.write("\n".join(svg) + "\n")


def room(data, out):
    rows = list(csv.DictReader(open(data)))
    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])
    resolutions = sorted({int(r["resolution"]) for r in rows})
    depths = sorted({r["depth"] for r in rows})
    bar, gap, chart_h, left, top = 14, 26, 200, 60, 50
    group_w = len(resolutions) * len(depths) * bar + gap
    width = left + len(methods) * group_w + 40
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{chart_h + top + 90}" '
           f'font-family="sans-serif" font-size="12">', '<rect width="100%" height="100%" fill="white"/>',
           f'<text x="{left}" y="22" font-size="15">Room frames: share of true colliding pairs missed</text>']
    for k in range(0, 101, 25):
        y = top + chart_h - chart_h * k / 100
        svg.append(f'<line x1="{left}" y1="{y}" x2="{width - 30}" y2="{y}" stroke="#ddd"/>')
        svg.append(f'<text x="{left - 8}" y="{y + 4}" text-anchor="end">{k}%</text>')
    shades = ["#08306b", "#2171b5", "#6baed6", "#c6dbef"]
    for mi, m in enumerate(methods):
        x = left + 10 + mi * group_w
        for ri, res in enumerate(resolutions):
            for di, d in enumerate(depths):
                r = [r for r in rows if r["method"] == m and int(r["resolution"]) == res and r["depth"] == d]
                if not r:
                    continue
                true, missed = int(r[0]["true_pairs"]), int(r[0]["missed_pairs"])
                share = missed / true if true else 0
                h = chart_h * share
                bx = x + (ri * len(depths) + di) * bar
                fill = shades[ri % len(shades)]
                svg.append(f'<rect x="{bx}" y="{top + chart_h - h}" width="{bar - 2}" height="{max(h, 0.5)}" '
                           f'fill="{fill}" fill-opacity="{1.0 if di == 0 else 0.55}"/>')
        svg.append(f'<text x="{x + (group_w - gap) / 2}" y="{top + chart_h + 18}" text-anchor="middle">{m}</text>')
    ly = top + chart_h + 40
    for ri, res in enumerate(resolutions):
        lx = left + ri * 150
        svg.append(f'<rect x="{lx}" y="{ly}" width="12" height="12" fill="{shades[ri % len(shades)]}"/>')
        svg.append(f'<text x="{lx + 16}" y="{ly + 11}">{res} px ({", ".join(depths)} side by side)</text>')
    svg.append("</svg>")
    with open(out, "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "views":
        views(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) == 4 and sys.argv[1] == "room":
        room(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)
