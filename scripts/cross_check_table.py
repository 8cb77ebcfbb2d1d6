#!/usr/bin/env python3
"""Cross-check the voxel and dexel stocks on every job of a batch manifest.

Runs `engage batch` on a copy of the manifest with "cross-check": true and the voxel stock as
the primary model for every job (the dexel stock is the other), then prints a Markdown table per job: steps,
steps differing beyond the tolerance, worst step, the total removed by each model, and the run
time and memory of each. Usage, from the repository root after building:

    python3 scripts/cross_check_table.py data/batch/manifest.json --out out/cross_check
"""
import argparse
import json
import os
import subprocess
import sys

parser = argparse.ArgumentParser()
parser.add_argument("manifest")
parser.add_argument("--out", default="out/cross_check")
parser.add_argument("--engage", default="build/apps/engage")
parser.add_argument("--tolerance", default="0.03")
args = parser.parse_args()

with open(args.manifest) as f:
    manifest = json.load(f)
manifest.setdefault("defaults", {})["cross-check"] = True
manifest["defaults"]["cross-check-tolerance"] = args.tolerance
manifest["defaults"]["stock-model"] = "voxel"
# Paths in the manifest are relative to it: keep them so by writing the copy beside it.
base = os.path.dirname(os.path.abspath(args.manifest))
copy = os.path.join(base, ".cross_check_manifest.json")
with open(copy, "w") as f:
    json.dump(manifest, f)
try:
    subprocess.run([args.engage, "batch", copy, "--out", args.out, "--quiet"], check=False)
finally:
    os.remove(copy)

print("| job | steps | differ > %.0f %% | worst step | removed voxel | removed dexel | total diff | "
      "time voxel / dexel (s) | memory voxel / dexel (MB) |" % (100 * float(args.tolerance)))
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for job in manifest["jobs"]:
    name = job.get("name") or os.path.splitext(os.path.basename(job["program"]))[0]
    summary = os.path.join(args.out, "jobs", name, "summary.json")
    if not os.path.exists(summary):
        print("| %s | failed | | | | | | | |" % name)
        continue
    with open(summary) as f:
        s = json.load(f)
    c = s["cross_check"]
    unit = s["unit_labels"]["volume"]
    print("| %s | %d | %d | %.1f %% | %.6g %s | %.6g %s | %+.3f %% | %.2f / %.2f | %.1f / %.1f |" % (
        name, c["steps"], c["steps_differing"], 100 * c["worst_relative"], s["removed"], unit,
        c["removed_dexel"], unit, 100 * c["removed_relative_difference"], s["run_time_s"],
        c["run_time_dexel_s"], s["stock_memory_bytes"] / 1e6, c["memory_bytes_dexel"] / 1e6))
