#!/usr/bin/env bash
# Builds firmware-core-ffi's host staticlib, compiles the C test against the committed header
# with strict warnings, runs it; then checks that the crate builds no_std for the Cortex-M
# targets (the staticlib C firmware links).
set -euo pipefail
cd "$(dirname "$0")/../.."
# the committed header is what cbindgen makes of the crate (its own package, outside the
# workspace: cbindgen is not compiled by `cargo test --workspace`)
cargo run -q --manifest-path firmware-core-ffi/header-check/Cargo.toml --target-dir target/header-check
cargo build -q --release -p firmware-core-ffi
out=target/ffi-c
mkdir -p "$out"
gcc -std=c99 -Wall -Wextra -Werror -pedantic -O2 -I firmware-core-ffi/include \
  firmware-core-ffi/c/test_host.c target/release/libfirmware_core_ffi.a \
  -lpthread -ldl -lm -o "$out/test_host"
"$out/test_host"
cargo build -q --release -p firmware-core-ffi --no-default-features --target thumbv7em-none-eabihf
cargo build -q --release -p firmware-core-ffi --no-default-features --target thumbv6m-none-eabi
ls -l target/thumbv7em-none-eabihf/release/libfirmware_core_ffi.a
