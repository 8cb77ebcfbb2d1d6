#!/usr/bin/env python3
"""Random cutter-compensation programs, interpreted by engage and by LinuxCNC's rs274.

Each seed writes a program: a tool from data/gcode/linuxcnc/tools.tbl, G41 or G42 (or
G41.1/G42.1 with a random diameter), mm or inch, a lead-in (a straight entry, or a straight
entry and a tangent arc of random radius, larger or smaller than the tool), then 3-12 moves:
straight moves turning by random angles and arcs either way, tangent or not, radii from below
the tool's to many times it; a lead-out arc or straight and G40. Both interpreters run it:

  OK      both ran, the moves agree within --tol (mm)
  REFUSED both refused it
  DIFFER  both ran, the moves differ
  ONLY-LINUXCNC / ONLY-ENGAGE  one refused, the other ran

  scripts/comp_campaign.py [--engage build/apps/engage] [--seeds 1-500] [--keep DIR]

Exit status 1 when any seed is DIFFER or ONLY-*. Needs rs274 (Debian package linuxcnc-uspace).
"""
import argparse
import math
import os
import random
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compare_linuxcnc as cl  # noqa: E402

TOOLS = {1: 0.125, 2: 0.0625, 4: 0.5, 5: 0.25}  # inch diameters in tools.tbl


def fmt(v):
    return ("%.4f" % v).rstrip("0").rstrip(".") if abs(v) > 5e-5 else "0"


def program(seed):
    rng = random.Random(seed)
    inch = rng.random() < 0.5
    unit = 1.0 if inch else 25.4  # program units per inch
    tool = rng.choice(list(TOOLS))
    r = TOOLS[tool] / 2 * unit
    dynamic = rng.random() < 0.15
    if dynamic:
        r = rng.uniform(0.02, 0.3) * unit
    side = rng.choice(["41", "42"])
    left = side == "41"
    out = ["G20" if inch else "G21", "G90 G17 G40 G49 G80 G94", "T%d M6" % tool, "G43 H%d" % tool,
           "S5000 M3", "G0 X0 Y0 Z%s" % fmt(0.5 * unit)]
    x, y = 0.0, 0.0
    heading = rng.uniform(0, 2 * math.pi)
    z = -0.1 * unit
    out.append("G1 Z%s F%s" % (fmt(z), fmt(10 * unit)))
    comp = ("G%s.1 D%s" % (side, fmt(2 * r))) if dynamic else ("G%s D%d" % (side, tool))
    # The entry: a straight move of 1.1-4 radii (one in ten shorter than one: refused by both).
    length = r * (rng.uniform(0.3, 1.0) if rng.random() < 0.1 else rng.uniform(1.1, 4.0))
    x += length * math.cos(heading)
    y += length * math.sin(heading)
    out.append("G1 %s X%s Y%s F%s" % (comp, fmt(x), fmt(y), fmt(20 * unit)))

    def arc(turn_left, radius, sweep):
        nonlocal x, y, heading
        normal = heading + (math.pi / 2 if turn_left else -math.pi / 2)
        cx, cy = x + radius * math.cos(normal), y + radius * math.sin(normal)
        start = math.atan2(y - cy, x - cx)
        end = start + (sweep if turn_left else -sweep)
        nx, ny = cx + radius * math.cos(end), cy + radius * math.sin(end)
        out.append("G%d X%s Y%s I%s J%s" % (3 if turn_left else 2, fmt(nx), fmt(ny), fmt(cx - x), fmt(cy - y)))
        x, y = float(fmt(nx)), float(fmt(ny))
        heading += sweep if turn_left else -sweep

    if rng.random() < 0.6:  # a lead-in arc tangent to the entry
        arc(rng.random() < 0.5, r * rng.uniform(0.6, 3.0), rng.uniform(0.3, math.pi / 2))
    for _ in range(rng.randint(3, 12)):
        if rng.random() < 0.3:  # a corner first
            heading += rng.choice([1, -1]) * rng.uniform(0.05, 2.8)
        if rng.random() < 0.55:
            length = r * rng.uniform(0.2, 8.0)
            x += length * math.cos(heading)
            y += length * math.sin(heading)
            x, y = float(fmt(x)), float(fmt(y))
            out.append("G1 X%s Y%s" % (fmt(x), fmt(y)))
        else:
            # radii from 1.05 to 10 tool radii, one in ten from half to one radius
            radius = rng.uniform(0.5, 1.0) if rng.random() < 0.1 else rng.uniform(1.05, 10.0)
            arc(rng.random() < 0.5, r * radius, rng.uniform(0.1, 3.0))
    if rng.random() < 0.6:  # a lead-out arc
        arc(rng.random() < 0.5, r * rng.uniform(0.6, 3.0), rng.uniform(0.3, math.pi / 2))
    length = r * rng.uniform(1.1, 4.0)
    heading += rng.uniform(-0.5, 0.5)
    out.append("G1 G40 X%s Y%s" % (fmt(x + length * math.cos(heading)), fmt(y + length * math.sin(heading))))
    out += ["G0 Z%s" % fmt(0.5 * unit), "M2"]
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--engage", default="build/apps/engage")
    ap.add_argument("--seeds", default="1-300")
    ap.add_argument("--tol", type=float, default=0.002)
    ap.add_argument("--keep", help="write every program into this folder")
    args = ap.parse_args()
    first, last = (int(v) for v in args.seeds.split("-"))
    table = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "gcode", "linuxcnc", "tools.tbl")
    folder = args.keep or tempfile.mkdtemp(prefix="comp_campaign_")
    os.makedirs(folder, exist_ok=True)
    counts = {}
    bad = []
    for seed in range(first, last + 1):
        path = os.path.join(folder, "comp_%d.ngc" % seed)
        with open(path, "w") as f:
            f.write(program(seed))
        try:
            theirs = cl.drop_zero_length(cl.linuxcnc_moves(path, table))
        except RuntimeError as e:
            theirs, their_error = None, str(e).splitlines()[-1]
        try:
            ours = cl.drop_zero_length(cl.engage_moves(args.engage, path, table))
        except RuntimeError as e:
            ours, our_error = None, str(e)
        if theirs is None and ours is None:
            verdict = "REFUSED"
        elif theirs is None:
            verdict = "ONLY-LINUXCNC refused: " + their_error[:150]
        elif ours is None:
            verdict = "ONLY-ENGAGE refused: " + our_error[:150]
        else:
            worst, problem = cl.compare(ours, theirs, args.tol)
            verdict = "DIFFER " + problem if problem else "OK"
        kind = verdict.split()[0]
        counts[kind] = counts.get(kind, 0) + 1
        if kind not in ("OK", "REFUSED"):
            bad.append(seed)
            print("seed %d %s (%s)" % (seed, verdict, path))
    print(", ".join("%s %d" % kv for kv in sorted(counts.items())), "of", last - first + 1, "seeds")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
