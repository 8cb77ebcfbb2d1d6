#!/usr/bin/env bash
# Regenerate the pocket programs of the example batch (data/batch/programs) from the
# boundaries in data/batch/boundaries with `engage pocket`. Run from the repository root
# after building; ENGAGE names another engage binary.
set -euo pipefail
E=${ENGAGE:-build/apps/engage}
B=data/batch/boundaries
P=data/batch/programs
mkdir -p "$P"
"$E" pocket $B/circle.ngc --diameter 10 --stepover 4 --depth 6 --step-down 3 --feed 1200 -o $P/circle_d10.ngc
"$E" pocket $B/circle.ngc --diameter 16 --stepover 6 --depth 3 --feed 2000 --conventional -o $P/circle_d16_conventional.ngc
"$E" pocket $B/rectangle.ngc --diameter 8 --stepover 3 --depth 4 --feed 1000 -o $P/rectangle_d8.ngc
"$E" pocket $B/l_shape.ngc --diameter 10 --stepover 5 --depth 5 --feed 1500 -o $P/l_shape_d10.ngc
"$E" pocket $B/hexagon.ngc --diameter 6 --stepover 2.5 --depth 3 --feed 900 -o $P/hexagon_d6.ngc
"$E" pocket $B/star.ngc --diameter 6 --stepover 2.5 --depth 4 --step-down 2 --feed 800 -o $P/star_d6.ngc
"$E" pocket $B/cross.ngc --diameter 8 --stepover 3.5 --depth 5 --feed 1200 -o $P/cross_d8.ngc
"$E" pocket $B/triangle.ngc --diameter 10 --stepover 4 --depth 4 --feed 1200 -o $P/triangle_d10.ngc
"$E" pocket $B/obround.ngc --diameter 8 --stepover 3 --depth 6 --step-down 2 --feed 1000 -o $P/obround_d8.ngc
"$E" pocket $B/island.ngc --diameter 6 --stepover 2.5 --depth 4 --feed 900 -o $P/island_d6.ngc
"$E" pocket data/paper/fig10_boundary.ngc --diameter 0.5in --stepover 0.2in --depth 0.25in --feed 60ipm -o $P/peanut_d0.5in.ngc
