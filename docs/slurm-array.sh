#!/usr/bin/env bash
# A Slurm job array that runs one experiment in N shards, then collects the results.
#
#   sbatch --array=0-7 docs/slurm-array.sh experiments/sweep.toml
#   sbatch --dependency=afterok:<array job id> --wrap \
#       "dcnet-exp collect experiments/sweep.toml --out /shared/results"
#
# Every shard writes its models and Monte Carlo blocks into /shared/results/.cache/ on
# the shared filesystem; `collect` puts the results folders together from them. The
# array indices must run from 0 to N-1 (N = the array size): dcnet-exp reads K from
# SLURM_ARRAY_TASK_ID. A shard that is killed or preempted resumes where it stopped when
# it is requeued (training checkpoints, stored blocks), so --requeue is safe.
#SBATCH --job-name=dcnet-exp
#SBATCH --cpus-per-task=8
#SBATCH --mem=16G
#SBATCH --time=04:00:00
#SBATCH --requeue
#SBATCH --output=logs/dcnet-exp-%A_%a.out
set -euo pipefail

spec=${1:?usage: sbatch --array=0-(N-1) docs/slurm-array.sh SPEC}
results=${DCNET_RESULTS:-/shared/results}
shards=${SLURM_ARRAY_TASK_COUNT:?run this script as a job array (sbatch --array=0-7)}

dcnet-exp --threads "${SLURM_CPUS_PER_TASK:-1}" run "$spec" --out "$results" --shard "$shards"
