"""A Haas program whose holes a shop macro places (G65 with arguments, IF, WHILE, vacant
defaults, an NGC variable counting the holes) removes what ten plunges of the 6 mm flat end
mill remove, by hand: six 3 mm deep and four 2 mm deep, pi 3^2 (6 x 3 + 4 x 2) mm^3 =
735.133 mm^3 (no two holes meet: 20 and 21.2 mm apart). Tolerance 0.1 %: a plunge's dexel
columns are cut exactly, the bound leaves room for the holes' rims on the grid.
"""
import json
import math
import sys

summary = json.load(open(sys.argv[1] + "/summary.json"))
assert summary["unit_labels"]["volume"] == "mm^3", summary["unit_labels"]
expected = math.pi * 9 * (6 * 3 + 4 * 2)
error = abs(summary["removed"] - expected) / expected
print(f"removed {summary['removed']:.3f} mm^3, expected {expected:.3f} mm^3, {100 * error:.4f} %")
sys.exit(0 if error < 1e-3 else 1)
