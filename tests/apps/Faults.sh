#!/usr/bin/env bash
# Faults injected into real runs of `engage` (registered with ctest as apps.faults):
#   a full disk (tmpfs), a read-only folder, SIGKILL and SIGINT at chosen points of a run, two
#   runs into one folder at once, an earlier run's files in the output folder, a batch on a
#   full disk. After each: the exit status, the message, and what the folder holds: either
#   nothing new, or one complete run (summary.json last, its steps.csv complete, no .part file).
# Needs root to mount tmpfs; without it prints why and exits 77 (ctest: skipped).
#   bash tests/apps/Faults.sh build/apps/engage data /tmp/engage-faults
set -u
engage=$1
data=$(cd "$2" && pwd)
work=$3
rm -rf "$work"
mkdir -p "$work"
passed=0
failed=0
crashes=0
check() {  # check NAME COMMAND...: one row of the table
  if "${@:2}"; then passed=$((passed + 1)); else echo "FAIL: $1"; failed=$((failed + 1)); fi
}
run() {  # run OUT ARGS...: engage simulate on the Fusion 360 pocket into OUT; sets rc
  "$engage" simulate "$data/gcode/dialects/fusion360_pocket.nc" --tool flat --diameter 6mm \
    --stock box:0,0,-10,60,60,0 --quiet --out "$@" >"$work/out.txt" 2>"$work/err.txt"
  rc=$?
  if [ "$rc" -ge 128 ] || [ "$rc" -eq 3 ]; then crashes=$((crashes + 1)); fi
}
complete() {  # the folder holds one complete run
  local d=$1
  [ -f "$d/summary.json" ] && [ -f "$d/stock.stl" ] && [ -f "$d/removed.vdb" ] || return 1
  ! ls -A "$d" | grep -q '\.part' || return 1
  local steps
  steps=$(python3 -c "import json; print(json.load(open('$d/summary.json'))['steps'])") || return 1
  [ "$(wc -l <"$d/steps.csv")" -eq $((steps + 1)) ]
}
nothing_or_complete() { [ ! -f "$1/summary.json" ] || complete "$1"; }
# (a killed run's hidden staging folder, .engage-partial-HOST-PID, is removed by the next run)
no_part_files() { ! ls -A "$1" | grep -q '\.part'; }
says() { grep -q "$1" "$work/err.txt"; }
absent() { [ ! -e "$1" ]; }
nonzero() { [ "$rc" -ne 0 ]; }

full=$work/full
mkdir -p "$full"
if ! mount -t tmpfs -o size=1200k tmpfs "$full" 2>/dev/null; then
  echo "faults: cannot mount a tmpfs here (needs root): skipped"
  exit 77
fi
ro=$work/ro
mkdir -p "$ro"
mount -t tmpfs -o ro,size=1m tmpfs "$ro"
trap 'umount "$full" 2>/dev/null; umount "$ro" 2>/dev/null' EXIT

# A full disk: a clear error naming the file, nothing left.
run "$full/out"
check "full disk: non-zero exit" nonzero
check "full disk: says so" says "No space left on device"
check "full disk: names the file" says "cannot write '"
check "full disk: leaves nothing" absent "$full/out"

# A batch on a full disk: an error, no crash, no job folder that looks complete.
cat >"$work/manifest.json" <<JSON
{"jobs": [{"program": "$data/gcode/dialects/fusion360_pocket.nc", "tool": "flat",
           "diameter": "6mm", "stock": "box:0,0,-10,60,60,0"}]}
JSON
"$engage" batch "$work/manifest.json" --out "$full/batch" --quiet >"$work/out.txt" 2>"$work/err.txt"
rc=$?
if [ "$rc" -ge 128 ] || [ "$rc" -eq 3 ]; then crashes=$((crashes + 1)); fi
check "batch, full disk: non-zero exit" nonzero
check "batch, full disk: says so" says "No space left on device"
check "batch, full disk: no zero-byte record" \
  bash -c "! find '$full/batch' -name job.json -size 0 | grep -q ."
umount "$full"

# A read-only folder.
run "$ro/out"
check "read-only: non-zero exit" nonzero
check "read-only: says so" says "Read-only file system"

# An earlier run's files do not stay beside a new run's.
out=$work/again
"$engage" schedule "$data/gcode/paper/fig9_corner.ngc" --tool flat --diameter 6mm \
  --stock box:-30,-10,-10,10,30,0 --quiet --out "$out" >/dev/null 2>&1
check "earlier run: its re-fed program was there" test -f "$out/fig9_corner.ngc"
run "$out"
check "earlier run: new run complete" complete "$out"
check "earlier run: its re-fed program is gone" absent "$out/fig9_corner.ngc"
check "earlier run: its feed plot is gone" absent "$out/feed.png"

# SIGKILL and SIGINT at chosen points of a longer run, into a folder holding a complete run:
# while it simulates (after 0.1 to 0.6 s of its CPU time), when its staging folder appears,
# while it writes steps.csv, stock.vdb or report.html (the file there, or its .part), and
# just before it publishes (summary.json staged). Each kill hits a working process (the
# event is waited for, not a wall-clock time); its exit status is checked: 137 for SIGKILL,
# 130 for SIGINT (0 only where the run had already published, and then it is complete).
out=$work/killed
run "$out"
cpu_seconds() {  # user + system CPU time of process $1, s
  awk '{ printf "%.2f", ($14 + $15) / 100 }' "/proc/$1/stat" 2>/dev/null || echo 0
}
# The run's own staging folder, .engage-partial-HOST-PID: a killed run's stays in $out until
# the next run gets as far as making its own, and a SIGINT at the sight of it came too early
# (in the run's simulation, or before its handler, which the background job ignores).
staged() {  # staged PID FILE: run PID's staging folder in $out holds FILE (or FILE.part)
  local d
  for d in "$out"/.engage-partial-*-"$1"; do
    [ -e "$d/$2" ] || [ -e "$d/$2.part" ] && return 0
  done
  return 1
}
reached() {  # reached PID EVENT: cpu:SECONDS | staging | file:NAME
  case $2 in
    cpu:*) awk -v a="$(cpu_seconds "$1")" -v b="${2#cpu:}" 'BEGIN { exit !(a >= b) }' ;;
    staging) compgen -G "$out/.engage-partial-*-$1" >/dev/null ;;
    file:*) staged "$1" "${2#file:}" ;;
  esac
}
hits=0
for event in cpu:0.1 cpu:0.3 cpu:0.6 staging file:steps.csv file:stock.vdb file:report.html \
  file:summary.json; do
  for sig in KILL INT; do
    "$engage" simulate "$data/gcode/bench/finishing_raster.ngc" --tool ball --diameter 1mm \
      --stock box:0,0,-10,65,65,0 --voxel 0.3mm --quiet --out "$out" >/dev/null 2>&1 &
    pid=$!
    hit=0
    for _ in $(seq 6000); do  # at most 60 s
      kill -0 "$pid" 2>/dev/null || break
      if reached "$pid" "$event"; then
        kill -s "$sig" "$pid" 2>/dev/null && hit=1
        break
      fi
      sleep 0.01
    done
    wait "$pid" 2>/dev/null  # (bash's "Killed" line is not the run's)
    rc=$?
    # (A file written within one 10 ms poll can be missed; then the run has ended by itself.)
    if [ "$hit" -eq 1 ]; then
      hits=$((hits + 1))
    else
      echo "faults: kill -$sig at $event: the run ended before the event was seen (rc $rc)"
      check "kill -$sig at $event: a run not killed ended complete" complete "$out"
    fi
    expected=$([ "$sig" = KILL ] && echo 137 || echo 130)
    if [ "$hit" -eq 1 ] && [ "$rc" -ne "$expected" ]; then
      # (0 only where the signal came as the run ended, its files published)
      check "kill -$sig at $event: exit $expected, or 0 for a published run (got $rc)" \
        test "$rc" -eq 0
      check "kill -$sig at $event: a run that ended is complete" complete "$out"
    fi
    if [ "$sig" = INT ]; then
      check "kill -$sig at $event: no staging folder left" \
        bash -c "! compgen -G '$out/.engage-partial-*' >/dev/null"
    fi
    check "kill -$sig at $event: the folder holds one complete run or none" \
      nothing_or_complete "$out"
    check "kill -$sig at $event: no half-written file" no_part_files "$out"
  done
done
check "at least 14 of the 16 kills hit a working run (got $hits)" test "$hits" -ge 14
run "$out"
check "after the kills: a new run completes" complete "$out"
check "after the kills: no staging folder left" bash -c "! ls -A '$out' | grep -q engage-partial"

# SIGINT and SIGTERM into a new folder: the run stops at its next step (or before it publishes)
# with status 130 and removes the folders it made; a second signal is not needed.
for t in 0.5 1.5 2.5 3.5; do
  for sig in INT TERM; do
    out=$work/fresh/run
    rm -rf "$work/fresh"
    "$engage" simulate "$data/gcode/bench/finishing_raster.ngc" --tool ball --diameter 1mm \
      --stock box:0,0,-10,65,65,0 --voxel 0.2mm --quiet --out "$out" >/dev/null 2>"$work/err.txt" &
    pid=$!
    sleep "$t"
    kill -s "$sig" "$pid" 2>/dev/null
    wait "$pid"
    rc=$?
    if [ "$rc" -eq 130 ]; then
      check "kill -$sig at $t s: nothing left of the new folder" absent "$work/fresh"
      check "kill -$sig at $t s: says it was interrupted" grep -q "engage: interrupted" "$work/err.txt"
    else
      check "kill -$sig at $t s: exit 130, or 0 for a run that had ended (got $rc)" test "$rc" -eq 0
      check "kill -$sig at $t s: a run that ended is complete" complete "$out"
    fi
  done
done

# SIGINT while the stock files of a fine grid are made (OpenVDB's level set cannot be asked to
# stop): the run ends within a second, exit 130, its new folder removed. The 40 x 30 mm board
# (12 million rays): its stock files take 2.5-4.5 s after steps.csv (the 20 x 15 mm board's
# were over within 2 s on two cores, before the later SIGINT came).
python3 "$data/../tests/bench/pcb_isolation.py" >"$work/pcb40.ngc"
python3 "$data/../tests/bench/pcb_isolation.py" --width 20 --height 15 >"$work/pcb.ngc"
for wait_after in 0.5 1.5; do
  out=$work/fine/run
  rm -rf "$work/fine"
  "$engage" simulate "$work/pcb40.ngc" --tool flat --diameter 0.2mm --stock box:0,0,-1.6,40,30,0 \
    --out "$out" >/dev/null 2>"$work/err.txt" &
  pid=$!
  for _ in $(seq 6000); do  # the outputs begin: steps.csv staged (at most 60 s)
    kill -0 "$pid" 2>/dev/null || break
    staged "$pid" steps.csv && break
    sleep 0.01
  done
  sleep "$wait_after"
  start=$(date +%s.%N)
  kill -INT "$pid" 2>/dev/null
  wait "$pid"
  rc=$?
  took=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }')
  echo "faults: SIGINT $wait_after s into the fine grid's outputs: exit $rc after $took s"
  [ "$rc" -eq 130 ] || sed 's/^/faults: its stderr: /' "$work/err.txt"
  check "SIGINT in the stock files: exit 130 (got $rc)" test "$rc" -eq 130
  check "SIGINT in the stock files: ended within a second (took $took s)" \
    awk -v t="$took" 'BEGIN { exit !(t < 1.0) }'
  check "SIGINT in the stock files: nothing left of the new folder" absent "$work/fine"
done

# Out of memory: under an address-space limit (a cluster job's) a run too large for it is
# refused before it starts with its estimate, a program that never ends is refused at the
# moves the memory holds, and an allocation that fails anyway ends as "out of memory", exit 8:
# never an abort. Each leaves no folder.
rm -rf "$work/oom"
(ulimit -v 2500000; "$engage" simulate "$work/pcb.ngc" --tool flat --diameter 0.1mm \
  --stock box:0,0,-1.6,20,15,0 --out "$work/oom/run" >/dev/null 2>"$work/err.txt")
rc=$?
check "too large for ulimit -v: refused up front (exit 1; got $rc)" test "$rc" -eq 1
check "too large for ulimit -v: says its estimate" says "this run needs about .* may use"
check "too large for ulimit -v: no folder" absent "$work/oom"
printf 'G21 G90 F600\nG0 X0 Y0 Z1\nG1 Z-1\no100 while [1]\nG1 X10\nG1 X0\no100 endwhile\nM2\n' \
  >"$work/endless.ngc"
(ulimit -v 2500000; "$engage" simulate "$work/endless.ngc" --tool flat --diameter 6mm \
  --stock box:-5,-5,-5,15,5,0 --out "$work/oom/run" >/dev/null 2>"$work/err.txt")
rc=$?
check "a loop that never ends under ulimit -v: refused (exit 1; got $rc)" test "$rc" -eq 1
check "a loop that never ends under ulimit -v: at the moves the memory holds" \
  says "moves in a program (what .* holds with their steps: the address-space limit"
check "a loop that never ends under ulimit -v: no folder" absent "$work/oom"
# (1.0 GB: the run's peak is 1.3 GB; at 1.5 GB it ran through once on a loaded machine, its
# threads' heaps then fewer.)
(ulimit -v 1000000; "$engage" simulate "$work/pcb.ngc" --tool flat --diameter 0.1mm \
  --stock box:0,0,-1.6,20,15,0 --max-memory 100GB --out "$work/oom/run" >/dev/null \
  2>"$work/err.txt")
rc=$?
check "past ulimit -v with --max-memory: out of memory, exit 8 (got $rc)" test "$rc" -eq 8
check "past ulimit -v with --max-memory: says out of memory" says "engage: out of memory"
check "past ulimit -v with --max-memory: no folder" absent "$work/oom"

# A batch interrupted: no record for the job it was running, and the next run completes it.
out=$work/batch_int
rm -rf "$out"
"$engage" batch "$data/../tests/data/batch/manifest.json" --out "$out" --quiet >/dev/null 2>&1 &
pid=$!
sleep 0.7
kill -INT "$pid" 2>/dev/null
wait "$pid"
rc=$?
# 130, or 4 if it had ended (its broken job fails by design).
check "batch interrupted: exit 130 (or 4: it had ended; got $rc)" test "$rc" -eq 130 -o "$rc" -eq 4
check "batch interrupted: no partial job folder" bash -c "! ls '$out/jobs' | grep -q partial"
"$engage" batch "$data/../tests/data/batch/manifest.json" --out "$out" --quiet >/dev/null 2>&1
check "batch interrupted: the rerun records every job" test "$(ls "$out"/jobs/*/job.json | wc -l)" -eq 5

# Two runs into one folder at once.
out=$work/both
"$engage" simulate "$data/gcode/dialects/fusion360_pocket.nc" --tool flat --diameter 6mm \
  --stock box:0,0,-10,60,60,0 --quiet --out "$out" >/dev/null 2>"$work/err1.txt" &
p1=$!
"$engage" simulate "$data/gcode/paper/fig9_corner.ngc" --tool flat --diameter 6mm \
  --stock box:-30,-10,-10,10,30,0 --quiet --out "$out" >/dev/null 2>"$work/err2.txt" &
p2=$!
wait "$p1"
r1=$?
wait "$p2"
r2=$?
check "two at once: both succeed" test "$r1" -eq 0 -a "$r2" -eq 0
check "two at once: one complete run in the folder" complete "$out"

# Two batches into one folder at once: every job runs once, no failed record but the broken
# program's, no crash; the merged table holds every job.
out=$work/batches
"$engage" batch "$data/../tests/data/batch/manifest.json" --out "$out" --quiet \
  >"$work/b1.txt" 2>&1 &
p1=$!
"$engage" batch "$data/../tests/data/batch/manifest.json" --out "$out" --quiet \
  >"$work/b2.txt" 2>&1 &
p2=$!
wait "$p1"
r1=$?
wait "$p2"
r2=$?
for r in $r1 $r2; do if [ "$r" -ge 128 ] || [ "$r" -eq 3 ]; then crashes=$((crashes + 1)); fi; done
runs=$(cat "$work/b1.txt" "$work/b2.txt" | grep -c '^batch: \[')
jobs=$(ls "$out/jobs" | grep -vc '\.lock$')
check "two batches: every job run once" test "$runs" -eq "$jobs"
check "two batches: only the broken program failed" \
  test "$(grep -l '"status": "failed"' "$out"/jobs/*/job.json | wc -l)" -eq 1
"$engage" merge "$data/../tests/data/batch/manifest.json" --out "$out" >/dev/null 2>&1
check "two batches: the merge finds every job" test $? -eq 0

echo "faults: $passed passed, $failed failed (crashes: $crashes)"
[ "$failed" -eq 0 ] && [ "$crashes" -eq 0 ]
