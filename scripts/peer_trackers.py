#!/usr/bin/env python3
"""Our `--points` trackers beside three peers, on the same frames and windows: accuracy against
the exact motion (`truth.csv`) and time per target-frame. Run on demand (not in CI); the figures
go to docs/performance.md.

    host-harness render --preset cantilever --recording REC --targets 5 --exposure-ms 2 \
        --read-noise 1
    python3 scripts/peer_trackers.py REC --harness target/release/host-harness

Peers, each given the frames preloaded as one numpy array (so the trackers are timed, not the
readers) and the windows of REC/points.csv (31 x 31 px centred on each target in frame 0):
- pyidi 1.4 `LucasKanade` (roi_size = the window, its defaults otherwise: cubic spline of the
  reference, up to 20 iterations, one process; with numba installed, as pip installs it, its
  compiled kernel, which runs the points in parallel threads), after a warm-up on the first
  10 frames so that numba's compilation is not timed;
- OpenCV `calcOpticalFlowPyrLK` (winSize = the window, 3 pyramid levels, up to 30 iterations
  or a step of 0.001 px), every frame against frame 0 starting from the last estimate (no
  frame-to-frame drift, as ours);
- scikit-image `phase_cross_correlation` (upsampled DFT registration, upsample factor 1000) of
  the window of frame 0 and the window of frame k at the last estimate's whole-pixel part.
Ours: `host-harness track --points REC/points.csv` with `--tracker lk`, `weighted` and
`blob` (threshold 127) for the accuracy. Time: for `lk`, the `lk_timing` example (firmware-core's
tracker on the same windows with the CLI's settings, frames preloaded as the peers'; build it
with `cargo build --release -p host-harness --example lk_timing`), run right before and right
after pyidi and the slower of the two kept (the machine's speed may change within a run); for
`weighted`, the process's time minus that of the same command with `blob` (decoding and
writing, which the peers do not pay), per target-frame.

RMS error as users compute it: per target, the estimated y minus the true y, its mean removed,
over all frames; the table gives each target's and their mean. Runs in a virtual environment
with pinned packages: $PEER_VENV, else .venv-peer-trackers at the repository root (created
with pip when missing). Writes REC/peer-trackers.md (an existing one is replaced only with
--force), with the versions of the packages that pip resolved (the peers' times depend on
them).
"""
import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from pinned_venv import rerun_in_venv

PINS = ["pyidi==1.4.0", "opencv-python-headless", "scikit-image", "numpy", "pillow"]
MARK = "PEER_TRACKERS_IN_VENV"


def ensure_venv():
    """Re-executes this script with the venv's python, creating the venv if needed."""
    probe = "pyidi, cv2, skimage, PIL"
    rerun_in_venv(__file__, MARK, "PEER_VENV", ".venv-peer-trackers", probe, PINS)


def read_csv(path):
    import csv
    with open(path) as f:
        return list(csv.DictReader(f))


def rms_errors(ys, truth):
    """ys[t][k]: estimated y of target t in frame k; truth[t][k] the true one."""
    import numpy as np
    out = []
    for est, tru in zip(ys, truth):
        e = np.asarray(est, float) - np.asarray(tru, float)
        e = e[np.isfinite(e)]
        out.append(float(np.sqrt(np.mean((e - e.mean()) ** 2))) if len(e) else float("nan"))
    return out


def main():
    ensure_venv()
    import numpy as np
    from PIL import Image

    ap = argparse.ArgumentParser()
    ap.add_argument("rec", type=Path)
    ap.add_argument("--harness", default="target/release/host-harness")
    ap.add_argument("--lk-timing", default="target/release/examples/lk_timing",
                    help="the built lk_timing example (frames preloaded)")
    ap.add_argument("--force", action="store_true", help="replace REC/peer-trackers.md")
    args = ap.parse_args()
    rec = args.rec
    if (rec / "peer-trackers.md").exists() and not args.force:
        sys.exit(f"{rec / 'peer-trackers.md'} exists: give --force to replace it")
    points = read_csv(rec / "points.csv")
    truth_rows = read_csv(rec / "truth.csv")
    files = sorted((rec / "frames").glob("frame_*.png"))
    frames = np.stack([np.asarray(Image.open(f).convert("L")) for f in files])
    n, k = len(frames), len(points)
    truth = [[0.0] * n for _ in range(k)]
    for r in truth_rows:
        truth[int(r["target"]) - 1][int(r["frame"])] = float(r["y_px"])
    pts = [(float(p["x"]), float(p["y"])) for p in points]
    win = int(points[0]["w"])
    results = []

    # ours, through the CLI
    with tempfile.TemporaryDirectory() as tmp:
        runs = []

        def ours(tracker):
            runs.append(tracker)
            out = Path(tmp) / f"{len(runs)}-{tracker}"
            extra = ["--tracker", tracker] + ([] if tracker == "lk" else ["--threshold", "127"])
            t0 = time.perf_counter()
            subprocess.run([args.harness, "track", "--frames", str(rec / "frames"), "--fps",
                            "120", "--points", str(rec / "points.csv"), "--out", str(out),
                            "--no-plots", *extra], check=True, capture_output=True)
            dt = time.perf_counter() - t0
            ys = [[float("nan")] * n for _ in range(k)]
            for r in read_csv(out / "displacement.csv"):
                if r["cy"]:
                    ys[int(r["target"]) - 1][int(r["frame"])] = float(r["cy"])
            return dt, ys
        base, _ = ours("blob")
        for tracker in ["lk", "weighted", "blob"]:
            dt, ys = ours(tracker)
            # lk: timed beside pyidi below
            cost = None if tracker in ("lk", "blob") else max(dt - base, 0.0) / (n * k)
            results.append((f"ours, {tracker}", rms_errors(ys, truth), cost))

    # pyidi LucasKanade
    import pyidi
    with tempfile.TemporaryDirectory() as tmp:
        # a warm-up on the first frames: pyidi 1.4 compiles its numba kernel on first use (or
        # loads it from numba's cache), which is not tracking time (ours is compiled before
        # the run too)
        warm = pyidi.LucasKanade(pyidi.VideoReader(frames[:10], root=tmp, fps=120))
        warm.set_points(np.array([[round(y), round(x)] for x, y in pts]))
        warm.configure(roi_size=(win, win), verbose=0, show_pbar=False, processes=1)
        warm.get_displacements()
    with tempfile.TemporaryDirectory() as tmp:
        video = pyidi.VideoReader(frames, root=tmp, fps=120)
        lk = pyidi.LucasKanade(video)
        lk.set_points(np.array([[round(y), round(x)] for x, y in pts]))
        lk.configure(roi_size=(win, win), verbose=0, show_pbar=False, processes=1)
        # ours timed right before and right after pyidi (the shared machine's speed changes by
        # up to 1.7x within minutes): the slower of the two goes into the table
        before = lk_preloaded(args.lk_timing, rec)
        t0 = time.perf_counter()
        lk.get_displacements()
        dt = time.perf_counter() - t0
        after = lk_preloaded(args.lk_timing, rec)
        print(f"ours, lk: {before * 1e6:.2f} us before pyidi, {after * 1e6:.2f} after")
        results = [(name, rms, max(before, after) if name == "ours, lk" else cost)
                   for name, rms, cost in results]
        d = np.asarray(lk.displacements)  # (points, frames, 2): (y, x)
        ys = [[round(y) + d[t, f, 0] for f in range(n)] for t, (x, y) in enumerate(pts)]
        results.append(("pyidi 1.4 LucasKanade", rms_errors(ys, truth), dt / (n * k)))

    # OpenCV pyramidal LK against frame 0
    import cv2
    p0 = np.array([[x, y] for x, y in pts], np.float32).reshape(-1, 1, 2)
    est = p0.copy()
    ys = [[float("nan")] * n for _ in range(k)]
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.001)
    t0 = time.perf_counter()
    for f in range(n):
        nxt, st, _ = cv2.calcOpticalFlowPyrLK(frames[0], frames[f], p0, est.copy(),
                                              winSize=(win, win), maxLevel=3, criteria=crit,
                                              flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
        for t in range(k):
            if st[t, 0]:
                est[t] = nxt[t]
                ys[t][f] = float(nxt[t, 0, 1])
    dt = time.perf_counter() - t0
    results.append((f"OpenCV {cv2.__version__} calcOpticalFlowPyrLK", rms_errors(ys, truth),
                    dt / (n * k)))

    # scikit-image phase correlation
    from skimage.registration import phase_cross_correlation
    h = win // 2
    ys = [[float("nan")] * n for _ in range(k)]
    t_total = 0.0
    for t, (x, y) in enumerate(pts):
        cx, cy = round(x), round(y)
        ref = frames[0, cy - h:cy + h + 1, cx - h:cx + h + 1].astype(float)
        at = (0.0, 0.0)
        for f in range(n):
            ox, oy = round(at[0]), round(at[1])
            mov = frames[f, cy + oy - h:cy + oy + h + 1, cx + ox - h:cx + ox + h + 1].astype(float)
            t0 = time.perf_counter()
            shift, _, _ = phase_cross_correlation(ref, mov, upsample_factor=1000)
            t_total += time.perf_counter() - t0
            # shift registers mov onto ref: the content moved by -shift within the window
            at = (ox - shift[1], oy - shift[0])
            ys[t][f] = y + at[1]
    results.append(("scikit-image phase_cross_correlation (x1000)", rms_errors(ys, truth),
                    t_total / (n * k)))

    lines = ["| tracker | RMS error per target, px | mean, px | time per target-frame, us |",
             "|---|---|---:|---:|"]
    for name, rms, cost in results:
        c = "" if cost is None else f"{cost * 1e6:.1f}"
        lines.append(f"| {name} | {' '.join(f'{v:.4f}' for v in rms)} | "
                     f"{np.nanmean(rms):.4f} | {c} |")
    from importlib.metadata import version
    lines.append("")
    # OpenCV as imported: pyidi pulls in opencv-contrib-python, whose cv2 may shadow the
    # headless package's
    lines.append("Versions: " + ", ".join(
        [f"{p} {version(p)}" for p in ["pyidi", "numpy", "scipy", "numba"] if have_dist(p)]
        + [f"OpenCV (cv2) {cv2.__version__}", f"scikit-image {version('scikit-image')}"]) + ".")
    text = "\n".join(lines)
    print(text)
    (rec / "peer-trackers.md").write_text(text + "\n")


def have_dist(name):
    """Whether the distribution `name` is installed (numba is optional for pyidi)."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        version(name)
        return True
    except PackageNotFoundError:
        return False


def lk_preloaded(exe, rec):
    """Seconds per target-frame of our LK with the frames preloaded (the `lk_timing` example)."""
    out = subprocess.run([exe, str(rec), "3"], check=True, capture_output=True, text=True).stdout
    for line in out.splitlines():
        if "us per target-frame" in line:
            return float(line.split(":")[1].split("us")[0]) * 1e-6
    raise SystemExit(f"lk_timing printed no time: {out}")


if __name__ == "__main__":
    main()
