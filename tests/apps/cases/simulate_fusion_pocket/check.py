"""Fusion 360's pocket against a volume computed here, not by engage's stocks.

The program's moves as engage reads them (`engage moves`, whose reading is checked against
LinuxCNC's rs274 elsewhere) are swept by the flat 6 mm end mill over a 0.025 mm grid of
points of the stock's top: each point is cut down to the lowest tip height of the moves whose
XY trace passes within the radius (lines and arcs exactly, by their distance to the point);
the removed volume is the sum of those depths times the cell's area. The grid's error is far
below the 0.1 % bound checked (a cell's half width along 250 mm of boundary, at random: about
1e-5).
"""
import csv
import io
import json
import math
import os
import subprocess
import sys

import numpy as np

out, data, engage = sys.argv[1:4]
R = 3.0
H = 0.025
text = subprocess.run([engage, "moves", os.path.join(data, "gcode/dialects/fusion360_pocket.nc")],
                      capture_output=True, text=True, check=True).stdout
moves = list(csv.DictReader(io.StringIO(text)))
# The grid: the stock's top (0..60 mm square) where the cutting moves reach, on cell centres.
cutting = [m for m in moves if m["kind"] != "rapid" and float(m["z"]) < 0.0]
lo = [max(0.0, min(float(m[a]) for m in cutting) - 2 * R) for a in "xy"]
hi = [min(60.0, max(float(m[a]) for m in cutting) + 2 * R) for a in "xy"]
X, Y = np.meshgrid(np.arange(math.floor(lo[0] / H) * H + H / 2, hi[0], H),
                   np.arange(math.floor(lo[1] / H) * H + H / 2, hi[1], H), indexing="ij")
lowest = np.zeros_like(X)  # the stock's top, Z0

start = None
for m in moves:
    end = np.array([float(m["x"]), float(m["y"]), float(m["z"])])
    if start is not None and m["kind"] != "rapid" and min(start[2], end[2]) < 0.0:
        z = min(start[2], end[2])
        if m["kind"] == "line":
            d = end[:2] - start[:2]
            L2 = d @ d
            t = np.clip(((X - start[0]) * d[0] + (Y - start[1]) * d[1]) / L2, 0, 1) if L2 > 0 else 0
            dist = np.hypot(X - start[0] - t * d[0], Y - start[1] - t * d[1])
        else:  # an arc in XY about (cx, cy), counter-clockwise when turns > 0
            cx, cy = float(m["cx"]), float(m["cy"])
            ccw = float(m["turns"]) > 0
            radius = math.hypot(start[0] - cx, start[1] - cy)
            a0 = math.atan2(start[1] - cy, start[0] - cx)
            a1 = math.atan2(end[1] - cy, end[0] - cx)
            sweep = (a1 - a0) % (2 * math.pi) if ccw else (a0 - a1) % (2 * math.pi)
            if sweep < 1e-12:
                sweep = 2 * math.pi  # a full circle
            ang = np.arctan2(Y - cy, X - cx)
            along = ((ang - a0) if ccw else (a0 - ang)) % (2 * math.pi)
            on = np.abs(np.hypot(X - cx, Y - cy) - radius)
            ends = np.minimum(np.hypot(X - start[0], Y - start[1]), np.hypot(X - end[0], Y - end[1]))
            dist = np.where(along <= sweep, on, ends)
        lowest = np.where(dist <= R, np.minimum(lowest, z), lowest)
    start = end
volume = float(-lowest.sum()) * H * H

with open(os.path.join(out, "summary.json")) as f:
    removed = json.load(f)["removed"]
print(f"removed {removed} mm^3 against {volume:.3f} mm^3 (swept on a {H} mm grid)")
# The project's bound for a program's total at the default cell: 0.1 %.
if abs(removed / volume - 1.0) > 1e-3:
    print("more than 0.1 % apart")
    sys.exit(1)
