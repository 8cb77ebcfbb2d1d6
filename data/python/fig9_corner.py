#!/usr/bin/env python3
"""The paper's Fig 9 corner, from Python: measured MRR against the analytic model.

A 6 mm flat end mill cuts a pass along y = 0 into a 90 deg inside corner left by an earlier
pass (stepover s = r = 3 mm, depth 2 mm, 600 mm/min). The analytic model (paper Eq 6) sees a
steady s x d band and predicts 3600 mm^3/min all along; the simulated stock shows the MRR
rising as the cutter meets the corner's uncut material, up to the full slot (2 x nominal)
at the corner. Run from the repository after the README's set-up command:

    PYTHONPATH=build/python python3 data/python/fig9_corner.py [out.png]
"""
import os
import sys

import engage

here = os.path.dirname(os.path.abspath(__file__))
program = os.path.join(here, "..", "gcode", "paper", "fig9_corner.ngc")
out = sys.argv[1] if len(sys.argv) > 1 else "fig9_corner.png"

# The same options as `engage simulate` (see engage.options()); '_' for '-'.
result = engage.run(program=program, tool="flat", diameter="6mm",
                    stock="box:-30,-10,-10,10,30,0", stepover="3mm", depth="2mm")
steps = result.steps

# The current pass: its feed steps from line 13 (G1 X0 F600) on.
wall = (steps["line"] >= 13) & (steps["kind"] == "line") & (steps["feed_mm_min"] == 600.0)
s = steps["arc_length_mm"][wall]
s = s - s[0]
measured = steps["mrr_mm3_min"][wall]

# The analytic model of the same cut, called directly: Eq 6 on a straight path.
model = engage.Model(engage.Cutter.flat(6.0, 18.0), stepover=3.0, depth=2.0)
nominal = model.mrr(600.0)
peak = measured.max()
print(f"analytic (Eq 6): {nominal:.1f} mm^3/min; measured peak {peak:.1f} mm^3/min "
      f"= {peak / nominal:.3f} x nominal at s = {s[measured.argmax()]:.2f} mm")

import matplotlib  # noqa: E402  (only for the plot)

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(s, measured, label="measured (voxel stock)")
ax.axhline(nominal, color="k", linestyle="--", label="analytic, Eq 6")
ax.set_xlabel("arc length along the pass, mm")
ax.set_ylabel("MRR, mm$^3$/min")
ax.set_title("Fig 9: a 90° inside corner after a previous pass")
ax.legend()
fig.tight_layout()
fig.savefig(out, dpi=120)
print(f"wrote {out}")
