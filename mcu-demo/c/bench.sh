#!/usr/bin/env bash
# The C demo (mcu-demo/c/main.c) on four Cortex-M cores under QEMU: exact instruction counts of
# the centroid, one tracker frame, one multi-target frame, the output-only FDD of four targets
# and one second of the vision pipeline, with flash and RAM, as
# a Markdown table (docs/mcu.md). Each core gets the staticlib built for its own Rust target and
# CPU, the demo compiled for it, and its board's memory map. The Cortex-M0 board (micro:bit,
# 16 KiB of RAM) cannot hold the pipeline's 57 600 bytes or the FDD's 45 KiB: it runs the
# centroids and the tracker.
# Needs: gcc-arm-none-eabi, qemu-system-arm, gcc, rustup targets thumbv6m-none-eabi,
# thumbv7em-none-eabihf, thumbv8m.main-none-eabihf; ../shared/tools/qemu-icount.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
tools=${QEMU_ICOUNT:-$root/../shared/tools/qemu-icount}
[ -f "$tools/build.sh" ] || { echo "bench.sh: $tools/build.sh not found (set QEMU_ICOUNT)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
sh "$tools/build.sh" "$tmp" >/dev/null

# core | QEMU machine | QEMU cpu | Rust target | Rust cpu | gcc flags | flash | RAM | defines
cores=(
  "Cortex-M0|microbit|cortex-m0|thumbv6m-none-eabi|cortex-m0|-mcpu=cortex-m0 -mfloat-abi=soft|0x00000000 256K|0x20000000 16K|-DVC_NO_PIPELINE"
  "Cortex-M4F|mps2-an386|cortex-m4|thumbv7em-none-eabihf|cortex-m4|-mcpu=cortex-m4 -mfloat-abi=hard -mfpu=fpv4-sp-d16|0x00000000 4M|0x20000000 4M|"
  "Cortex-M7|mps2-an500|cortex-m7|thumbv7em-none-eabihf|cortex-m7|-mcpu=cortex-m7 -mfloat-abi=hard -mfpu=fpv5-d16|0x00000000 4M|0x20000000 4M|"
  "Cortex-M33|mps2-an505|cortex-m33|thumbv8m.main-none-eabihf|cortex-m33|-mcpu=cortex-m33 -mfloat-abi=hard -mfpu=fpv5-sp-d16|0x10000000 4M|0x38000000 2M|"
)
rows=()
for spec in "${cores[@]}"; do
  IFS='|' read -r name machine cpu target rcpu cflags flash ram defs <<<"$spec"
  rustup target add "$target" >/dev/null 2>&1 || true
  dir=target/mcu-c-bench/$machine
  CARGO_TARGET_DIR=$dir RUSTFLAGS="-C target-cpu=$rcpu" cargo build -q --release \
    -p firmware-core-ffi --no-default-features --target "$target"
  read -r fo fl <<<"$flash"
  read -r ro rl <<<"$ram"
  sed -e "s/FLASH : ORIGIN = 0x00000000, LENGTH = 4M/FLASH : ORIGIN = $fo, LENGTH = $fl/" \
      -e "s/RAM   : ORIGIN = 0x20000000, LENGTH = 4M/RAM   : ORIGIN = $ro, LENGTH = $rl/" \
      mcu-demo/c/link.ld >"$tmp/$machine.ld"
  # shellcheck disable=SC2086
  arm-none-eabi-gcc -mthumb $cflags -std=c99 -Wall -Wextra -Werror -O2 -ffunction-sections \
    -fdata-sections -ffreestanding -nostdlib -Wa,--noexecstack $defs \
    -I firmware-core-ffi/include -T "$tmp/$machine.ld" -Wl,--gc-sections mcu-demo/c/main.c \
    "$dir/$target/release/libfirmware_core_ffi.a" -lgcc -o "$tmp/$machine.elf"
  mark=$(arm-none-eabi-nm -t d "$tmp/$machine.elf" | awk '$3=="bench_mark"{printf "0x%x\n", $1 - $1 % 2}')
  timeout 600 qemu-system-arm -cpu "$cpu" -machine "$machine" -nographic \
    -semihosting-config enable=on,target=native -icount shift=0 \
    -plugin "$tmp/libmarks.so,mark=$mark" -d plugin -D "$tmp/$machine.log" \
    -kernel "$tmp/$machine.elf" >"$tmp/$machine.out" 2>&1
  grep -q "all checks passed" "$tmp/$machine.out" || { cat "$tmp/$machine.out"; echo "bench.sh: $name failed" >&2; exit 1; }
  # label k <-> plugin segment 2k-1; label 1 ("empty") is the marker's own overhead
  counts=$(awk '
    FNR==NR { if ($1=="bench:") { sub(/^bench: /, ""); label[++n]=$0 } next }
    $1=="marks:" && $2=="segment" { seg[$3+0]=$4 }
    END {
      over = seg[1]; c = "-"; t = "-"; m = "-"; p = "-"; f = "-"; q = "-"
      for (k = 2; k <= n; k++) {
        v = seg[2*k-1] - over
        if (label[k] ~ /^centroid/) c = sprintf("%d (%.2f per pixel)", v, v / 3072)
        else if (label[k] ~ /^tracker/) t = v
        else if (label[k] ~ /^multi/) m = v
        else if (label[k] ~ /^fdd.*frames/) f = v
        else if (label[k] ~ /^fdd.*peaks/) q = v
        else if (label[k] ~ /^pipeline/) p = v
      }
      printf "%s | %s | %s | %s / %s | %s", c, t, m, f, q, p
    }' "$tmp/$machine.out" "$tmp/$machine.log")
  read -r text data bss <<<"$(arm-none-eabi-size "$tmp/$machine.elf" | awk 'NR==2{print $1, $2, $3}')"
  [ -n "$defs" ] && counts="${counts% | - / - | -} | does not fit | does not fit (${rl}iB of RAM)"
  rows+=("| $name (QEMU \`$machine\`, \`$target\`) | $counts | $text | $((data + bss)) |")
done
echo "| core | centroid, 64 x 48 frame | tracker frame (windowed) | multi-target frame (2 targets) | FDD, 4 targets: 256 frames / peaks of 257 lines | pipeline, one second (120 frames, 2048 samples) | flash, B | RAM, B |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|"
printf '%s\n' "${rows[@]}"
