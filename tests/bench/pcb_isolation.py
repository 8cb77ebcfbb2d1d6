#!/usr/bin/env python3
"""A PCB isolation-milling program of the kind FlatCAM writes, for measuring fine-tool runs.

Isolation passes around pads (rectangles, circles as G2 arcs) and traces between them on a
board; a 0.2 mm tool 0.05 mm deep by default. The board is --width x --height mm; the pads lie
on a grid of --pitch mm. Deterministic (seeded).

usage: pcb_isolation.py [--width 40] [--height 30] [--pitch 2.54] [--tool 0.2] [--depth 0.05]
                        [--seed 1] > board.ngc
then: engage simulate board.ngc --tool flat --diameter 0.2mm --stock box:0,0,-1.6,W,H,0
"""
import argparse
import math
import random


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--width", type=float, default=40.0)
    ap.add_argument("--height", type=float, default=30.0)
    ap.add_argument("--pitch", type=float, default=2.54)
    ap.add_argument("--tool", type=float, default=0.2)
    ap.add_argument("--depth", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    rnd = random.Random(a.seed)
    r = a.tool / 2.0
    out = ["(PCB isolation, tool %.3f mm, depth %.3f mm)" % (a.tool, a.depth),
           "G21 G90 G17 G94", "F120", "G0 Z1.0"]

    def cut(path):
        """One closed or open isolation pass through the points (x, y[, arc centre])."""
        x0, y0 = path[0][:2]
        out.append("G0 X%.4f Y%.4f" % (x0, y0))
        out.append("G1 Z%.4f F60" % -a.depth)
        out.append("F120")
        for p in path[1:]:
            if len(p) == 2:
                out.append("G1 X%.4f Y%.4f" % p)
            else:
                out.append("G2 X%.4f Y%.4f I%.4f J%.4f" % p)
        out.append("G0 Z1.0")

    nx = int((a.width - 4) // a.pitch)
    ny = int((a.height - 4) // a.pitch)
    pads = []
    for i in range(nx):
        for j in range(ny):
            if rnd.random() < 0.45:
                continue
            cx, cy = 2 + (i + 0.5) * a.pitch, 2 + (j + 0.5) * a.pitch
            pads.append((cx, cy))
            if rnd.random() < 0.5:  # a round pad: one full circle, offset by the tool radius
                rr = 0.6 + r
                cut([(cx + rr, cy), (cx + rr, cy, -rr, 0.0)])
            else:  # a square pad
                h = 0.65 + r
                cut([(cx - h, cy - h), (cx + h, cy - h), (cx + h, cy + h), (cx - h, cy + h),
                     (cx - h, cy - h)])
    # Traces: both sides of a 0.3 mm track between neighbouring pads, with a 45-degree jog.
    for (x0, y0), (x1, y1) in zip(pads, pads[1:]):
        if math.hypot(x1 - x0, y1 - y0) > 3 * a.pitch:
            continue
        for side in (-1, 1):
            off = side * (0.15 + r)
            mx = x0 + (x1 - x0) / 2
            cut([(x0 + 0.9, y0 + off), (mx, y0 + off), (mx + (y1 - y0) / 2, y1 + off),
                 (x1 - 0.9, y1 + off)])
    out += ["G0 Z5", "M2"]
    print("\n".join(out))


if __name__ == "__main__":
    main()
