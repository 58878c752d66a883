#!/usr/bin/env bash
# The figures the Rust demo and the C demo both print, compared as text: the centroid of the
# Rust demo's 320 x 240 disk frame (binary and weighted) and the vision pipeline's H1 and peak
# for the C demo's 7 Hz motion. Both demos make the same inputs bit for bit, so firmware-core
# called from Rust and through the C ABI must print the same lines.
# Usage: same_figures.sh RUST_DEMO_OUTPUT C_DEMO_OUTPUT (the captured QEMU output of each)
set -euo pipefail
[ $# -eq 2 ] || { echo "usage: $0 RUST_DEMO_OUTPUT C_DEMO_OUTPUT" >&2; exit 2; }
pick() { grep -E '^(centroid u8  (Binary|Weighted):|pipeline: H1\(7 Hz\)( bits)?)' "$1" | tr -d '\r' || true; }
rust=$(pick "$1")
c=$(pick "$2")
n=$(printf '%s\n' "$rust" | grep -c . || true)
if [ "$n" -ne 4 ]; then
  echo "same_figures.sh: $1 has $n of the 4 shared lines" >&2
  exit 1
fi
if [ "$rust" != "$c" ]; then
  echo "same_figures.sh: the demos differ" >&2
  diff <(printf '%s\n' "$rust") <(printf '%s\n' "$c") >&2 || true
  exit 1
fi
echo "the Rust and the C demo print the same figures:"
printf '  %s\n' "$rust" | sed 's/^  //; s/^/  /'
