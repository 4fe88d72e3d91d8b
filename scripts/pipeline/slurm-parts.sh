#!/usr/bin/env bash
# One large mesh baked as a Slurm job array: task K of N builds part K (mesh2svo --pages K/N),
# then a job that depends on the whole array merges the parts. Every node must see MESH and OUT
# (a shared file system) and have svokit's tools in BIN.
#
#   scripts/pipeline/slurm-parts.sh MESH OUT N "OPTIONS" [LIMIT]
#   e.g. scripts/pipeline/slurm-parts.sh scan.ply /shared/scan 64 "-r 65536 --bricks none --attributes none" 4G
#
# A rerun submits only the tasks whose part is missing (a task that died left no part file).
set -euo pipefail
mesh="${1:?mesh}" out="${2:?output directory}" parts="${3:?number of parts}"
options="${4:?mesh2svo options}" limit="${5:-4G}"
bin="${BIN:-$(cd "$(dirname "$0")/../.." && pwd)/build/apps}"
name="$(basename "${mesh%.*}")"
mkdir -p "$out"

missing=()
for ((k = 0; k < parts; ++k)); do
  [ -s "$out/part-$k-of-$parts.svopart" ] || missing+=("$k")
done
merge_deps=()
if ((${#missing[@]} > 0)); then
  array="$(IFS=,; echo "${missing[*]}")"
  # One core and the limit (plus room for the mesh) per task.
  job=$(sbatch --parsable --array="$array" --cpus-per-task=1 --mem="$((${limit%G} + 2))G" \
    --job-name="svo-$name" --output="$out/part-%a-of-$parts.log" \
    --wrap="'$bin/mesh2svo' '$mesh' -o '$out'/part-\$SLURM_ARRAY_TASK_ID-of-$parts.svopart \
            $options --pages \$SLURM_ARRAY_TASK_ID/$parts --memory-limit $limit -q -j 1")
  merge_deps=(--dependency="afterok:$job")
fi
sbatch "${merge_deps[@]}" --job-name="svo-$name-merge" --output="$out/$name.merge.log" \
  --wrap="'$bin/svo-merge' '$out'/part-*-of-$parts.svopart -o '$out/$name.svo' -q"
