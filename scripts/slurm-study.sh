#!/bin/bash
# A Slurm job array for a study too large for one machine: each array task computes one shard
# (runs r with r mod N = K-1) into its own directory, with --resume so a preempted task that is
# requeued continues where it stopped. Merge afterwards (on any node) with
#
#   host-harness merge out/paper/shard-* --out out/paper/merged
#
# which writes exactly the summary an unsharded study gives (same seed => same numbers).
#
# Submit from the repository root after `cargo build --release -p host-harness`:
#   sbatch scripts/slurm-study.sh
#SBATCH --job-name=vibcam-study
#SBATCH --array=1-16
#SBATCH --cpus-per-task=8
#SBATCH --mem=4G
#SBATCH --time=01:00:00
#SBATCH --requeue
set -euo pipefail
N=${SLURM_ARRAY_TASK_COUNT:-16}
K=${SLURM_ARRAY_TASK_ID:?run this as a Slurm array job}
OUT=${OUT:-out/paper}
mkdir -p "$OUT"
./target/release/host-harness study --preset grandstand --runs "${RUNS:-1000}" --seed "${SEED:-1}" \
  --threads "${SLURM_CPUS_PER_TASK:-1}" --shard "$K/$N" --out "$OUT/shard-$K" --resume --no-plots
