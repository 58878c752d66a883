#!/usr/bin/env python3
"""Check the mode shapes of an output-only analysis (`modal`, or `analyze` without --accel)
as pyuff reads them: every dataset 55 of DIR/shapes.uff against DIR/modes.csv and
DIR/shapes.csv (frequency from the eigenvalue within 1e-5 relative, damping, the shape's
components within 1e-5 of the largest).

    python3 scripts/check_shapes_uff.py DIR

Runs in the virtual environment of scripts/check_uff.py ($CHECK_UFF_VENV, else .venv; pyuff
pinned there). Exit status 0 when every check passes, 1 otherwise.
"""
import csv
import math
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import check_uff  # noqa: E402  (its pins: pyuff)


def ensure_venv():
    """Re-executes this script with the venv's python (check_uff.py's venv and pins)."""
    check_uff.ensure_venv_for(__file__)


def main():
    ensure_venv()
    import pyuff

    out = Path(sys.argv[1])
    sets = pyuff.UFF(str(out / "shapes.uff")).read_sets()
    if isinstance(sets, dict):
        sets = [sets]
    modes = list(csv.DictReader(open(out / "modes.csv")))
    shapes = list(csv.DictReader(open(out / "shapes.csv")))
    methods = {1: "fdd", 2: "efdd", 3: "ssi"}
    failures = []
    if len(sets) != len(modes):
        failures.append(f"{len(sets)} datasets 55, {len(modes)} rows in modes.csv")
    for s in sets:
        if s["type"] != 55:
            failures.append(f"dataset type {s['type']}")
            continue
        method = methods[int(s["load_case"])]
        mode = int(s["mode_n"])
        row = [m for m in modes if m["method"] == method and int(m["mode"]) == mode]
        if len(row) != 1:
            failures.append(f"{method} mode {mode}: not one row in modes.csv")
            continue
        f = float(row[0]["f_hz"])
        eig = complex(s["eig"])
        f_uff = abs(eig) / (2 * math.pi)
        if abs(f_uff - f) > 1e-5 * f:
            failures.append(f"{method} mode {mode}: eigenvalue {f_uff} Hz, modes.csv {f}")
        z = float(row[0]["damping"]) if row[0]["damping"] else 0.0
        z_uff = -eig.real / abs(eig)
        if abs(z_uff - z) > 1e-4:
            failures.append(f"{method} mode {mode}: damping {z_uff}, modes.csv {z}")
        want = {int(r["target"]): complex(float(r["re"]), float(r["im"]))
                for r in shapes if r["method"] == method and int(r["mode"]) == mode}
        # the motion is along y (r2) or x (r1)
        comp = s["r2"] if any(abs(v) > 0 for v in s["r2"]) else s["r1"]
        for node, v in zip(s["node_nums"], comp):
            w = want.get(int(node))
            if w is None or abs(complex(v) - w) > 1e-5:
                failures.append(f"{method} mode {mode} node {int(node)}: {v} vs {w}")
    for f in failures:
        print("FAIL:", f)
    print(f"{len(sets)} mode shapes read by pyuff {pyuff.__version__}: "
          f"{'ok' if not failures else 'FAILED'}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
