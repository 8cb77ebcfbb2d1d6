"""A program that touches off on the stock's top (G38.2, then G10 L20 Z0) cuts 1 mm into the
top wherever the top is: the stock's top at Z-2.3 here, not the probe's target Z-10. By hand,
a 6 mm flat end mill plunged 1 mm at (10, 10) and run to X40: a half disc, a 30 x 6 mm
rectangle and a half disc, 1 mm deep: (pi 3^2 + 30 x 6) x 1 = 208.274 mm^3 (a probe run to its
target would cut 8.7 mm deeper: 1811 mm^3). Tolerance 0.1 % (the dexels' closed-form slots
hold 0.012 %).
"""
import json
import math
import sys

summary = json.load(open(sys.argv[1] + "/summary.json"))
assert summary["unit_labels"]["volume"] == "mm^3", summary["unit_labels"]
expected = math.pi * 9 + 30 * 6
error = abs(summary["removed"] - expected) / expected
print(f"removed {summary['removed']:.3f} mm^3, expected {expected:.3f} mm^3, {100 * error:.4f} %")
sys.exit(0 if error < 1e-3 else 1)
