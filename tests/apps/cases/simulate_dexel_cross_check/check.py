"""The cross-check of the Fusion 360 pocket: the dexel run and the voxel run it made compute
the removal in unrelated ways (rays of material intervals; volume fractions with planes);
both must remove the volume the pocket's swept cutter removes (2893.55 mm^3 on a 0.025 mm
grid of the swept depth, tests/apps/cases/simulate_fusion_pocket/check.py) within 0.1 %,
and no step may differ between them by more than the 3 % tolerance."""
import json
import os
import sys

out = sys.argv[1]
SWEPT = 2893.55  # mm^3; the grid's own error about 1e-5
with open(os.path.join(out, "summary.json")) as f:
    s = json.load(f)
c = s["cross_check"]
failures = []
for name, removed in (("dexel", s["removed"]), ("voxel", c["removed_voxel"])):
    print(f"{name}: removed {removed} mm^3 against {SWEPT} mm^3 swept")
    if abs(removed / SWEPT - 1.0) > 1e-3:
        failures.append(f"{name} more than 0.1 % from the swept volume")
if c["steps_differing"] != 0:
    failures.append(f"{c['steps_differing']} steps differ by more than 3 %")
if failures:
    print("\n".join(failures))
    sys.exit(1)
