#!/usr/bin/env python3
"""Loads an irslam PGM map back with a real reader (Pillow + NumPy) and checks it
against the map JSON it was drawn from: every occupied pixel lies within one cell
of a mapped line, every mapped line is drawn (an occupied pixel within one cell of
each point along it), the room's centre is free and the corners outside are unknown.
  pgm_check.py MAP.json MAP.pgm      (MAP.yaml beside MAP.pgm)
Exit 0: good; 1: a check failed; 77: Pillow or NumPy missing (ctest: skipped)."""
import json
import math
import os
import sys

try:
    import numpy as np
    from PIL import Image
except ImportError as e:
    print(f"pgm_check: skipped: {e} (apt-get install python3-pil python3-numpy)")
    sys.exit(77)


def read_yaml(path):
    """map_server's flat YAML (key: value, origin as [x, y, theta])."""
    out = {}
    with open(path) as f:
        for line in f:
            key, _, value = line.partition(":")
            value = value.strip()
            out[key.strip()] = json.loads(value) if value.startswith("[") else value
    return out


def seg_dist(px, py, x0, y0, x1, y1):
    dx, dy = x1 - x0, y1 - y0
    n = dx * dx + dy * dy
    s = 0.0 if n == 0 else max(0.0, min(1.0, ((px - x0) * dx + (py - y0) * dy) / n))
    return math.hypot(px - (x0 + s * dx), py - (y0 + s * dy))


def main():
    map_path, pgm_path = sys.argv[1], sys.argv[2]
    with open(map_path) as f:
        m = json.load(f)
    meta = read_yaml(os.path.splitext(pgm_path)[0] + ".yaml")
    res = float(meta["resolution"])
    ox, oy, _ = meta["origin"]
    assert meta["image"] == os.path.basename(pgm_path), meta
    assert float(meta["occupied_thresh"]) == 0.65 and float(meta["free_thresh"]) == 0.196
    assert int(meta["negate"]) == 0
    img = Image.open(pgm_path)
    assert img.format == "PPM" and img.mode == "L", (img.format, img.mode)
    a = np.asarray(img)
    h, w = a.shape
    # map_server's reading (negate 0): occupancy = (255 - p) / 255.
    occ = (255.0 - a) / 255.0
    occupied = occ > 0.65
    free = occ < 0.196
    segs = [(l["p0"][0], l["p0"][1], l["p1"][0], l["p1"][1]) for l in m["lines"]]
    assert segs, "no lines in the map"

    def centre(row, col):
        return ox + (col + 0.5) * res, oy + (h - 1 - row + 0.5) * res

    worst = 0.0
    rows, cols = np.nonzero(occupied)
    for r, c in zip(rows, cols):
        x, y = centre(r, c)
        worst = max(worst, min(seg_dist(x, y, *s) for s in segs))
    # A cell is "within one cell" of a line when its centre is at most one cell away.
    if worst > res:
        print(f"pgm_check: an occupied cell lies {worst:.3f} m from every line (cell {res} m)")
        return 1
    missed = 0
    for x0, y0, x1, y1 in segs:
        n = max(1, int(math.hypot(x1 - x0, y1 - y0) / (0.5 * res)))
        for i in range(n + 1):
            x, y = x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n
            col, row = int((x - ox) / res), h - 1 - int((y - oy) / res)
            win = occupied[max(0, row - 1):row + 2, max(0, col - 1):col + 2]
            missed += not win.any()
    if missed:
        print(f"pgm_check: {missed} points along the lines have no occupied cell within one cell")
        return 1
    box = m["room"]["box"]
    cx, cy = (box[0] + box[2]) / 2, (box[1] + box[3]) / 2
    inside_free = free[h - 1 - int((cy - oy) / res), int((cx - ox) / res)] or any(
        free[h - 1 - int((y - oy) / res), int((x - ox) / res)]
        for x, y in [(box[0] + 0.3, box[1] + 0.3), (box[2] - 0.3, box[3] - 0.3)])
    unknown_corners = all(not occupied[r, c] and not free[r, c] for r, c in [(0, 0), (0, w - 1), (h - 1, 0), (h - 1, w - 1)])
    print(f"pgm_check: {w}x{h} cells of {res} m, {int(occupied.sum())} occupied, {int(free.sum())} free; "
          f"worst occupied cell {worst:.3f} m from a line; all {len(segs)} lines drawn")
    if not inside_free or not unknown_corners:
        print(f"pgm_check: room inside free: {inside_free}, corners unknown: {unknown_corners}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
