#!/usr/bin/env python3
"""What motion blur does to each tracker: the grandstand Monte Carlo (method-uncertainty
variant, read noise 1 grey level) at 40, 100 and 180 ms for `[imaging] tracker = blob`,
`weighted` and `lk` (the plain disk) and `lk` on the speckled target, with the ratio of the
vision amplitude to the transducer's per run: its mean, the standard uncertainty of the mean,
the run-to-run scatter and the shortest 95 % coverage interval of one run's ratio, raw and
compensated. Prints the Markdown table of docs/method.md §2.11.

    cargo build --release -p host-harness
    python3 scripts/tracker_blur_table.py [RUNS] [OUT_DIR]     # 200 runs: about 10 minutes

Only the standard library; the studies are the `host-harness study` command.
"""
import csv
import math
import os
import subprocess
import sys
from collections import defaultdict

RUNS = int(sys.argv[1]) if len(sys.argv) > 1 else 200
OUT = sys.argv[2] if len(sys.argv) > 2 else "out/tracker-blur"
EXE = os.path.join(os.path.dirname(__file__), "..", "target", "release", "host-harness")
CASES = [
    ("blob", 'tracker = "blob"'),
    ("weighted", 'tracker = "weighted"'),
    ("lk", 'tracker = "lk"'),
    ("lk, speckle", 'tracker = "lk"\ntarget_texture = "speckle"'),
]


def shortest(values, p=0.95):
    v = sorted(values)
    n = len(v)
    k = max(1, int(math.ceil(p * n)))
    best = min(range(n - k + 1), key=lambda i: v[i + k - 1] - v[i])
    return v[best], v[best + k - 1]


def main():
    os.makedirs(OUT, exist_ok=True)
    rows = []
    for name, imaging in CASES:
        tag = name.replace(", ", "-")
        cfg = os.path.join(OUT, f"{tag}.toml")
        with open(cfg, "w") as f:
            f.write(
                f'preset = "grandstand"\nruns = {RUNS}\nfixed_structure = true\n'
                f"[imaging]\nread_noise = 1.0\n{imaging}\n"
            )
        out = os.path.join(OUT, tag)
        cmd = [EXE, "study", "--config", cfg, "--exposures-ms", "40,100,180", "--out", out]
        if os.path.isdir(out):
            cmd.append("--resume")
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        amp = defaultdict(dict)
        with open(os.path.join(out, "realizations.csv")) as f:
            for r in csv.DictReader(f):
                amp[(r["exposure_ms"], r["mode"], r["run"])][r["system"]] = float(r["a"])
        ratios = defaultdict(lambda: defaultdict(list))
        for (exp, mode, _), s in amp.items():
            for system in ("vision", "vision_compensated"):
                if system in s and "transducer" in s:
                    ratios[(exp, mode)][system].append(s[system] / s["transducer"])
        for (exp, mode), by in sorted(ratios.items(), key=lambda kv: (int(kv[0][1]), float(kv[0][0]))):
            cells = []
            for system in ("vision", "vision_compensated"):
                v = by[system]
                n = len(v)
                m = sum(v) / n
                sd = math.sqrt(sum((x - m) ** 2 for x in v) / (n - 1))
                lo, hi = shortest(v)
                cells.append(f"{m:.4f} ± {sd / math.sqrt(n):.4f} | {sd:.4f} | [{lo:.3f}, {hi:.3f}]")
            rows.append(f"| {name} | {mode} | {exp} | {len(by['vision'])} | " + " | ".join(cells) + " |")
    print(
        "| tracker | mode | exposure, ms | runs | vision / transducer: mean ± u | scatter | "
        "95 % interval | compensated: mean ± u | scatter | 95 % interval |"
    )
    print("|---|---:|---:|---:|---:|---:|---|---:|---:|---|")
    for r in rows:
        print(r)


if __name__ == "__main__":
    main()
