"""paper.json's figures against the paper's settings worked by hand (D = 1 in, s = 0.5 in,
d = 0.3 in, 100 ipm): a flat end mill's cross-section is s d = 0.15 in^2, 15 in^3/min on a
straight path; on an arc of tool-centre radius rho its centroid (r - s/2 = 0.25 in from the
axis) runs at (rho +- 0.25) / rho of the feed (Pappus); the paper's Eq 12 uses instead the
distance m = sqrt(0.25^2 + 0.15^2) from the contact point to the centroid and R = rho + r."""
import json
import math
import os
import sys

out = sys.argv[1]
with open(os.path.join(out, "paper.json")) as f:
    p = json.load(f)
failures = []


def near(what, value, expected, rel):
    ok = abs(value / expected - 1.0) <= rel
    print(f"{what}: {value:.6g} against {expected:.6g} ({'ok' if ok else 'FAIL'})")
    if not ok:
        failures.append(what)


flat = p["fig8"]["flat_R_over_D_1_concave_in3_min"]  # rho = 1 in
near("Fig 8 flat R/D 1 concave, exact", flat["exact"], 15.0 * 1.25, 1e-9)
m = math.sqrt(0.25 ** 2 + 0.15 ** 2)
near("Fig 8 flat R/D 1 concave, paper Eq 12", flat["paper"], 15.0 * (1.5 - m) / 1.0, 1e-9)
# Measured in 0.1 in cells (D/10): the steady cuts within 0.1 % of the exact model.
near("Fig 8 flat R/D 1 concave, measured", flat["measured"], 18.75, 1e-3)
fig9 = p["fig9"]
near("Fig 9 nominal MRR, measured", fig9["nominal_mrr_in3_min"], 15.0, 1e-3)
# At the corner the cutter is in a full slot: 1 in x 0.3 in, twice the nominal.
near("Fig 9 peak over nominal, measured", fig9["peak_over_nominal_measured"], 2.0, 0.01)
for tool in ("flat", "taper"):  # both cut a band s wide: 15 in^3/min on straight stretches
    near(f"Fig 12 {tool} straight, exact", p["fig12"]["tools"][tool]["straight_exact_in3_min"],
         15.0, 1e-9)
f12 = p["fig12"]["tools"]["flat"]  # the wall pass's arcs: tool-centre radius 2 in
near("Fig 12 flat concave median, measured", f12["concave_median_mrr_in3_min"], 15.0 * 2.25 / 2,
     1e-3)
near("Fig 12 flat convex median, measured", f12["convex_median_mrr_in3_min"], 15.0 * 1.75 / 2,
     1e-3)
if failures:
    sys.exit(1)
