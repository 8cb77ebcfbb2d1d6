#!/usr/bin/env bash
# Issue 44's random campaign: both stock models at the default cell against the exact reference
# (tests/support/ExactSweep.h) on the generator's programs (tests/support/RandomPrograms.h), one
# seed per process over the cores. The exact removals are kept in build/random-cuts, so that a
# campaign after a change to the stock models costs only the simulations (the reference takes
# 10 s to 4 min a program; the simulations a second).
#   scripts/random_campaign.sh [FIRST-LAST] [JOBS] [MODELS]  (default 1-200 on every core,
#                                                            models dexel and voxel)
# MODELS: any of dexel, voxel, quarter, tilted, mesh separated by spaces (quarter and tilted:
# each program carried onto a tilted tool, issue 48; bench_random_cuts.cpp says how).
# Writes every run's figures to build/random-cuts/campaign.jsonl and prints, per model, how many
# programs hold all of issue 44's bounds and the worst of each, then the 20 worst runs with
# their seeds. One seed again, with its program written out to run with `engage simulate`:
#   build/tests/bench/bench_random_cuts --seeds N --cache build/random-cuts --programs DIR
set -euo pipefail
cd "$(dirname "$0")/.."
range=${1:-1-200}
jobs=${2:-$(nproc)}
models=${3:-dexel voxel}
bench=build/tests/bench/bench_random_cuts
cache=build/random-cuts
if [ ! -x "$bench" ]; then
  echo "random_campaign.sh: build the tests first ($bench is missing)" >&2
  exit 2
fi
mkdir -p "$cache"
# (One process a seed: its models one after another, so that the first computes the reference.)
seq "${range%-*}" "${range#*-}" |
  MODELS="$models" CACHE="$cache" xargs -P "$jobs" -I{} sh -c \
    'for m in $MODELS; do "$0" --seeds "$1" --model "$m" --cache "$CACHE"; done' "$bench" {} |
  grep '^{"seed"' >"$cache/campaign.jsonl.part"
mv "$cache/campaign.jsonl.part" "$cache/campaign.jsonl"
python3 - "$cache/campaign.jsonl" <<'EOF'
import json, sys

runs = [json.loads(line) for line in open(sys.argv[1])]
for r in runs:
    if "error" in r:
        print(f"seed {r['seed']} {r['model']}: not run: {r['error']}")
runs = [r for r in runs if "error" not in r]
def score(r):  # 1 = at one of issue 44's bounds
    return max(abs(r["total_pct"]) / 0.1, abs(r["worst_big_pct"]) / 1.0,
               abs(r["worst_small_cells"]) / 2.0, 1e9 if r["worst_zero_mm3"] > 0 else 0.0)
for model in sorted({r["model"] for r in runs}):
    rs = [r for r in runs if r["model"] == model]
    held = sum(1 for r in rs if r["failures"] == 0 and abs(r["total_pct"]) <= 0.1)
    big = sum(r["big_moves"] for r in rs)
    print(f"{model}: {held} of {len(rs)} programs hold every bound; "
          f"worst total {max(abs(r['total_pct']) for r in rs):.3f} %, "
          f"worst move of 1 mm3 or more {max(abs(r['worst_big_pct']) for r in rs):.2f} % "
          f"({big} such moves), worst smaller move "
          f"{max(abs(r['worst_small_cells']) for r in rs):.2f} cells, "
          f"most taken where nothing is {max(r['worst_zero_mm3'] for r in rs):.3g} mm3")
print("worst runs (score 1 = at a bound):")
for r in sorted(runs, key=score, reverse=True)[:20]:
    print(f"  seed {r['seed']} {r['model']}: score {score(r):.3g}; {r['case']}; "
          f"{'; '.join(r.get('outside', [])[:2])}")
EOF
