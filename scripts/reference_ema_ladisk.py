#!/usr/bin/env python3
"""The independent reference for tests/data/real/ladisk-ema-beam: sdypy-EMA (LSCF poles, the
stable poles closest to the given frequencies) on FRFs formed as the recording's own tutorial
forms them (LADISK's ImageBasedModalAnalysisTutorial: the FFT of each response over the FFT of
the force, no window, the record's first 0.25 s for the camera, the whole second for the
accelerometer; orders to 50; the band 50-4000 Hz for the accelerometer, 300-2500 Hz for the
camera, where alone sdypy-EMA finds stable poles at its modes).

    python3 scripts/reference_ema_ladisk.py [DIR]

Prints each mode's frequency and damping for the camera's y displacements (over camera.lvm's
force) and for the accelerometer (acceleration.lvm). Runs inside the virtual environment of
scripts/check_uff.py ($CHECK_UFF_VENV; pinned sdypy-EMA).
"""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import check_uff  # noqa: E402  (its ensure_venv re-executes this script in the venv)


def lvm(path):
    """The two data columns of a LabVIEW file with decimal commas."""
    import numpy as np
    lines = Path(path).read_text(encoding="latin-1").split("\n")
    start = next(i for i, l in enumerate(lines) if l.startswith("X_Value")) + 1
    rows = [l.split("\t")[1:3] for l in lines[start:]]
    return np.array([[float(v.replace(",", ".")) for v in r] for r in rows if len(r) == 2 and r[0]])


def fit(frf, freq, near, lower, upper):
    from sdypy import EMA
    m = EMA.Model(frf, freq, lower=lower, upper=upper, pol_order_high=50)
    m.get_poles(show_progress=False)
    m.select_closest_poles(near)
    return m.nat_freq, m.nat_xi


def main():
    check_uff.ensure_venv_for(__file__)
    import numpy as np
    d = Path(sys.argv[1] if len(sys.argv) > 1 else "tests/data/real/ladisk-ema-beam")
    disp = np.load(d / "displacements_lk.npy")[:, :, 0]  # pyidi's direction 0: y
    n, dt_cam = disp.shape[1], 1 / 15000
    force = lvm(d / "camera.lvm")[:, 1]
    fs = 50000
    nf = int(round(n * dt_cam * fs))
    freq = np.fft.rfftfreq(n, dt_cam)
    fft_f = np.fft.rfft(force[:nf], nf) * 2 / nf
    fft_x = np.fft.rfft(disp, n, axis=1) * 2 / n
    k = freq < 4000
    # over 50-4000 Hz sdypy-EMA finds no stable pole near either mode of the camera's FRFs
    # (the suspension's motion below 300 Hz and the noise above 2.5 kHz): its band is chosen
    f_cam, z_cam = fit(fft_x[:, k] / fft_f[: k.sum()], freq[k], [695, 1898], 300, 2500)
    acc = lvm(d / "acceleration.lvm")
    freq_a = np.fft.rfftfreq(len(acc), 1 / fs)
    h = np.fft.rfft(acc[:, 0]) / np.fft.rfft(acc[:, 1])
    ka = (freq_a > 0) & (freq_a < 4000)
    f_acc, z_acc = fit(h[ka][None, :], freq_a[ka], [695, 1898, 2777, 3671], 50, 4000)
    for name, f, z in (("camera y", f_cam, z_cam), ("accelerometer", f_acc, z_acc)):
        print(name + ": " + ", ".join(f"{a:.2f} Hz ({b:.5f})" for a, b in zip(f, z)))


if __name__ == "__main__":
    main()
