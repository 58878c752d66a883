#!/usr/bin/env python3
"""An independent track of a recording's chosen points by pyidi's Lucas-Kanade: the reference
the real-recording corpus (tests/data/real/) is checked against.

    python3 scripts/reference_tracks_pyidi.py REC.cih POINTS.csv OUT.csv [--venv DIR]

POINTS.csv is a `--points` file (`target,x,y,w,h`; whole-pixel centres, odd windows: pyidi
centres its region of interest on a whole pixel). OUT.csv gets `frame,target,dx_px,dy_px`:
each target's displacement since the first frame by pyidi 1.4's `LucasKanade` (its defaults
otherwise: cubic-spline template, one process), frame 0-based. Run in a venv of its own
(pyidi 1.4.0 and pyMRAW, which reads the Photron file), made on first use.
"""
import argparse
import csv
import os
import subprocess
import sys
from pathlib import Path

PINS = ["pyidi==1.4.0", "numpy"]


def in_venv(venv: Path) -> None:
    py = venv / "bin" / "python"
    if not py.exists():
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        subprocess.run([str(py), "-m", "pip", "install", "-q", *PINS], check=True)
    if Path(sys.prefix).resolve() != venv.resolve():
        os.execv(str(py), [str(py), *sys.argv])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recording")
    ap.add_argument("points")
    ap.add_argument("out")
    ap.add_argument("--venv", default="target/pyidi-venv")
    args = ap.parse_args()
    in_venv(Path(args.venv))
    import numpy as np
    import pyidi

    rows = list(csv.DictReader(open(args.points)))
    sizes = {(int(r["w"]), int(r["h"])) for r in rows}
    if len(sizes) != 1:
        sys.exit(f"{args.points}: pyidi takes one window size for every point, got {sizes}")
    (w, h), = sizes
    pts = []
    for r in rows:
        x, y = float(r["x"]), float(r["y"])
        if x != round(x) or y != round(y) or w % 2 == 0 or h % 2 == 0:
            sys.exit(f"{args.points} row {r['target']}: whole-pixel centres and odd windows only")
        pts.append([int(y), int(x)])
    video = pyidi.VideoReader(args.recording)
    lk = pyidi.LucasKanade(video)
    lk.set_points(np.array(pts))
    lk.configure(roi_size=(h, w), verbose=0, show_pbar=False, processes=1)
    d = np.asarray(lk.get_displacements())  # (points, frames, 2): (y, x)
    with open(args.out, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["frame", "target", "dx_px", "dy_px"])
        for k in range(d.shape[1]):
            for t, r in enumerate(rows):
                out.writerow([k, r["target"], f"{d[t, k, 1]:.6f}", f"{d[t, k, 0]:.6f}"])
    print(f"{args.out}: {d.shape[0]} targets x {d.shape[1]} frames (pyidi {pyidi.__version__})")


if __name__ == "__main__":
    main()
