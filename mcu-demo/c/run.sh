#!/usr/bin/env bash
# The C demo: mcu-demo/c/main.c, compiled with arm-none-eabi-gcc against the committed header
# (c99, -Wall -Wextra -Werror), linked with firmware-core-ffi's no_std staticlib for the
# Cortex-M4F, run under QEMU (mps2-an386). Exit 0 only if every check passed. Also the C
# boundary's panic-freedom: with --gc-sections nothing of Rust's panic machinery may be left in
# the linked image. Needs: gcc-arm-none-eabi, qemu-system-arm, the thumbv7em-none-eabihf target.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build -q --release -p firmware-core-ffi --no-default-features --target thumbv7em-none-eabihf
out=target/mcu-demo-c
mkdir -p "$out"
arm-none-eabi-gcc -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -std=c99 -Wall \
  -Wextra -Werror -O2 -ffunction-sections -fdata-sections -ffreestanding -nostdlib -Wa,--noexecstack \
  -I firmware-core-ffi/include -T mcu-demo/c/link.ld -Wl,--gc-sections \
  mcu-demo/c/main.c target/thumbv7em-none-eabihf/release/libfirmware_core_ffi.a -lgcc \
  -o "$out/demo.elf"
arm-none-eabi-size "$out/demo.elf"
if arm-none-eabi-nm -C "$out/demo.elf" | grep -i -e "panic" -e "rust_begin_unwind"; then
  echo "a panic path survived in the C demo's image" >&2
  exit 1
fi
timeout 120 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
  -semihosting-config enable=on,target=native -kernel "$out/demo.elf"
