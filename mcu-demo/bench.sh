#!/usr/bin/env bash
# Instruction counts and memory of the Cortex-M4F demo, as a Markdown table (the README's
# "On a microcontroller" table). Runnable on Debian with: rustup target thumbv7em-none-eabihf,
# apt-get install qemu-system-arm binutils-arm-none-eabi gcc. Counts come from QEMU TCG plugins
# (../shared/tools/qemu-icount, built here into a temporary directory): exact guest instructions
# between calls of the firmware's `bench_mark`, identical run to run. Instructions are not cycles.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cd "$here"
tools=${QEMU_ICOUNT:-$here/../../shared/tools/qemu-icount}
[ -f "$tools/build.sh" ] || { echo "bench.sh: $tools/build.sh not found (set QEMU_ICOUNT)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
sh "$tools/build.sh" "$tmp" >/dev/null
cargo build --release --quiet
# honour a CARGO_TARGET_DIR set by the caller (CI caches, shared target dirs)
elf=${CARGO_TARGET_DIR:-target}/thumbv7em-none-eabihf/release/mcu-demo
mark=$(arm-none-eabi-nm -t d "$elf" | awk '$3=="bench_mark"{printf "0x%x\n", $1 - $1 % 2}')
timeout 600 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
  -semihosting-config enable=on,target=native -icount shift=0 \
  -plugin "$tmp/libmarks.so,mark=$mark" -d plugin -D "$tmp/marks.log" -kernel "$elf" >"$tmp/out.txt"
grep -q "all checks passed" "$tmp/out.txt" || { cat "$tmp/out.txt"; echo "bench.sh: demo failed" >&2; exit 1; }

# label k (printed as "bench: LABEL") <-> plugin segment 2k-1; "empty" is the marker overhead
awk '
  FNR==NR { if ($1=="bench:") { sub(/^bench: /, ""); label[++n]=$0 } next }
  $1=="marks:" && $2=="segment" { seg[$3+0]=$4 }
  END {
    over = seg[1]
    print "| what | instructions | per unit |"
    print "|---|---:|---:|"
    for (k = 2; k <= n; k++) {
      v = seg[2*k-1] - over; l = label[k]
      if (l ~ /76800$/) { sub(/ 76800$/, "", l); printf "| %s, 320 x 240 frame | %d | %.2f per pixel |\n", l, v, v/76800 }
      else printf "| %s | %d | |\n", l, v
    }
  }' "$tmp/out.txt" "$tmp/marks.log"
echo
grep "^ram:" "$tmp/out.txt" | sed 's/^ram: /RAM (size_of): /'
echo
# memory: whole image, and firmware-core symbols per module (LTO inlines much of a module into
# its callers; these are the out-of-line functions and data that keep the module's name)
read -r text data bss <<<"$(arm-none-eabi-size "$elf" | awk 'NR==2{print $1, $2, $3}')"
frames=$(arm-none-eabi-nm -S -t d "$elf" | awk '$4 ~ /FRAME_U8|FRAME_U16|DENSE_U8/ {s += $2} END{print s+0}')
echo "| image / module | flash (text + rodata), B | static RAM (data + bss), B |"
echo "|---|---:|---:|"
echo "| whole image | $text (of which test frames $frames) | $((data + bss)) |"
arm-none-eabi-nm -S -C -t d "$elf" | awk '
  NF >= 4 {
    name = $4; for (i = 5; i <= NF; i++) name = name " " $i
    if (match(name, /firmware_core::[a-z_0-9]+/)) {
      m = substr(name, RSTART + 15, RLENGTH - 15); sz = $2 + 0; t = $3
      if (t ~ /[tTrRwW]/) fl[m] += sz; else if (t ~ /[dDbB]/) ram[m] += sz
      seen[m] = 1
    }
  }
  END { for (m in seen) printf "| firmware_core::%s | %d | %d |\n", m, fl[m], ram[m] }' | sort
