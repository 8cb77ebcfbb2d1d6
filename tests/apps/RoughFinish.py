#!/usr/bin/env python3
"""Rough, then finish from the first run's stock.vdb: the engage command line as a user runs it.

data/gcode/rough_finish: rough.ngc roughs a 30 x 20 x 3 mm pocket (6 mm flat end mill) leaving
0.3 mm on walls and floor, finish.ngc takes the 0.3 mm. Checks, for both stock models:
- rough then finish (from rough's stock.vdb) removes what one run of the two programs
  concatenated removes, within 0.1 % (the issue's bar), and each run's removal is within
  0.1 % of its closed form (hand computed below);
- finish at another voxel size keeps the stock's volume (resampled by overlap);
- the batch example (`"stock": "job:rough"`) runs finish after rough with the same figures,
  and a second batch run finds all done;
- a .vdb that is not an engage stock (missing, removed.vdb, not a VDB file) is refused with
  its reason, exit 1, and no output folder.

usage: RoughFinish.py ENGAGE DATA_DIR OUT_DIR
"""
import json
import math
import os
import shutil
import subprocess
import sys

ENGAGE, DATA, OUT = sys.argv[1:4]
RF = os.path.join(DATA, "gcode", "rough_finish")
TOOL = ["--tool", "flat", "--diameter", "6mm"]
BOX = "box:0,0,-10,40,30,0"

# Closed forms (mm^3). A 6 mm flat end mill sweeping a rectangle of centre positions
# a x b covers (a + 6) x (b + 6) less the four corners a radius of 3 mm leaves: (4 - pi) 9.
CORNERS = (4.0 - math.pi) * 9.0
ROUGH = ((31.7 - 8.3 + 6.0) * (21.7 - 8.3 + 6.0) - CORNERS) * 2.7  # 1519.11
TOTAL = ((32.0 - 8.0 + 6.0) * (22.0 - 8.0 + 6.0) - CORNERS) * 3.0  # 1776.82
FINISH = TOTAL - ROUGH  # 257.71

failures = []


def check(ok, what):
    print(("ok:   " if ok else "FAIL: ") + what)
    if not ok:
        failures.append(what)


def run(args, expect=0):
    p = subprocess.run([ENGAGE] + args + ["--quiet"], capture_output=True, text=True)
    if p.returncode != expect:
        check(False, "%s exited %d (expected %d): %s" % (" ".join(args), p.returncode, expect,
                                                         p.stderr.strip()))
    return p


def summary(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        return json.load(f)


def removed(folder):
    return summary(folder)["removed"]


def stock_after(folder):
    return summary(folder)["volume_after"]


shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
both = os.path.join(OUT, "both.ngc")
with open(both, "w") as f:
    rough_text = open(os.path.join(RF, "rough.ngc")).read().replace("\nM2\n", "\n")
    f.write(rough_text + open(os.path.join(RF, "finish.ngc")).read())

for model in ("voxel", "dexel"):
    o = lambda name: os.path.join(OUT, model + "_" + name)
    m = ["--stock-model", model]
    run(["simulate", os.path.join(RF, "rough.ngc")] + TOOL + m + ["--stock", BOX, "--out", o("rough")])
    run(["simulate", os.path.join(RF, "finish.ngc")] + TOOL + m +
        ["--stock", os.path.join(o("rough"), "stock.vdb"), "--out", o("finish")])
    run(["simulate", both] + TOOL + m + ["--stock", BOX, "--out", o("both")])
    r, fin, one = removed(o("rough")), removed(o("finish")), removed(o("both"))
    # The bar of issue 20: rough then finish totals one run within 0.1 %.
    check(abs((r + fin) - one) <= 1e-3 * one,
          "%s: rough %.3f + finish %.3f = %.3f mm^3, one run %.3f mm^3" % (model, r, fin, r + fin, one))
    # Each against its closed form: 0.1 % of the pocket (a 0.3 mm finishing cut is thin: the
    # finish alone within 1 %, measured 0.07 % voxels, 0.06 % dexels).
    check(abs(r - ROUGH) <= 1e-3 * ROUGH, "%s: rough %.3f vs %.3f mm^3" % (model, r, ROUGH))
    check(abs(fin - FINISH) <= 1e-2 * FINISH, "%s: finish %.3f vs %.3f mm^3" % (model, fin, FINISH))
    check(abs(r + fin - TOTAL) <= 1e-3 * TOTAL,
          "%s: total %.3f vs %.3f mm^3" % (model, r + fin, TOTAL))
    # The stock the finish starts from is the one rough left (volume kept through the file:
    # 32-bit fractions, 1e-5 relative).
    before = summary(o("finish"))["volume_before"]
    check(abs(before - stock_after(o("rough"))) <= 1e-5 * before,
          "%s: finish starts from %.4f mm^3, rough left %.4f mm^3" % (model, before,
                                                                     stock_after(o("rough"))))

# Another voxel size: resampled by overlap, the volume kept; in either model from the voxel
# rough, and as dexels (the default) from the dexel rough. Its first rapid leaves from the
# stock's top corner: exit 0 says it met nothing there (a corner's resampled material had
# risen above the top face).
for model, rough in (("voxel", "voxel"), ("dexel", "voxel"), ("dexel", "dexel")):
    f017 = os.path.join(OUT, "%s_finish_017_from_%s" % (model, rough))
    run(["simulate", os.path.join(RF, "finish.ngc")] + TOOL +
        ["--stock-model", model, "--stock", os.path.join(OUT, rough + "_rough", "stock.vdb"),
         "--voxel", "0.17mm", "--out", f017])
    before = summary(f017)["volume_before"]
    left = stock_after(os.path.join(OUT, rough + "_rough"))
    check(abs(before - left) <= 1e-5 * before,
          "%s at 0.17 mm from 0.3 mm %ss: %.4f vs %.4f mm^3" % (model, rough, before, left))
    check(abs(removed(f017) - FINISH) <= 1e-2 * FINISH,
          "%s: finish at 0.17 mm from 0.3 mm %ss: %.3f vs %.3f mm^3" % (model, rough, removed(f017),
                                                                       FINISH))

# The batch example: finish after rough, from its stock.
b = os.path.join(OUT, "batch")
run(["batch", os.path.join(RF, "batch.json"), "--out", b])
recs = {}
with open(os.path.join(b, "batch.json")) as f:
    for r in json.load(f)["records"]:
        recs[r["name"]] = r
check(all(r["status"] == "ok" for r in recs.values()), "batch: all jobs ok")
check(abs(recs["rough"]["removed_mm3"] - removed(os.path.join(OUT, "dexel_rough"))) <= 1e-9,
      "batch rough = simulate rough (dexels, the default)")
check(abs(recs["finish"]["removed_mm3"] - removed(os.path.join(OUT, "dexel_finish"))) <= 1e-9,
      "batch finish (schedule) from job:rough = simulate finish from rough's stock.vdb")
check(abs(recs["finish_voxel"]["removed_mm3"] - FINISH) <= 1e-2 * FINISH, "batch finish_voxel")
again = run(["batch", os.path.join(RF, "batch.json"), "--out", b])
check("3 already done" in again.stderr + again.stdout, "batch again: all done")

# Refused stocks: the reason, exit 1, no output folder.
text = os.path.join(OUT, "notes.vdb")
with open(text, "w") as f:
    f.write("not a grid\n")
for stock, reason in ((os.path.join(OUT, "missing.vdb"), "no such file"),
                      (os.path.join(OUT, "voxel_rough", "removed.vdb"), "has no grid named 'stock'"),
                      (text, "not a VDB file")):
    bad = os.path.join(OUT, "refused")
    p = run(["simulate", os.path.join(RF, "finish.ngc")] + TOOL + ["--stock", stock, "--out", bad], 1)
    check(reason in p.stderr and not os.path.exists(bad),
          "refused %s: %s" % (os.path.basename(stock), p.stderr.strip()))

print("%d failure(s)" % len(failures))
sys.exit(1 if failures else 0)
