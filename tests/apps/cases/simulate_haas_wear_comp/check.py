"""A Haas profile with CAM wear compensation (the path is the tool centre's, D01 holds only the
wear) removes what its centre path sweeps, computed here by hand.

The 0.5 in flat end mill's centre runs up X0.25 from Y-0.3, around the 2 x 1 in part
(0.5-2.5, 0.5-1.5) at 0.25 in on arcs about its corners, and 0.1 in deep: it clears the 3 x 2 in
block's top but the part and three corners (the straight entry along X0.25 clears the fourth),
each the square of the outer radius 0.5 in less its quarter disc, (1 - pi/4) 0.5^2 in^2.
Removed: (3 x 2 - 2 x 1 - 3 (1 - pi/4) 0.25) x 0.1 in^3 = 0.383905 in^3. Tolerance 0.1 %: the
dexel stock's steps against closed forms hold 0.012 % on slots (docs/accuracy.md); the
wear-compensation reading as control would be off by far more (it is refused, see
error_wear_comp_read_as_control).
"""
import json
import math
import sys

out = sys.argv[1]
summary = json.load(open(out + "/summary.json"))
assert summary["unit_labels"]["volume"] == "in^3", summary["unit_labels"]
removed = summary["removed"]
expected = (3 * 2 - 2 * 1 - 3 * (1 - math.pi / 4) * 0.25) * 0.1
error = abs(removed - expected) / expected
print(f"removed {removed:.6f} in^3, expected {expected:.6f} in^3, {100 * error:.4f} %")
sys.exit(0 if error < 1e-3 else 1)
