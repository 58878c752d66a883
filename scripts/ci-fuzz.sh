#!/usr/bin/env bash
# Runs every cargo-fuzz target of fuzz/ for a fixed time: FUZZ_SECONDS each
# (default 40), starting from the committed corpus in fuzz/corpus/TARGET. Installs the nightly
# toolchain and cargo-fuzz when missing. A crash fails the step and leaves the input in
# fuzz/artifacts/TARGET/ (turn it into a regression test).
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
secs="${FUZZ_SECONDS:-40}"
log() { echo "[ci-fuzz +${SECONDS}s] $*"; }
rustup toolchain list | grep -q '^nightly' || rustup toolchain install nightly --profile minimal
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked --version 0.13.2
targets=$(cargo +nightly fuzz list)
log "building: $(echo $targets)"
cargo +nightly fuzz build -O
for t in $targets; do
  mkdir -p "corpus/$t"
  log "$t: ${secs} s"
  cargo +nightly fuzz run -O "$t" "corpus/$t" -- -max_total_time="$secs" -rss_limit_mb=2048 \
    -print_final_stats=1 2>&1 | grep -E 'Done|stat::number_of_executed_units|ERROR|panicked|SUMMARY' || true
  if [ -n "$(ls -A "artifacts/$t" 2>/dev/null)" ]; then
    log "$t: crash inputs in fuzz/artifacts/$t"; exit 1
  fi
done
log "no crash"
