#!/usr/bin/env bash
# `cmake --install` into a fresh prefix, as a user installs engage: the installed program finds
# the installed data (its --version names the folder), simulates with a bundled material from
# there, and the installed Python module imports and runs a job.
#   bash tests/apps/Install.sh BUILD_DIR WORK_DIR
set -euo pipefail
build=$1
work=$2
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" > "$work/install.log"
exe="$prefix/bin/engage"
data="$prefix/share/engage/data"
version=$(env -u ENGAGE_DATA "$exe" --version)
if [ "$version" != "engage 0.1.0 (data: $data)" ]; then
  echo "installed engage does not use its installed data: '$version'" >&2
  exit 1
fi
test -f "$data/materials/aluminium-7075-t6.json"
test ! -e "$data/readme" || { echo "the README's pictures were installed" >&2; exit 1; }
env -u ENGAGE_DATA "$exe" simulate "$data/gcode/paper/fig9_corner.ngc" --tool flat \
  --diameter 6mm --stock box:-30,-10,-10,10,30,0 --material aluminium-7075-t6 \
  --spindle 10000rpm --outputs summary --out "$work/run" --quiet > "$work/run.log"
grep -q '"material": "Aluminium 7075-T6"' "$work/run/summary.json" ||
  { echo "the installed run's summary names no material" >&2; exit 1; }
module=$(ls "$prefix"/lib/python3/dist-packages/engage*.so 2>/dev/null | head -1)
if [ -n "$module" ]; then
  (cd "$work" && env -u ENGAGE_DATA PYTHONPATH="$prefix/lib/python3/dist-packages" /usr/bin/python3 -c "
import engage
r = engage.run(program='$data/gcode/paper/fig9_corner.ngc', tool='flat', diameter='6mm',
               stock='box:-30,-10,-10,10,30,0', material='aluminium-7075-t6', spindle='10000rpm')
assert r.removed_mm3 > 0, r.removed_mm3
print('python: removed', r.removed_mm3, 'mm^3')
")
fi
echo "installed into $prefix: engage, its data and the Python module work from there"
