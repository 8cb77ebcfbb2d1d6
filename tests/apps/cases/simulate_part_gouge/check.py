"""A 20 x 20 x 5 mm pocket (its design: square corners, floor at Z-5) cleared by a 6 mm flat
end mill with one pass typed 0.2 mm too deep (line 13, along Y18.6 from X13 to X27, entered by
the plunge of line 12): the one gouge is that pass's stadium, 14 x 6 mm plus a 3 mm disc,
(84 + 9 pi) mm^2, 0.2 mm deep; the tool leaves its radius in the four corners, each
3 - 3 / sqrt(2) = 0.8787 mm from the part along the diagonal. A corner's leftover is its
material where it stands more than the 0.05 mm allowance off the part: each point of the
material belongs to the nearest of the two walls and the floor, and counts where that face's
point below it has more than the allowance of material over it (integrated here on a fine
grid: of the corner's (9 - 9 pi / 4) x 5 = 9.657 mm^3, the edges thinner than 0.05 mm along
the walls, 0.09 mm^3, are not a leftover). Depths within a tenth of the 0.3 mm cell, volumes
within 1 % (the issue's bounds).
"""
import csv
import json
import math
import sys

out = sys.argv[1]
part = json.load(open(out + "/summary.json"))["part"]
cell = 0.3
gouges = part["gouges"]
assert gouges["count"] == 1, gouges
g = gouges["regions"][0]
area = 14 * 6 + 9 * math.pi
print(f"gouge {g['depth']:.6f} mm deep, {g['area']:.4f} mm^2 ({area:.4f}), "
      f"{g['volume']:.4f} mm^3 ({0.2 * area:.4f})")
assert abs(g["depth"] - 0.2) <= 0.1 * cell, g
assert abs(g["volume"] - 0.2 * area) <= 0.01 * 0.2 * area, g
assert g["lines"][0]["line"] == 13, g["lines"]
assert all(line["line"] in (12, 13) for line in g["lines"]), g["lines"]
left = part["leftovers"]
assert left["count"] == 4, left
corner = 3 - 3 / math.sqrt(2)


def corner_leftover(allowance=0.05, n=600):
    """Corner at the origin, walls along the axes, material where a, b in [0, 3] lie outside
    the tool's circle about (3, 3): a wall's point at u along it carries min(t(u), u, w) of
    material (t: to the circle, u: the other wall's bisector, w: the floor's, at height w);
    the floor's point at (a, b) min(a, b)."""
    def t_air(u):
        return 3 - math.sqrt(max(0.0, 9 - (3 - u) ** 2))
    walls = 0.0
    du, dw = 3.0 / n, 5.0 / n
    for i in range(n):
        u = (i + 0.5) * du
        for k in range(n):
            s = min(t_air(u), u, (k + 0.5) * dw)
            if s > allowance:
                walls += s * du * dw
    floor = 0.0
    da = 3.0 / n
    for i in range(n):
        a = (i + 0.5) * da
        for j in range(n):
            b = (j + 0.5) * da
            if (a - 3) ** 2 + (b - 3) ** 2 > 9 and min(a, b) > allowance:
                floor += min(a, b) * da * da
    return 2 * walls + floor


volume = corner_leftover()
for r in left["regions"]:
    print(f"corner {r['thickness']:.6f} mm ({corner:.6f}), {r['volume']:.4f} mm^3 ({volume:.4f})")
    assert abs(r["thickness"] - corner) <= 0.1 * cell, r
    assert abs(r["volume"] - volume) <= 0.01 * volume, r
rows = list(csv.DictReader(open(out + "/gouges.csv")))
assert len(rows) == 1 and rows[0]["lines"].split()[0].endswith("pocket_gouge.ngc:13"), rows
