#!/bin/bash
# Run an engage batch as a Slurm job array: one shard of the manifest per array task, all
# writing into one shared output folder; then merge once every task has ended.
#
#   export MANIFEST=$PWD/data/batch/manifest.json OUT=$PWD/out/batch ENGAGE=$PWD/build/apps/engage
#   jobid=$(sbatch --parsable --array=0-7 scripts/slurm_batch.sh)
#   sbatch --dependency=afterany:$jobid --wrap "$ENGAGE merge $MANIFEST --out $OUT"
#
# A task whose shard holds a failed job exits 1 (its error is in OUT/jobs/NAME/job.json);
# `afterany` merges anyway. Resubmitting the array reruns only the jobs without a record.
#SBATCH --job-name=engage-batch
#SBATCH --cpus-per-task=2
#SBATCH --output=engage-batch-%A_%a.log
set -euo pipefail
: "${MANIFEST:?set MANIFEST}" "${OUT:?set OUT}"
ENGAGE=${ENGAGE:-engage}
"$ENGAGE" batch "$MANIFEST" --out "$OUT" --quiet \
  --shard "${SLURM_ARRAY_TASK_ID}/${SLURM_ARRAY_TASK_COUNT}"
