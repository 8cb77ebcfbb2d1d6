#!/usr/bin/env bash
# scripts/slurm_batch.sh against a stand-in for sbatch (registered with ctest as
# apps.slurm_script): the stand-in runs each array task in turn with SLURM_ARRAY_TASK_ID set and
# its output in the --output file, and the merge after them, as Slurm would. Checks: 3 shards
# merged equal a local batch (every column but the run time), logs in OUT/logs, a resubmission
# of one shard alone, ENGAGE as a command with arguments. A real Slurm is not needed.
#   bash tests/apps/SlurmScript.sh build/apps/engage SOURCE_DIR WORK
set -u
engage=$(realpath "$1")
source_dir=$(realpath "$2")
work=$3
rm -rf "$work"
mkdir -p "$work/bin"
cat >"$work/bin/sbatch" <<'STUB'
#!/usr/bin/env bash
# Stand-in for sbatch: --array=LIST, --output=PATTERN, --wrap=COMMAND or SCRIPT ARGS.
array="" output=/dev/null wrap="" args=()
while [ $# -gt 0 ]; do
  case $1 in
    --array=*) array=${1#--array=} ;;
    --output=*) output=${1#--output=} ;;
    --wrap) wrap=$2; shift ;;
    --parsable | --job-name=* | --cpus-per-task=* | --dependency=* | --partition=* | \
      --account=* | --time=* | --mem*) ;;
    *) args+=("$1") ;;
  esac
  shift
done
echo "$array|${args[*]}" >>"$(dirname "$0")/submitted"
if [ -n "$wrap" ]; then bash -c "$wrap" >"$output" 2>&1; echo 2; exit 0; fi
tasks=()
IFS=, read -r -a parts <<<"$array"
for p in "${parts[@]}"; do
  if [[ $p == *-* ]]; then tasks+=($(seq "${p%-*}" "${p#*-}")); else tasks+=("$p"); fi
done
for t in "${tasks[@]}"; do
  SLURM_ARRAY_TASK_ID=$t bash "${args[@]}" >"${output//%a/$t}" 2>&1
done
echo 1
STUB
chmod +x "$work/bin/sbatch"
export PATH="$work/bin:$PATH"
manifest=$source_dir/tests/data/batch/manifest.json
failed=0
check() { if "${@:2}"; then :; else echo "FAIL: $1"; failed=$((failed + 1)); fi; }
table() { cut -d, -f1-5,7- "$1"; }  # batch.csv without run_time_s

"$engage" batch "$manifest" --out "$work/local" --quiet >/dev/null 2>&1
ENGAGE="env ENGAGE_WRAPPED=1 $engage" bash "$source_dir/scripts/slurm_batch.sh" submit \
  "$manifest" "$work/slurm" 3 --partition=cpu --time=00:10:00 >"$work/submit.txt"
check "submit says what it submitted" grep -q "submitted array 1 (--array=0-2 of 3 shards)" \
  "$work/submit.txt"
check "a log per shard and the merge's" test -s "$work/slurm/logs/shard-0.log" -a \
  -s "$work/slurm/logs/shard-2.log" -a -s "$work/slurm/logs/merge.log"
check "3 shards merged equal the local batch" \
  cmp <(table "$work/local/batch.csv") <(table "$work/slurm/batch.csv")
# One shard alone, resubmitted: it has run, nothing runs again, the merge still succeeds.
ENGAGE=$engage bash "$source_dir/scripts/slurm_batch.sh" submit "$manifest" "$work/slurm" 3 \
  --array=1 >/dev/null
check "a resubmitted shard runs alone" grep -q "shard 1/3" "$work/slurm/logs/shard-1.log"
check "and finds its jobs done" grep -q "0 run (0 failed)" "$work/slurm/logs/shard-1.log"
check "the merge after it" grep -q "merged 5 jobs" "$work/slurm/logs/merge.log"
check "a bad shard count is refused" bash -c \
  "! bash '$source_dir/scripts/slurm_batch.sh' submit '$manifest' '$work/x' 0 2>/dev/null"
echo "slurm script: $failed failed"
[ "$failed" -eq 0 ]
