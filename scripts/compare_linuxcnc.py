#!/usr/bin/env python3
"""Compare `engage moves` with LinuxCNC's stand-alone interpreter `rs274` (Debian package
linuxcnc-uspace) on G-code programs.

rs274 prints canonical machining calls in program coordinates and program units; this script
turns them into moves in machine coordinates (mm) by tracking SET_G5X_OFFSET,
SET_G92_OFFSET and USE_LENGTH_UNITS, drops zero-length moves on both sides, and compares the
moves one by one: kind, end point and (for arcs) centre and direction, within a tolerance.

  scripts/compare_linuxcnc.py [--engage build/apps/engage] [--tol 0.002] [--golden DIR] FILE...

With --golden DIR it writes DIR/<name>.csv with LinuxCNC's moves (line,kind,x,y,z,cx,cy,cz,
plane,turns) for tests that run without LinuxCNC. Exit status 1 when any program differs.
"""
import argparse
import math
import os
import re
import subprocess
import sys

CALL = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z0-9_]+)\((.*)\)\s*$")


def numbers(args):
    out = []
    for tok in args.replace(" ", ",").split(","):
        tok = tok.strip()
        if not tok:
            continue
        try:
            out.append(float(tok))
        except ValueError:
            pass
    return out


def linuxcnc_moves(path, tool_table, tries=2):
    """Moves from rs274 as dicts (mm, machine coordinates); raises RuntimeError on failure.

    A run that stops short of the program's end is tried again once: under a loaded CI machine
    rs274 once stopped at a tool change (T5 M6) on a program it ran through alone."""
    folder = os.path.dirname(os.path.abspath(path))
    proc = subprocess.run(["rs274", "-t", tool_table, "-g", os.path.abspath(path)], cwd=folder, input="",
                          capture_output=True, text=True, timeout=60)
    unit = 1.0
    g5x = [0.0, 0.0, 0.0]
    g92 = [0.0, 0.0, 0.0]
    plane = "XY"
    pos = [0.0, 0.0, 0.0]
    moves = []
    ended = False
    lines = proc.stdout.splitlines()
    for line in lines:
        m = CALL.match(line)
        if not m:
            continue
        name, args = m.group(1), m.group(2)
        if name == "USE_LENGTH_UNITS":
            unit = 25.4 if "INCHES" in args else (10.0 if "CM" in args else 1.0)
        elif name == "SET_G5X_OFFSET":
            v = numbers(args)
            g5x = [v[1] * unit, v[2] * unit, v[3] * unit]
        elif name == "SET_G92_OFFSET":
            v = numbers(args)
            g92 = [v[0] * unit, v[1] * unit, v[2] * unit]
        elif name == "SELECT_PLANE":
            plane = "XY" if "XY" in args else ("XZ" if "XZ" in args else "YZ")
        elif name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED"):
            v = numbers(args)
            end = [v[i] * unit + g5x[i] + g92[i] for i in range(3)]
            moves.append({"kind": "rapid" if name == "STRAIGHT_TRAVERSE" else "line", "end": end})
            pos = end
        elif name == "STRAIGHT_PROBE":
            # rs274 (saicanon.cc) takes the probe to its target and leaves it 0.254 mm back
            # towards the start; engage writes that back-off as a second line.
            v = numbers(args)
            end = [v[i] * unit + g5x[i] + g92[i] for i in range(3)]
            d = math.dist(end, pos)
            if d > 0.0:
                moves.append({"kind": "line", "end": end})
                back = [end[i] + (pos[i] - end[i]) * 0.254 / d for i in range(3)]
                moves.append({"kind": "line", "end": back})
                pos = back
        elif name == "RIGID_TAP":
            # G33.1: in to the target and back out to the start.
            v = numbers(args)
            end = [v[i] * unit + g5x[i] + g92[i] for i in range(3)]
            moves.append({"kind": "line", "end": end})
            moves.append({"kind": "line", "end": list(pos)})
        elif name == "ARC_FEED":
            v = numbers(args)
            fe, se, fa, sa, rot, ae = v[0], v[1], v[2], v[3], int(v[4]), v[5]
            # (first, second, axis) per plane: XY (x, y, z), XZ (z, x, y), YZ (y, z, x)
            idx = {"XY": (0, 1, 2), "XZ": (2, 0, 1), "YZ": (1, 2, 0)}[plane]
            end = [0.0, 0.0, 0.0]
            cen = [0.0, 0.0, 0.0]
            end[idx[0]], end[idx[1]], end[idx[2]] = fe, se, ae
            cen[idx[0]], cen[idx[1]] = fa, sa
            end = [end[i] * unit + g5x[i] + g92[i] for i in range(3)]
            cen = [cen[i] * unit + g5x[i] + g92[i] for i in range(3)]
            cen[idx[2]] = pos[idx[2]]
            moves.append({"kind": "arc", "end": end, "center": cen, "turns": rot, "plane": plane})
            pos = end
        elif name == "NURBS_FEED":
            moves.append({"kind": "spline", "end": None})
        elif name in ("PROGRAM_END", "FINISH"):
            ended = True
    if not ended:
        if tries > 1:
            return linuxcnc_moves(path, tool_table, tries - 1)
        tail = "\n".join((proc.stdout.splitlines() + proc.stderr.splitlines())[-3:])
        raise RuntimeError("rs274 did not reach the program end: " + tail)
    return moves


def engage_moves(engage, path, tool_table):
    # rs274 without an INI file reads tool tables in inches.
    proc = subprocess.run([engage, "moves", path, "--tool-table", tool_table, "--tool-table-units", "in"],
                          capture_output=True, text=True, timeout=120)
    if proc.returncode != 0:
        raise RuntimeError("engage failed: " + proc.stderr.strip())
    moves = []
    previous_spline_line = None
    for row in proc.stdout.splitlines()[1:]:
        c = row.split(",")
        kind = c[1]
        end = [float(c[2]), float(c[3]), float(c[4])]
        if kind == "spline":
            # One spline move prints one row per line piece: keep one move, its last point.
            if previous_spline_line == c[0] and moves and moves[-1]["kind"] == "spline":
                moves[-1]["end"] = end
                continue
            previous_spline_line = c[0]
            moves.append({"kind": "spline", "end": end, "line": int(c[0])})
            continue
        previous_spline_line = None
        mv = {"kind": kind, "end": end, "line": int(c[0])}
        if kind == "arc":
            mv["center"] = [float(c[5]), float(c[6]), float(c[7])]
            mv["plane"] = c[8]
            mv["turns"] = int(c[9])
        moves.append(mv)
    return moves


def drop_zero_length(moves):
    out = []
    pos = [0.0, 0.0, 0.0]
    for m in moves:
        if m["end"] is None:
            out.append(m)
            continue
        if m["kind"] in ("rapid", "line") and max(abs(m["end"][i] - pos[i]) for i in range(3)) < 1e-9:
            continue
        out.append(m)
        pos = m["end"]
    return out


def compare(ours, theirs, tol):
    """Largest deviation (mm) and the first mismatch description, or None."""
    if len(ours) != len(theirs):
        return None, f"{len(ours)} moves against LinuxCNC's {len(theirs)}"
    worst = 0.0
    for i, (a, b) in enumerate(zip(ours, theirs)):
        if a["kind"] != b["kind"]:
            return None, f"move {i + 1} (line {a.get('line')}): {a['kind']} against LinuxCNC's {b['kind']}"
        if b["end"] is None:
            continue  # NURBS_FEED prints no end point; the next move checks where it ended
        if i == 0 and a["kind"] == "rapid" and max(abs(a["end"][k] - b["end"][k]) for k in range(2)) <= tol:
            # A G43 before the first move: rs274 shifts its assumed start by the tool length,
            # engage does not (before a move the position is an assumption, not a homed
            # machine; GcodeReader.cpp). The first rapid's X and Y must agree.
            continue
        d = max(abs(a["end"][k] - b["end"][k]) for k in range(3))
        if a["kind"] == "arc":
            d = max(d, max(abs(a["center"][k] - b["center"][k]) for k in range(3)))
            if (a["turns"] > 0) != (b["turns"] > 0) or abs(a["turns"]) != abs(b["turns"]):
                return None, f"move {i + 1} (line {a.get('line')}): turns {a['turns']} against {b['turns']}"
        if d > tol:
            return d, f"move {i + 1} (line {a.get('line')}): {d:.6f} mm apart"
        worst = max(worst, d)
    return worst, None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--engage", default="build/apps/engage")
    ap.add_argument("--tol", type=float, default=0.002)
    ap.add_argument("--golden", help="write LinuxCNC's moves as CSV into this folder")
    ap.add_argument("--tool-table", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                                         "data", "gcode", "linuxcnc", "tools.tbl"),
                    help="tool table given to both interpreters (lengths in inches)")
    args = ap.parse_args()
    failures = compared = 0
    for path in args.files:
        name = os.path.basename(path)
        try:
            theirs = drop_zero_length(linuxcnc_moves(path, args.tool_table))
        except (RuntimeError, subprocess.TimeoutExpired) as e:
            print(f"SKIP {name}: LinuxCNC does not run it: {str(e).splitlines()[-1][:120]}")
            continue
        try:
            ours = drop_zero_length(engage_moves(args.engage, path, args.tool_table))
        except RuntimeError as e:
            print(f"FAIL {name}: {str(e)[:300]}")
            failures += 1
            continue
        worst, problem = compare(ours, theirs, args.tol)
        compared += 1
        if problem:
            print(f"FAIL {name}: {problem}")
            failures += 1
        else:
            print(f"OK   {name}: {len(ours)} moves, max deviation {worst:.6f} mm")
        if args.golden:
            os.makedirs(args.golden, exist_ok=True)
            with open(os.path.join(args.golden, os.path.splitext(name)[0] + ".csv"), "w") as f:
                f.write("kind,x,y,z,cx,cy,cz,plane,turns\n")
                for m in theirs:
                    if m["end"] is None:
                        f.write("spline,,,,,,,,\n")
                    elif m["kind"] == "arc":
                        f.write("arc,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%s,%d\n" % (*m["end"], *m["center"], m["plane"], m["turns"]))
                    else:
                        f.write("%s,%.6f,%.6f,%.6f,,,,,\n" % (m["kind"], *m["end"]))
    print(f"{compared} programs compared, {failures} failed")
    if compared == 0:
        print("no program was compared (is LinuxCNC's rs274 running?)")
    sys.exit(1 if failures or compared == 0 else 0)


if __name__ == "__main__":
    main()
