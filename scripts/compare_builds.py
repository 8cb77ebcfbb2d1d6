#!/usr/bin/env python3
"""Compare two engage builds output for output: every golden command-line case of tests/apps/cases
and the example batch (data/batch/manifest.json), run with both binaries, then every file
they wrote compared byte for byte, with the fields that time the run masked (run_time_s,
steps_per_second, voxels_changed_per_second, run_time_<model>_s, the timing figures of the
printed lines). Prints one line per difference and exits 1 if there is any.

  python3 scripts/compare_builds.py OLD/engage NEW/engage [WORKDIR]
"""
import json, os, re, shutil, subprocess, sys

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
old, new = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
work = sys.argv[3] if len(sys.argv) > 3 else "/tmp/compare_builds"
TIMING = re.compile(r'"(run_time[a-z_]*|steps_per_second|voxels_changed_per_second)": ?[-0-9.e+]+')
TIMING_TEXT = re.compile(r"[0-9.]+ s\b|\([0-9]+ steps/s\)|\[ *[0-9.]+ s\]")


UUID = re.compile(rb"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")


def masked(path, data, out):
    if path.endswith(".vdb"):  # OpenVDB writes a new UUID into every file's header
        return data[:100].replace(UUID.search(data[:100]).group(0), b"U" * 36) + data[100:]
    data = data.replace(out.encode(), b"@OUT@")
    if path.endswith(".json") or path.endswith(".html"):  # (report.html carries summary.json)
        return TIMING.sub(r'"\1": T', data.decode(errors="replace")).encode()
    if path.endswith("batch.csv"):
        lines = data.decode().splitlines()
        out = []
        for line in lines:
            cols = line.split(",")
            if len(cols) > 5:
                cols[5] = "T"
            out.append(",".join(cols))
        return "\n".join(out).encode()
    return data


def run(binary, args, out):
    shutil.rmtree(out, ignore_errors=True)
    args = [a.replace("@DATA@", os.path.join(root, "data")).replace("@SOURCE@", root)
            .replace("@OUT@", out) for a in args]
    p = subprocess.run([binary] + args, capture_output=True, cwd=os.path.dirname(out))
    return p.returncode, \
        TIMING_TEXT.sub("T", p.stdout.decode(errors="replace")).replace(out, "@OUT@"), \
        p.stderr.decode(errors="replace").replace(out, "@OUT@")


def files(folder):
    found = {}
    for base, _, names in os.walk(folder):
        for n in names:
            full = os.path.join(base, n)
            if n == ".engage-files":  # the list of a run's files (since the staged outputs)
                continue
            if n.startswith(".") and n.endswith(".lock"):  # a batch job's lock: its owner's pid
                continue
            found[os.path.relpath(full, folder)] = masked(full, open(full, "rb").read(), folder)
    return found


differences = 0


def compare(name, a, b, oa, ob):
    global differences
    for what, x, y in (("exit", a[0], b[0]), ("stdout", a[1], b[1]), ("stderr", a[2], b[2])):
        if x != y:
            differences += 1
            print(f"{name}: {what} differs:\n--- old\n{x}\n--- new\n{y}")
    fa, fb = files(oa), files(ob)
    for f in sorted(set(fa) | set(fb)):
        if fa.get(f) != fb.get(f):
            differences += 1
            print(f"{name}: {f} differs" + ("" if f in fa and f in fb else " (only in one)"))
    return len(fa)


os.makedirs(work, exist_ok=True)
cases = os.path.join(root, "tests", "apps", "cases")
compared = 0
for case in sorted(os.listdir(cases)):
    args = open(os.path.join(cases, case, "args")).read().split("\n")
    args = [a for a in args if a]
    oa, ob = os.path.join(work, "old", case), os.path.join(work, "new", case)
    os.makedirs(os.path.dirname(oa), exist_ok=True)
    os.makedirs(os.path.dirname(ob), exist_ok=True)
    compared += compare(case, run(old, args, oa), run(new, args, ob), oa, ob)
batch = ["batch", os.path.join(root, "data", "batch", "manifest.json"), "--out", "@OUT@", "--quiet"]
oa, ob = os.path.join(work, "old", "example_batch"), os.path.join(work, "new", "example_batch")
compared += compare("example batch", run(old, batch, oa), run(new, batch, ob), oa, ob)
print(f"{len(os.listdir(cases))} golden cases and the example batch, {compared} files: "
      f"{differences} differences")
sys.exit(1 if differences else 0)
