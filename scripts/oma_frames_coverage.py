#!/usr/bin/env python3
"""Coverage of the output-only intervals through frames (docs/validation.md section 3).

Renders field recordings with `host-harness simulate-field --render` (the shear frame filmed:
5 targets, a 10 px disk each, the chosen exposure and read noise, 8-bit frames), analyses each
with `host-harness analyze --frames ... --targets 5` without an accelerometer (the weighted
centroid, or another tracker), and counts how often the 95 % intervals of each SSI and EFDD
mode's frequency and damping hold the true mode (truth.csv), a mode found when its frequency is
within 5 % of the truth's. Also prints the mean width over the needed width (2 x 1.96 x the
standard deviation of the estimates' errors over the records) per method and quantity.

Standard library only. Usage:

    python3 scripts/oma_frames_coverage.py --harness target/release/host-harness \
        --records 12 --minutes 3 [--first-seed 1] [--tracker weighted] [--read-noise 1]
"""

import argparse
import csv
import math
import os
import statistics
import subprocess
import sys
import tempfile


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{r.stderr}")
    return r.stdout


def truth_modes(path):
    modes = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            modes[int(row["mode"])] = (float(row["f_hz"]), float(row["damping"]))
    return [modes[k] for k in sorted(modes)]


def cell(row, key):
    v = row.get(key, "")
    return float(v) if v not in ("", None) else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--harness", required=True)
    ap.add_argument("--records", type=int, default=12)
    ap.add_argument("--minutes", type=float, default=3.0)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--tracker", default="weighted")
    ap.add_argument("--read-noise", type=float, default=1.0)
    args = ap.parse_args()

    # (method, mode, quantity) -> list of (estimate, lo, hi, truth)
    found = {}
    missing = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.records):
            seed = args.first_seed + r
            rec = os.path.join(tmp, f"rec{seed}")
            run([args.harness, "simulate-field", "--render", "--minutes", str(args.minutes),
                 "--seed", str(seed), "--read-noise", str(args.read_noise), "--out", rec])
            out = os.path.join(rec, "analysis")
            run([args.harness, "analyze", "--frames", os.path.join(rec, "frames"), "--fps", "60",
                 "--targets", "5", "--threshold", "127", "--tracker", args.tracker,
                 "--out", out])
            truth = truth_modes(os.path.join(rec, "truth.csv"))
            with open(os.path.join(out, "modes.csv"), newline="") as f:
                rows = list(csv.DictReader(f))
            for method in ("ssi", "efdd"):
                mine = [x for x in rows if x["method"] == method]
                for k, (f_true, z_true) in enumerate(truth, start=1):
                    near = [x for x in mine if abs(float(x["f_hz"]) / f_true - 1) < 0.05]
                    if not near:
                        missing[(method, k)] = missing.get((method, k), 0) + 1
                        continue
                    x = min(near, key=lambda x: abs(float(x["f_hz"]) - f_true))
                    for q, t in (("f_hz", f_true), ("damping", z_true)):
                        est, lo, hi = cell(x, q), cell(x, q + "_lo"), cell(x, q + "_hi")
                        if est is None or lo is None:
                            continue
                        found.setdefault((method, k, q), []).append((est, lo, hi, t))
            print(f"record {r + 1}/{args.records} (seed {seed}) done", file=sys.stderr)

    print(f"{args.records} records of {args.minutes} min, tracker {args.tracker}, read noise "
          f"{args.read_noise}")
    print("| method | mode | quantity | given | held | width / needed | mean error |")
    print("|---|---:|---|---:|---:|---:|---:|")
    totals = {}
    for (method, k, q), v in sorted(found.items()):
        held = sum(1 for e, lo, hi, t in v if lo <= t <= hi)
        errs = [e - t for e, lo, hi, t in v]
        sd = statistics.stdev(errs) if len(errs) > 1 else float("nan")
        width = statistics.mean(hi - lo for e, lo, hi, t in v)
        ratio = width / (2 * 1.96 * sd) if sd and not math.isnan(sd) and sd > 0 else float("nan")
        rel = statistics.mean(errs) / v[0][3]
        print(f"| {method} | {k} | {q} | {len(v)} | {100 * held / len(v):.0f} % | "
              f"{ratio:.2f} | {100 * rel:+.1f} % |")
        t = totals.setdefault((method, q), [0, 0])
        t[0] += len(v)
        t[1] += held
    for (method, q), (n, h) in sorted(totals.items()):
        print(f"{method} {q}: {h} of {n} intervals hold ({100 * h / n:.1f} %)")
    for (method, k), n in sorted(missing.items()):
        print(f"{method} mode {k}: not found in {n} record(s)")


if __name__ == "__main__":
    main()
