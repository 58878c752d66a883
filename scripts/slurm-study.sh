#!/bin/bash
# A Slurm job array for a study too large for one machine: each array task computes one shard
# (runs r with r mod N = K-1, K = 1..N counted from the array's first index) into its own
# directory, with --resume so a preempted task that is requeued continues where it stopped.
# Merge afterwards (on any node) with
#
#   host-harness merge out/paper/shard-* --out out/paper/merged
#
# which writes exactly the summary an unsharded study gives (same seed => same numbers).
#
# Submit from the repository root after `cargo build --release -p host-harness`:
#   sbatch scripts/slurm-study.sh
# Options on the sbatch command line override the #SBATCH lines (e.g. --array=1-64,
# --cpus-per-task=4); the environment sets the study: RUNS (1000), SEED (1), EXPOSURES (comma
# list in ms; default the preset's), OUT (out/paper), HOST_HARNESS (the binary).
#SBATCH --job-name=vibcam-study
#SBATCH --array=1-16
#SBATCH --cpus-per-task=8
#SBATCH --mem=4G
#SBATCH --time=01:00:00
#SBATCH --requeue
#SBATCH --open-mode=append
set -euo pipefail
: "${SLURM_ARRAY_TASK_ID:?run this as a Slurm array job (sbatch scripts/slurm-study.sh)}"
N=${SLURM_ARRAY_TASK_COUNT:-16}
K=$((SLURM_ARRAY_TASK_ID - ${SLURM_ARRAY_TASK_MIN:-1} + 1))
OUT=${OUT:-out/paper}
HH=${HOST_HARNESS:-./target/release/host-harness}
EXTRA=()
if [ -n "${EXPOSURES:-}" ]; then EXTRA+=(--exposures-ms "$EXPOSURES"); fi
mkdir -p "$OUT"
echo "task $SLURM_ARRAY_TASK_ID (shard $K/$N) of job ${SLURM_ARRAY_JOB_ID:-?} on $(hostname), restart ${SLURM_RESTART_COUNT:-0}"
exec "$HH" study --preset grandstand --runs "${RUNS:-1000}" --seed "${SEED:-1}" "${EXTRA[@]}" \
  --threads "${SLURM_CPUS_PER_TASK:-1}" --shard "$K/$N" --out "$OUT/shard-$K" --resume --no-plots
