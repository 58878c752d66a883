#!/usr/bin/env python3
"""A dense field of windows on a real recording, tracked by our Lucas-Kanade and by pyidi's on
the same frames and windows: time per target-frame of each, and how far their y displacements
are apart. Run on demand (not in CI); the figures go to docs/performance.md.

    cargo build --release -p host-harness --bin host-harness --example lk_timing \
        --example frame_dump
    python3 scripts/peer_dense.py tests/data/real/pyidi-showcase/data_showcase.cih \
        --region '0,0;640,0;640,40;0,40' --spacing 4 --direction y --work /tmp/dense

The windows: `host-harness pick --region ... --points-out` (docs/method.md 2.12), 21 x 21 px.
The frames: decoded by our reader (`frame_dump`), written as PNG for `lk_timing` and given to
pyidi preloaded as one numpy array, so that both trackers are timed, not the readers. pyidi
1.4 `LucasKanade` with `roi_size` the window and its defaults otherwise, one process (its
numba kernel runs the points in threads), after a warm-up on the first 10 frames (numba's
compilation is not tracking). Ours: the `lk_timing` example (firmware-core's tracker with the
CLI's settings, frames preloaded), run right before and right after pyidi, the slower kept
(the shared machine's speed changes within minutes). Also timed: the whole `track --tracker lk`
process (decoding, the forward-backward verification of every position, writing), per
target-frame. Runs in a virtual environment with pinned packages: $PEER_VENV, else
.venv-peer-dense at the repository root (created with pip when missing).
"""
import argparse
import subprocess
import tempfile
import time
from pathlib import Path

from pinned_venv import rerun_in_venv

PINS = ["pyidi==1.4.0", "numpy", "pillow"]
MARK = "PEER_DENSE_IN_VENV"


def ensure_venv():
    """Re-executes this script with the venv's python, creating the venv if needed."""
    rerun_in_venv(__file__, MARK, "PEER_VENV", ".venv-peer-dense", "pyidi, PIL", PINS)


def read_points(path):
    import csv

    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [(float(r["x"]), float(r["y"])) for r in rows], int(rows[0]["w"])


def lk_preloaded(lk_timing, rec):
    """Our tracker's time per target-frame, s, the best of three passes (printed in us)."""
    out = subprocess.run([lk_timing, str(rec), "3"], capture_output=True, text=True, check=True)
    for line in out.stdout.splitlines():
        if "per target-frame" in line:
            return float(line.split("us per target-frame")[0].split()[-1]) * 1e-6
    raise RuntimeError(f"no time in lk_timing's output: {out.stdout}")


def main():
    ensure_venv()
    import numpy as np
    from PIL import Image

    ap = argparse.ArgumentParser()
    ap.add_argument("frames")
    ap.add_argument("--region", required=True)
    ap.add_argument("--spacing", default="4")
    ap.add_argument("--direction", default="y")
    ap.add_argument("--work", type=Path, required=True)
    ap.add_argument("--harness", default="target/release/host-harness")
    ap.add_argument("--examples", default="target/release/examples")
    args = ap.parse_args()
    rec = args.work / "rec"
    (rec / "frames").mkdir(parents=True, exist_ok=True)
    raw = args.work / "frames.bin"
    dump = subprocess.run([f"{args.examples}/frame_dump", args.frames, str(raw)],
                          capture_output=True, text=True, check=True).stdout.split()
    w, h, bits, n = (int(v) for v in dump[:4])
    frames = np.fromfile(raw, dtype=np.uint8 if bits == 8 else "<u2").reshape(n, h, w)
    for k, f in enumerate(frames):
        Image.fromarray(f).save(rec / "frames" / f"frame_{k:05d}.png")
    subprocess.run([args.harness, "pick", "--frames", args.frames, "--region", args.region,
                    "--spacing", args.spacing, "--direction", args.direction, "--points-out",
                    str(rec / "points.csv"), "--out", str(args.work / "pick.html"), "--force"],
                   check=True)
    pts, win = read_points(rec / "points.csv")
    k = len(pts)
    print(f"{k} windows of {win} x {win} px, {n} frames of {w} x {h}")

    t0 = time.perf_counter()
    subprocess.run([args.harness, "track", "--frames", str(rec / "frames"), "--fps", "100",
                    "--points", str(rec / "points.csv"), "--tracker", "lk", "--out",
                    str(args.work / "track"), "--force", "--no-plots"],
                   check=True, capture_output=True)
    process = (time.perf_counter() - t0) / (n * k)

    import pyidi

    yx = np.array([[round(y), round(x)] for x, y in pts])
    with tempfile.TemporaryDirectory() as tmp:
        warm = pyidi.LucasKanade(pyidi.VideoReader(frames[:10], root=tmp, fps=100))
        warm.set_points(yx)
        warm.configure(roi_size=(win, win), verbose=0, show_pbar=False, processes=1)
        warm.get_displacements()
    with tempfile.TemporaryDirectory() as tmp:
        lk = pyidi.LucasKanade(pyidi.VideoReader(frames, root=tmp, fps=100))
        lk.set_points(yx)
        lk.configure(roi_size=(win, win), verbose=0, show_pbar=False, processes=1)
        before = lk_preloaded(f"{args.examples}/lk_timing", rec)
        t0 = time.perf_counter()
        lk.get_displacements()
        peer = (time.perf_counter() - t0) / (n * k)
        after = lk_preloaded(f"{args.examples}/lk_timing", rec)
        d = np.asarray(lk.displacements)  # (points, frames, 2): (y, x)
    ours = max(before, after)

    import csv

    ys = {}
    with open(args.work / "track" / "displacement.csv") as f:
        for r in csv.DictReader(f):
            if r["cy"]:
                ys[(int(r["target"]) - 1, int(r["frame"]))] = float(r["cy"])
    diffs = [abs((ys[(t, f)] - ys[(t, 0)]) - d[t, f, 0])
             for t in range(k) for f in range(n) if (t, f) in ys and (t, 0) in ys]
    print(f"ours, lk_timing (tracker, frames preloaded): {before * 1e6:.2f} us before pyidi, "
          f"{after * 1e6:.2f} after: {ours * 1e6:.2f} us per target-frame")
    print(f"ours, the track process (decoding, verification, writing): {process * 1e6:.2f} us")
    print(f"pyidi {pyidi.__version__} LucasKanade: {peer * 1e6:.2f} us per target-frame: "
          f"{peer / ours:.0f}x ours")
    print(f"y apart (ours' positions kept, {len(diffs)} of {n * k}): median "
          f"{np.median(diffs):.4f} px, 99th percentile {np.percentile(diffs, 99):.4f} px")


if __name__ == "__main__":
    main()
