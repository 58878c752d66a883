#!/usr/bin/env bash
# Compares every output of two host-harness binaries on the same inputs: the default study
# (100 runs), the cantilever study (20 runs), a 60-run grandstand with [imaging] noise and the
# weighted centroid, analyze (one target on PNG frames and on the FFV1 video, five targets,
# chosen points in a cluttered scene, output-only without an accelerometer), track (chosen
# points by Lucas-Kanade and by Otsu's threshold), modal on a simulate-field record, the
# rendered release scene and field record (their frames too), simulate-field's files,
# calibrate (3 evaluations), frf, upsample, plan and centroid. Refactors that must not move a
# number are checked with it (plots and runs.jsonl, which holds timings, are left out; paths and
# durations in printed text are masked).
#   scripts/compare_outputs.sh OLD_BINARY NEW_BINARY [WORKDIR]
set -euo pipefail
A=$(realpath "$1"); B=$(realpath "$2"); W=${3:-$(mktemp -d)}
mkdir -p "$W/in"
"$A" render --preset cantilever --recording "$W/in/r1" --exposure-ms 2 --video > /dev/null
"$A" render --preset cantilever --recording "$W/in/r5" --exposure-ms 2 --targets 5 \
  --read-noise 1 > /dev/null
"$A" render --preset cantilever --recording "$W/in/clutter" --targets 5 --exposure-ms 2 \
  --read-noise 1 --scene cluttered > /dev/null
"$A" simulate-field --minutes 3 --out "$W/in/field" > /dev/null
cat > "$W/in/g60.toml" <<'TOML'
preset = "grandstand"
runs = 60
exposures_ms = [40.0, 120.0, 180.0]
seed = 3

[imaging]
read_noise = 1.5
shot_noise_e_per_level = 4.0
centroid = "weighted"
TOML
printf 'rig,mode,exposure_ms,quantity,value,u,unit\ngrandstand,1,40,mu_a,4.44,,\ngrandstand,1,180,mu_a,3.21,,\n' \
  > "$W/in/obs.csv"
common=(--fps 120 --fs 2048 --time-col t_s --threshold 127 --mm-per-px 0.1266)
for v in a b; do
  H=$A; [ $v = b ] && H=$B
  o=$W/$v; mkdir -p "$o/misc"
  $H study --out "$o/default" --no-plots > "$o/default.stdout" 2>&1
  $H study --preset cantilever --runs 20 --out "$o/cant" --no-plots > "$o/cant.stdout" 2>&1
  $H study --config "$W/in/g60.toml" --out "$o/g60" --no-plots > "$o/g60.stdout" 2>&1
  $H analyze --frames "$W/in/r1/frames" --accel "$W/in/r1/accel.csv" "${common[@]}" \
    --exposure-ms 2 --compensate-exposure --out "$o/an1" > /dev/null 2>&1
  $H analyze --frames "$W/in/r1/frames.mkv" --accel "$W/in/r1/accel.csv" "${common[@]}" \
    --out "$o/anv" > /dev/null 2>&1
  $H analyze --frames "$W/in/r5/frames" --accel "$W/in/r5/accel.csv" "${common[@]}" \
    --exposure-ms 2 --targets 5 --window rect --compensate-exposure --out "$o/an5" > /dev/null 2>&1
  $H analyze --frames "$W/in/clutter/frames" --accel "$W/in/clutter/accel.csv" "${common[@]}" \
    --exposure-ms 2 --window rect --points "$W/in/clutter/points.csv" \
    --out "$o/anp" > /dev/null 2>&1
  $H analyze --frames "$W/in/r5/frames" --fps 120 --targets 5 --threshold 127 \
    --out "$o/ano" > /dev/null 2>&1
  $H track --frames "$W/in/clutter/frames" --fps 120 --points "$W/in/clutter/points.csv" \
    --tracker lk --mm-per-px 0.1266 --no-plots --out "$o/tlk" > /dev/null 2>&1
  $H track --frames "$W/in/clutter/frames" --fps 120 --points "$W/in/clutter/points.csv" \
    --threshold auto --no-plots --out "$o/tauto" > /dev/null 2>&1
  $H modal --displacement "$W/in/field/displacement.csv" --no-plots --out "$o/modal" \
    > /dev/null 2>&1
  $H render --recording "$o/release" --scene cluttered --motion release > /dev/null 2>&1
  $H simulate-field --render --minutes 0.3 --out "$o/fieldr" > /dev/null 2>&1
  $H simulate-field --minutes 1 --out "$o/field" > /dev/null 2>&1
  $H calibrate --observed "$W/in/obs.csv" --preset grandstand --free threshold_frac=0.3:0.6 \
    --runs 4 --grid 2 --refine 0 --out "$o/cal" > "$o/cal.stdout" 2>&1
  $H frf --input "$W/in/r1/accel.csv" --x base_acc --y tip_acc --fs 2048 --nperseg 1024 \
    --bands 20-45,150-250 --out "$o/misc/frf.csv" > "$o/misc/peaks.stdout" 2>&1
  $H upsample --input "$o/an1/displacement.csv" --col disp_mm --from 120 --to 2048 \
    --out "$o/misc/up.csv" > /dev/null 2>&1 || true
  $H plan --preset grandstand --out "$o/misc/plan.csv" > "$o/misc/plan.stdout" 2>&1
  $H centroid --threshold 127 "$W/in/r1/frames/frame_0000"*.png > "$o/misc/centroid.stdout" 2>&1
done
mask() { sed "s#$W/[ab]/#OUT/#g; s/computed in .* s/T/; s/evaluations, .* s)/E/; s/ ([0-9.]* s)$/ (T)/" "$1"; }
same=0; diff=0
while IFS= read -r f; do
  case $f in *.png|*.svg|*runs.jsonl|*.lock) continue ;; esac
  if cmp -s <(mask "$W/a/$f") <(mask "$W/b/$f"); then same=$((same + 1)); else
    echo "DIFF $f"; diff=$((diff + 1)); fi
done < <(cd "$W/a" && find . -type f | sort)
echo "$same files identical, $diff different ($W)"
[ "$diff" -eq 0 ]
