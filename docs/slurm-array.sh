#!/usr/bin/env bash
# A Slurm job array that runs one experiment in N shards, then collects the results.
# From the project folder (the one with docs/ and experiments/), on a filesystem every
# node mounts:
#
#   mkdir -p logs
#   job=$(sbatch --parsable --array=0-7 docs/slurm-array.sh experiments/sweep.toml)
#   sbatch --dependency=afterany:$job --output=logs/collect-%j.out \
#       --wrap "dcnet-exp collect experiments/sweep.toml --out ${DCNET_RESULTS:-/shared/results}"
#
# Every shard writes its models and Monte Carlo blocks into /shared/results/.cache/ on
# the shared filesystem; `collect` puts the results folders together from them. The
# array indices must run from 0 to N-1 (N = the array size): dcnet-exp reads K from
# SLURM_ARRAY_TASK_ID. A shard that is killed or preempted resumes where it stopped when
# it is requeued (training checkpoints, stored blocks), so --requeue is safe. A shard
# whose model fails (a diverging training) exits 2 and the others go on; collect, run
# after every task whatever its end (afterany), writes the results without that model
# and exits 2 naming it. Each task's log says, at most every 30 s, how far its tasks are.
#
# sbatch's options override the #SBATCH lines (--cpus-per-task=2 --mem=4G on a small
# node). The environment passes to the jobs: DCNET_RESULTS sets the results folder,
# DCNET_LOG_EVERY the seconds between progress lines, and dcnet-exp must be on PATH.
# scripts/slurm-e2e.sh submits this file, unchanged, to a one-node Slurm.
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
