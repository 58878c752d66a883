#!/usr/bin/env python3
"""Analyse a multi-target synthetic recording with a Python peer -- pyidi (Lucas-Kanade
displacement of every target from the frames) and pyFRF (H1 against the base acceleration) --
and with `host-harness analyze --targets`, and print their accuracy against the model and
their wall times side by side.

    host-harness render --preset cantilever --recording REC --targets 5 --exposure-ms 2 \
        --read-noise 2 --video
    python3 scripts/peer_pyidi.py REC --harness target/release/host-harness [--out DIR]

The peer, as a test engineer would chain these tools: pyidi.VideoReader on the frames,
pyidi.LucasKanade with one square ROI per target (side 2 radius + 5 px, odd) centred on the
target's intensity centroid in the first frame, displacement along y (image up positive) in
mm; the base acceleration resampled to the camera rate by the Fourier method
(scipy.signal.resample: the record is periodic) and pyFRF's H1 (one segment over the whole
record, no window: the synthetic record is periodic, as in `analyze --window rect`) with
`resp_type='d'`, read as accelerance. Per mode: the peak of |Im H| in the mode's band of the
tip target (frequency), the shape from Im H at that bin over the targets (peak picking), MAC
against the true shapes in REC/recording.toml. Ours: `analyze --frames ... --targets K
--window rect`, with the binary and with the weighted centroid, modes.csv and shapes.csv
(fitted poles and residues). Both read the PNG frames (frames.mkv holds the same
pixels; pyidi 1.4's pyav reader stops early on a Matroska file, whose header has no frame
count).

Wall times are each tool's whole analysis from the frames (ours: the process, incl.
decoding, tracking, upsampling, H1 and the modal fit; the peer's: pyidi from the frames, the
resampling and pyFRF). Runs in a virtual environment with pinned packages: $PEER_VENV, else
.venv-peer at the repository root (created with pip when missing). Writes DIR/peer.csv and
DIR/peer.md (default REC/peer).
"""
import argparse
import subprocess
import time
from pathlib import Path

from pinned_venv import rerun_in_venv

PINS = ["pyidi==1.4.0", "pyFRF==1.5.0", "numpy", "scipy"]
MARK = "PEER_PYIDI_IN_VENV"


def ensure_venv():
    """Re-executes this script with the venv's python, creating the venv if needed."""
    rerun_in_venv(__file__, MARK, "PEER_VENV", ".venv-peer", "pyidi, pyFRF, scipy", PINS)


def mac(a, b):
    import numpy as np

    a, b = np.asarray(a, complex), np.asarray(b, complex)
    return abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real)


def first_frame_points(frame, xs, threshold):
    """(y, x) of each target: the intensity centroid above `threshold` in its column strip."""
    import numpy as np

    h, w = frame.shape
    strip = w // len(xs)
    pts = []
    for t in range(len(xs)):
        sub = frame[:, t * strip:(t + 1) * strip].astype(float)
        m = np.where(sub > threshold, sub, 0.0)
        ys, xx = np.mgrid[0:h, 0:sub.shape[1]]
        pts.append([(m * ys).sum() / m.sum(), t * strip + (m * xx).sum() / m.sum()])
    return np.array(pts)


def peer(rec, cfg):
    """pyidi displacement + pyFRF H1; returns (seconds, freq, H per target)."""
    import numpy as np
    import pyFRF
    import pyidi
    import scipy.signal

    t0 = time.perf_counter()
    # the PNG frames, not frames.mkv (the same pixels): pyidi 1.4 reads videos through pyav
    # by frame index, which finds no frame count in a Matroska header and stops before the
    # last frames of our FFV1 file (StopIteration)
    video = pyidi.VideoReader(str(rec / "frames" / "frame_00000.png"), fps=cfg["fps"])
    first = np.asarray(video.get_frame(0))
    pts = first_frame_points(first, cfg["target_x_px"], cfg["threshold"])
    side = 2 * int(round(cfg["radius_px"])) + 5
    side += 1 - side % 2
    lk = pyidi.LucasKanade(video)
    lk.set_points(np.round(pts).astype(int))
    lk.configure(roi_size=(side, side), verbose=0, show_pbar=False, processes=1)
    lk.get_displacements(autosave=False)
    d = np.asarray(lk.displacements)  # (points, frames, 2): (y, x) px, y down
    t_pyidi = time.perf_counter() - t0
    disp_m = -d[:, :, 0] * cfg["mm_per_px"] * 1e-3
    acc = np.genfromtxt(rec / "accel.csv", delimiter=",", names=True)
    n = disp_m.shape[1]
    base = scipy.signal.resample(acc["base_acc"][: int(n * cfg["fs"] / cfg["fps"])], n)
    hs = []
    for resp in disp_m:
        frf = pyFRF.FRF(cfg["fps"], exc=base, resp=resp - resp.mean(), exc_type="a",
                        resp_type="d", window="none", frf_estimator="H1")
        hs.append(np.asarray(frf.get_FRF(frf_form="accelerance")).ravel())
        freq = np.asarray(frf.get_f_axis()).ravel()
    t_all = time.perf_counter() - t0
    return t_pyidi, t_all, np.asarray(freq), np.asarray(hs)


def ours(rec, cfg, harness, out, mode):
    t0 = time.perf_counter()
    cmd = [harness, "analyze", "--frames", str(rec / "frames"), "--fps", str(cfg["fps"]),
           "--accel", str(rec / "accel.csv"), "--fs", str(cfg["fs"]), "--input-col",
           "base_acc", "--output-col", "tip_acc", "--time-col", "t_s", "--threshold",
           str(cfg["threshold"]), "--mm-per-px", str(cfg["mm_per_px"]), "--exposure-ms",
           str(cfg["exposure_ms"]), "--targets", str(cfg["targets"]), "--window", "rect",
           "--mode", mode, "--out", str(out), "--force"]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main():
    ensure_venv()
    import numpy as np
    import tomllib

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rec", type=Path)
    ap.add_argument("--harness", default="target/release/host-harness")
    ap.add_argument("--out", type=Path)
    a = ap.parse_args()
    rec = a.rec
    out = a.out or rec / "peer"
    out.mkdir(parents=True, exist_ok=True)
    cfg = tomllib.loads((rec / "recording.toml").read_text())
    k = cfg["targets"]
    truth = {s["mode"]: np.array(s["shape"]) for s in cfg["target_shapes"]}
    bands = [(5.0, 15.0), (25.0, 45.0)]  # analyze's default bands

    t_ours = {m: ours(rec, cfg, a.harness, out / f"ours-{m}", m)
              for m in ("binary", "weighted")}
    t_pyidi, t_peer, freq, hs = peer(rec, cfg)

    rows = []
    for m, model in enumerate(cfg["modes"], start=1):
        lo, hi = bands[m - 1]
        sel = np.where((freq >= lo) & (freq <= hi))[0]
        j = sel[np.argmax(np.abs(hs[-1, sel].imag))]
        peer_shape = hs[:, j].imag / hs[-1, j].imag
        peer_shape /= peer_shape[np.argmax(np.abs(peer_shape))]
        row = {"mode": m, "model_f_hz": model["f_hz"], "model_damping": model["zeta"]}
        for c in t_ours:
            modes = np.genfromtxt(out / f"ours-{c}" / "modes.csv", delimiter=",", names=True,
                                  dtype=None, encoding="utf-8")
            shapes = np.genfromtxt(out / f"ours-{c}" / "shapes.csv", delimiter=",", names=True)
            tip = modes[(modes["system"] == "vision") & (modes["target"] == k)
                        & (modes["mode"] == m)]
            acc = modes[(modes["system"] == "accelerometer") & (modes["mode"] == m)]
            sh = shapes[shapes["mode"] == m]
            row |= {f"ours_{c}_f_hz": float(tip["f_hz"][0]),
                    f"ours_{c}_damping": float(tip["damping"][0]),
                    f"ours_{c}_mac": mac(sh["re"] + 1j * sh["im"], truth[m]),
                    f"ours_{c}_tip_over_acc": float(tip["amplitude"][0] / acc["amplitude"][0])}
        row |= {"peer_f_hz": float(freq[j]), "peer_mac": mac(peer_shape, truth[m]),
                "peer_tip_over_acc": float(abs(hs[-1, j].imag) / acc["amplitude"][0])}
        rows.append(row)
    keys = list(rows[0])
    (out / "peer.csv").write_text(
        ",".join(keys) + "\n" + "".join(",".join(str(r[c]) for c in keys) + "\n" for r in rows))
    md = [f"recording {rec}: {k} targets, {cfg['frames']} frames of {cfg['frame_size'][0]} x "
          f"{cfg['frame_size'][1]} px, exposure {cfg['exposure_ms']} ms, read noise "
          f"{cfg.get('read_noise', 0)} grey levels; both read the PNG frames", "",
          "| mode | model f / damping | ours, binary centroid: f / damping / MAC / tip:acc | "
          "ours, weighted centroid | pyidi + pyFRF: f / MAC / tip:acc |", "|---|---|---|---|---|"]
    for r in rows:
        cells = [f"{r[f'ours_{c}_f_hz']:.4f} Hz / {r[f'ours_{c}_damping']:.5f} / "
                 f"{r[f'ours_{c}_mac']:.6f} / {r[f'ours_{c}_tip_over_acc']:.4f}" for c in t_ours]
        md.append(f"| {r['mode']} | {r['model_f_hz']} Hz / {r['model_damping']} | "
                  + " | ".join(cells) + f" | {r['peer_f_hz']:.4f} Hz (bin) / "
                  f"{r['peer_mac']:.6f} / {r['peer_tip_over_acc']:.4f} |")
    md += ["", f"wall time from the PNG frames: ours {t_ours['binary']:.2f} s (binary) "
           f"and {t_ours['weighted']:.2f} s (weighted), host-harness analyze, whole process; "
           f"peer {t_peer:.2f} s (pyidi {t_pyidi:.2f} s, resampling + pyFRF "
           f"{t_peer - t_pyidi:.2f} s); ratio {t_peer / t_ours['binary']:.0f}",
           "(the peer has no damping estimate: pyFRF stops at the FRF; its frequency is the "
           "peak bin of |Im H|, its shape Im H at that bin; ours are fitted poles and residues)"]
    (out / "peer.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
