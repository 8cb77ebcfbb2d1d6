#!/usr/bin/env python3
"""Write a detailed 3-axis finishing program for benchmarks: a zig-zag raster over a wavy
surface z = -0.5 - 0.4 sin(x/7) cos(y/9) mm on a 65 x 65 mm part, stepover 0.4 mm, about
17,000 moves, for a 1 mm ball end mill (stock box:0,0,-10,65,65,0).

  scripts/make_finishing_program.py > data/gcode/bench/finishing_raster.ngc
"""
import math

def z(x, y):
    return -0.5 - 0.4 * math.sin(x / 7.0) * math.cos(y / 9.0)

print("(finishing raster, 1 mm ball, stepover 0.4 mm, wavy surface; made by scripts/make_finishing_program.py)")
print("G21 G90 G17 G94")
print("T1 M6")
print("S18000 M3")
print("G0 Z5")
print("G0 X0 Y0")
print("G1 Z%.4f F300" % z(0, 0))
print("F1200")
passes = 163
points = 105
for j in range(passes):
    y = j * 0.4
    xs = [i * 65.0 / (points - 1) for i in range(points)]
    if j % 2:
        xs.reverse()
    if j > 0:
        print("G1 Y%.4f Z%.4f" % (y, z(xs[0], y)))
    for x in xs[1:]:
        print("G1 X%.4f Z%.4f" % (x, z(x, y)))
print("G0 Z5")
print("M5")
print("M2")
