#!/usr/bin/env python3
"""Figures of docs/hunt.md, as plain SVG (no plotting package needed).

The room figures: OUT=/tmp/x; cullide hunt --method cullide --generators room --cases 1
--shrink-checks 0 --out $OUT/full, and the same without --shrink-checks 0 into $OUT/shrunk; then
`views $OUT/full/finding-001 ...` and `views $OUT/shrunk/finding-001 ...`.

usage:
  scripts/hunt_figures.py views FINDING_DIR OUT.svg TITLE   the finding's objects seen along x, y and z
                                                            (the axis views CULLIDE renders), one
                                                            colour per object; the triangles of
                                                            missed pairs outlined in red
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
                colour = COLOURS[oi % len(COLOURS)]
                poly = " ".join(f"{x:.2f},{y:.2f}" for x, y in map(to_px, tri))
                # Filled in the object's colour, outlined in red when in a missed pair. An edge-on
                # triangle is a segment here, still drawn by its outline.
                svg.append(f'<polygon points="{poly}" fill="{colour}" fill-opacity="0.25" '
                           f'stroke="{"#d62728" if red else colour}" stroke-width="{2 if red else 1}"/>')
    svg.append("</svg>")
    with open(out, "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "views":
        views(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        sys.exit(__doc__)
