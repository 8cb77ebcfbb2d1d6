#!/usr/bin/env bash
# The README's pictures of report.html, taken in headless Chromium (Debian's chromium):
#   scripts/report_screenshots.sh [ENGAGE]   (default build/apps/engage; about 2 minutes)
# writes data/readme/report_run.png (a schedule with cutting physics, the step of the peak
# force selected), report_paper.png (`engage paper`, the demo) and report_batch.png (the
# example batch, data/batch/manifest.json).
set -euo pipefail
cd "$(dirname "$0")/.."
engage=$(realpath "${1:-build/apps/engage}")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
shot() {  # shot URL PNG WIDTH HEIGHT
  chromium --headless --no-sandbox --disable-dev-shm-usage --enable-unsafe-swiftshader \
    --use-angle=swiftshader --user-data-dir="$tmp/profile" --hide-scrollbars \
    --window-size="$3,$4" --virtual-time-budget=8000 --screenshot="$2" "$1" >/dev/null 2>&1
  echo "wrote $2"
}
"$engage" schedule data/gcode/paper/fig9_corner.ngc --tool flat --diameter 6mm \
  --stock box:-30,-10,-10,10,30,0 --material aluminium-7075-t6 --spindle 10000rpm \
  --max-chip 0.04mm --max-power 0.3kW --out "$tmp/run" --quiet >/dev/null
step=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['physics']['peaks']['f_peak']['step'])" "$tmp/run/summary.json")
shot "file://$tmp/run/report.html#step=$step" data/readme/report_run.png 1400 1700
"$engage" paper --out "$tmp/paper" --quiet >/dev/null
shot "file://$tmp/paper/report.html" data/readme/report_paper.png 1400 1300
"$engage" batch data/batch/manifest.json --out "$tmp/batch" --quiet >/dev/null 2>&1 || true
shot "file://$tmp/batch/report.html" data/readme/report_batch.png 1400 1150
