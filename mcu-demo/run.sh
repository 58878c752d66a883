#!/usr/bin/env bash
# Builds the Cortex-M4F demo and runs it under QEMU (mps2-an386). Exit code 0 only if every
# check in the firmware passed (semihosting exit status). Needs: rustup target
# thumbv7em-none-eabihf, qemu-system-arm (Debian: apt-get install qemu-system-arm).
set -euo pipefail
cd "$(dirname "$0")"
cargo build --release
# the panic-freedom build: links only if no panic path survives optimisation
cargo build --release --features panic-check --target-dir target/panic-check
# honour a CARGO_TARGET_DIR set by the caller (CI caches, shared target dirs)
elf=${CARGO_TARGET_DIR:-target}/thumbv7em-none-eabihf/release/mcu-demo
timeout 120 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
  -semihosting-config enable=on,target=native -icount shift=0 -kernel "$elf"
