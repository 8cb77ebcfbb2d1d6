#!/usr/bin/env python3
"""engage (and, where given, CAMotics' camsim) on CAMotics' own example projects, side by side.

For each example (../shared/real-programs/camotics/NAME/NAME.camotics) and grid (the project's
resolution, and half of it with --half), runs engage's voxel and dexel models (--models) and
camsim, the runs alternating, each --repeats times, on one core (taskset -c 0) and, with
--all-cores, on all. Prints a Markdown table of medians: whole-process wall time, engage's loop time (its
summary's run_time_s) and the rest (outputs), steps/s, changed cells/s, peak memory (the
child's maximum resident set), removed volume; and camsim / engage ratios.

camsim is not part of engage: build it from CAMotics' public sources outside this repository
and give its path with --camsim. It gets the workpiece engage computed (the project's stored
automatic workpiece can differ: botomata_bottom's is off its program's second half), and
writes its final surface (binary STL); its removed volume is that box less the surface's.

usage: camotics.py ENGAGE [--camsim PATH] [--examples a,b] [--half] [--repeats 3]
                          [--all-cores] [--outputs all|tables|summary] [--models voxel,dexel]
                          [--work DIR]
"""
import argparse
import json
import os
import shutil
import statistics
import struct
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLES = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared", "real-programs", "camotics"))


def run(cmd, one_core):
    """Wall seconds, user+system seconds and peak resident MiB of one child process."""
    if one_core:
        cmd = ["taskset", "-c", "0"] + cmd
    start = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - start
    err = p.stderr.read().decode(errors="replace")
    p.stderr.close()
    code = os.waitstatus_to_exitcode(status)
    if code not in (0, 5):  # 5: collisions, a finding, not a failure
        raise RuntimeError("%s exited %d: %s" % (" ".join(cmd), code, err.strip()[-300:]))
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


def stl_volume(path):
    """The volume inside a binary STL, read a block of triangles at a time: the peak memory of
    the children measured after it is the most of theirs and of this process's when it forked
    them (Linux keeps a process's largest resident set across exec), and reading cameo's STL at
    0.18 mm whole grew this process to 278 MiB, which every later child then reported."""
    v = 0.0
    with open(path, "rb") as f:
        f.seek(80)
        n = struct.unpack("<I", f.read(4))[0]
        while n > 0:
            count = min(n, 20000)
            data = f.read(50 * count)
            for t in struct.iter_unpack("<12fH", data):
                a, b, c = t[3:6], t[6:9], t[9:12]
                v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                      + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0
            n -= count
    return v


def box_of(stock):
    """box:x0mm,y0mm,... (engage's summary) -> ([x0, y0, z0], [x1, y1, z1]) in mm."""
    v = [float(x.replace("mm", "")) for x in stock[len("box:"):].split(",")]
    return v[:3], v[3:]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("engage")
    ap.add_argument("--camsim")
    ap.add_argument("--examples", default="flower_mold,tiger,bear,cameo,botomata_bottom,heart")
    ap.add_argument("--half", action="store_true", help="also at half the project's grid")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--all-cores", action="store_true", help="also on all cores")
    ap.add_argument("--outputs", default="all", help="engage's --outputs (all: its default)")
    ap.add_argument("--models", default="voxel,dexel",
                    help="engage's stock models to run (dexel is its default)")
    ap.add_argument("--work", default="/tmp/engage_bench_camotics")
    args = ap.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    print("| example | grid mm | cores | run | wall s | loop s | rest s | steps/s | cells/s | peak MiB | removed mm³ |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    sys.stdout.flush()
    for name in args.examples.split(","):
        project = os.path.join(EXAMPLES, name, name + ".camotics")
        with open(project) as f:
            spec = json.load(f)
        grids = [spec["resolution"]] + ([spec["resolution"] / 2.0] if args.half else [])
        for grid in grids:
            for one_core in [True] + ([False] if args.all_cores else []):
                runs = {"engage " + m: [] for m in args.models.split(",")}
                if args.camsim:
                    runs["camsim"] = []
                extra = {}
                for rep in range(args.repeats):
                    for label in runs:
                        out = os.path.join(args.work, "%s_%s" % (name, label.replace(" ", "_")))
                        shutil.rmtree(out, ignore_errors=True)
                        if label.startswith("engage"):
                            cmd = [args.engage, "simulate", project, "--voxel", "%.6gmm" % grid,
                                   "--stock-model", label.split()[1], "--out", out, "--quiet",
                                   "--outputs", args.outputs]
                            wall, cpu, mem = run(cmd, one_core)
                            with open(os.path.join(out, "summary.json")) as f:
                                s = json.load(f)
                            extra[label] = s
                            runs[label].append((wall, s["run_time_s"], mem))
                        else:
                            box = box_of(extra["engage " + args.models.split(",")[0]]["stock"])
                            copy = dict(spec)
                            copy["workpiece"] = {"automatic": False, "margin": 0,
                                                 "bounds": {"min": box[0], "max": box[1]}}
                            folder = os.path.join(args.work, name + "_camsim_project")
                            os.makedirs(folder, exist_ok=True)
                            for fn in spec["files"]:
                                shutil.copy(os.path.join(EXAMPLES, name, fn), folder)
                            pfile = os.path.join(folder, name + ".camotics")
                            with open(pfile, "w") as f:
                                json.dump(copy, f)
                            stl = out + ".stl"
                            cmd = [args.camsim, "--binary", "--threads", "1" if one_core else str(os.cpu_count()),
                                   "--resolution", "%.6g" % grid, pfile, stl]
                            wall, cpu, mem = run(cmd, one_core)
                            size = [box[1][i] - box[0][i] for i in range(3)]
                            extra[label] = size[0] * size[1] * size[2] - stl_volume(stl)
                            runs[label].append((wall, None, mem))
                for label, rs in runs.items():
                    wall = statistics.median(r[0] for r in rs)
                    mem = statistics.median(r[2] for r in rs)
                    if label.startswith("engage"):
                        s = extra[label]
                        loop = statistics.median(r[1] for r in rs)
                        # (summary.json speaks the program's units: in^3 for inch programs)
                        removed = s["removed"] * (25.4 ** 3 if s.get("units") == "in" else 1.0)
                        row = (wall, loop, wall - loop, s["steps_per_second"],
                               s.get("voxels_changed_per_second") or 0.0, mem, removed)
                        print("| %s | %.3g | %s | %s | %.2f | %.2f | %.2f | %.0f | %.3g | %.0f | %.1f |" % (
                            name, grid, "1" if one_core else "all", label, *row))
                    else:
                        print("| %s | %.3g | %s | camsim | %.2f | | | | | %.0f | %.1f |" % (
                            name, grid, "1" if one_core else "all", wall, mem, extra[label]))
                if args.camsim:
                    cs = statistics.median(r[0] for r in runs["camsim"])
                    ratios = ", ".join("%s %.2fx" % (m, cs / statistics.median(r[0] for r in runs["engage " + m]))
                                       for m in args.models.split(","))
                    print("| %s | %.3g | %s | camsim / engage | %s | | | | | | |" % (
                        name, grid, "1" if one_core else "all", ratios))
                sys.stdout.flush()


if __name__ == "__main__":
    main()
