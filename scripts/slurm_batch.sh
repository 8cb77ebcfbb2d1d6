#!/bin/bash
# An engage batch on Slurm: a job array, one shard of the manifest per task (task i runs
# shard i/SHARDS), all writing into one shared output folder, then a merge job once every task
# has ended (afterany). Logs go to OUT/logs/.
#
#   scripts/slurm_batch.sh submit MANIFEST OUT SHARDS [sbatch options...]
#     e.g. scripts/slurm_batch.sh submit data/batch/manifest.json /shared/out 8 \
#            --partition=cpu --account=lab --time=02:00:00 --mem-per-cpu=4G
#   Resubmit any subset of shards with the same SHARDS: ... 8 --array=3,5
#   CPUS (default 2) CPUs per task; engage uses the CPUs Slurm gives it (affinity, cgroup).
#   ENGAGE may be a command with arguments, e.g. ENGAGE="apptainer exec engage.sif engage"
#   (compute nodes rarely have Debian's OpenVDB and TBB).
#
# A task whose shard holds a failed job exits 4 (the error is in OUT/jobs/NAME/job.json), one
# whose jobs ran but met material with a rapid, shank or holder exits 5; the merge runs anyway
# (afterany) and lists every job. Jobs with a record for the same options and files are
# not run again, and a job never runs in two tasks at once (a lock per job).
#
#   scripts/slurm_batch.sh task MANIFEST OUT SHARDS   (what each array task runs)
set -euo pipefail
usage="usage: $0 submit|task MANIFEST OUT SHARDS [sbatch options...]"
[ $# -ge 4 ] || { echo "$usage" >&2; exit 2; }
mode=$1
manifest=$(realpath "$2")
out=$(realpath -m "$3")
shards=$4
shift 4
[[ $shards =~ ^[1-9][0-9]*$ ]] || { echo "$0: SHARDS must be a positive number, found '$shards'" >&2; exit 2; }
read -r -a engage <<<"${ENGAGE:-engage}"
case $mode in
  submit)
    mkdir -p "$out/logs"
    array="--array=0-$((shards - 1))"
    extra=()
    for a in "$@"; do
      case $a in
        --array=*) array=$a ;;
        *) extra+=("$a") ;;
      esac
    done
    jobid=$(sbatch --parsable --job-name=engage-batch --cpus-per-task="${CPUS:-2}" "$array" \
      --output="$out/logs/shard-%a.log" "${extra[@]}" "$0" task "$manifest" "$out" "$shards")
    merge=$(printf '%q ' "${engage[@]}" merge "$manifest" --out "$out")
    mergeid=$(sbatch --parsable --job-name=engage-merge --dependency="afterany:$jobid" \
      --output="$out/logs/merge.log" "${extra[@]}" --wrap "$merge")
    echo "submitted array $jobid ($array of $shards shards) and merge $mergeid; logs in $out/logs"
    ;;
  task)
    : "${SLURM_ARRAY_TASK_ID:?run by Slurm as an array task}"
    (( SLURM_ARRAY_TASK_ID < shards )) || {
      echo "$0: array task $SLURM_ARRAY_TASK_ID is not a shard of $shards (tasks are 0..$((shards - 1)))" >&2
      exit 2
    }
    exec "${engage[@]}" batch "$manifest" --out "$out" --quiet \
      --shard "$SLURM_ARRAY_TASK_ID/$shards"
    ;;
  *)
    echo "$usage" >&2
    exit 2
    ;;
esac
