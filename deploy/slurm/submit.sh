#!/usr/bin/env bash
# Submits a render split into N parts and its merge: a job array of N
# tasks (render.sbatch) and a merge job that starts when all of them
# succeeded (merge.sbatch, --dependency=afterok).
#
#   deploy/slurm/submit.sh SCENE OUTDIR N OUT.exr|OUT.png [render options...]
#
# Prints the two job ids. If a task fails for good, the merge job never
# starts (its dependency can no longer be met; --kill-on-invalid-dep=yes
# cancels it): resubmit that part (sbatch --array=K render.sbatch ...) and
# then the merge. Extra sbatch options go in SBATCH_RENDER and SBATCH_MERGE
# (e.g. SBATCH_RENDER="--partition=cpu --time=02:00:00").
set -euo pipefail
if [[ $# -lt 4 ]]; then
  sed -n '2,14p' "$0"
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
scene=$1 outdir=$2 parts=$3 image=$4
shift 4
mkdir -p "$outdir/logs"
# shellcheck disable=SC2086 # the extra options are words
array=$(sbatch --parsable ${SBATCH_RENDER:-} --array=0-$((parts - 1)) \
  --output="$outdir/logs/render-%A_%a.log" "$here/render.sbatch" "$scene" "$outdir" "$parts" "$@")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable ${SBATCH_MERGE:-} --dependency=afterok:"$array" --kill-on-invalid-dep=yes \
  --output="$outdir/logs/merge-%j.log" "$here/merge.sbatch" "$outdir" "$parts" "$image")
merge=${merge%%;*}
echo "render array: $array ($parts tasks), merge: $merge"
