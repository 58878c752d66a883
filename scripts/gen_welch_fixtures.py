#!/usr/bin/env python3
"""Generate the scipy reference fixtures of firmware-core's streaming Welch H1 estimator.

Run from the repository root (needs numpy and scipy: `pip install numpy scipy`):

    python3 scripts/gen_welch_fixtures.py

It writes, under firmware-core/tests/fixtures/welch/:

* input.csv   columns x,y: one deterministic record (numpy PCG64, seed 20161), x white noise with
              an offset, y = x through two resonant two-pole filters plus independent noise and
              another offset (so the coherence is high near the resonances but never 1). The
              values are rounded to float32 and written with 9 significant digits, so that the
              Rust test (f32) and scipy (float64) see exactly the same numbers.
* cases.csv   one row per configuration: name,window,nperseg,noverlap,nfft,detrend,n,fs_hz
              (each case uses the first n samples of input.csv).
* <name>.csv  scipy's result per bin: freq_hz,pxx,pyy,pxy_re,pxy_im,h1_re,h1_im,coherence with
              pxx/pyy from scipy.signal.welch and pxy from scipy.signal.csd (density scaling,
              default arguments otherwise: average='mean', no boundary extension, no padding),
              H1 = Pxy / Pxx and coherence = |Pxy|^2 / (Pxx Pyy).

The fixtures are consumed by firmware-core/tests/welch_scipy.rs. Re-running the script
reproduces the committed files bit for bit with the same numpy/scipy major versions.
"""

import os

import numpy as np
import scipy
import scipy.signal as sig

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "firmware-core", "tests",
                   "fixtures", "welch")
N = 8192
SEED = 20161

# name, scipy window, nperseg, noverlap, nfft, detrend ('constant' or False), n, fs
CASES = [
    ("hann_256_128_256_constant", "hann", 256, 128, 256, "constant", 4096, 100.0),
    ("hann_200_150_512_none", "hann", 200, 150, 512, False, 3000, 100.0),
    ("hann_2048_0_2048_constant", "hann", 2048, 0, 2048, "constant", 8192, 2048.0),
    ("hann_4800_0_4800_constant", "hann", 4800, 0, 4800, "constant", 4800, 480.0),
    ("hann_64_60_100_constant", "hann", 64, 60, 100, "constant", 8192, 100.0),
    ("hamming_1111_555_5000_constant", "hamming", 1111, 555, 5000, "constant", 5000, 50.0),
    ("hamming_100_0_128_none", "hamming", 100, 0, 128, False, 6000, 100.0),
    ("hamming_333_111_1000_none", "hamming", 333, 111, 1000, False, 8192, 20.0),
    ("boxcar_128_64_128_constant", "boxcar", 128, 64, 128, "constant", 4096, 100.0),
    ("boxcar_300_100_1000_none", "boxcar", 300, 100, 1000, False, 8192, 100.0),
    ("boxcar_97_48_97_constant", "boxcar", 97, 48, 97, "constant", 2000, 10.0),
]


def record():
    rng = np.random.Generator(np.random.PCG64(SEED))
    x = rng.standard_normal(N) + 0.3
    y = np.zeros(N)
    for f0, r, g in ((0.06, 0.985, 1.0), (0.21, 0.97, 0.6)):
        th = 2 * np.pi * f0
        y += sig.lfilter([g * (1 - r)], [1.0, -2 * r * np.cos(th), r * r], x - 0.3)
    y += 0.3 * np.std(y) * rng.standard_normal(N) - 1.2
    # exactly what the f32 code will see
    return x.astype(np.float32).astype(np.float64), y.astype(np.float32).astype(np.float64)


def main():
    os.makedirs(OUT, exist_ok=True)
    x, y = record()
    with open(os.path.join(OUT, "input.csv"), "w") as f:
        f.write("x,y\n")
        for a, b in zip(x, y):
            f.write("%.9g,%.9g\n" % (a, b))
    with open(os.path.join(OUT, "cases.csv"), "w") as f:
        f.write("name,window,nperseg,noverlap,nfft,detrend,n,fs_hz\n")
        for name, win, nperseg, noverlap, nfft, detrend, n, fs in CASES:
            f.write(f"{name},{win},{nperseg},{noverlap},{nfft},"
                    f"{'constant' if detrend else 'none'},{n},{fs!r}\n")
            xs, ys = x[:n], y[:n]
            kw = dict(fs=fs, window=win, nperseg=nperseg, noverlap=noverlap, nfft=nfft,
                      detrend=detrend, scaling="density")
            freq, pxx = sig.welch(xs, **kw)
            _, pyy = sig.welch(ys, **kw)
            _, pxy = sig.csd(xs, ys, **kw)
            with np.errstate(divide="ignore", invalid="ignore"):
                h1 = pxy / pxx
                coh = np.abs(pxy) ** 2 / (pxx * pyy)
            assert len(freq) == nfft // 2 + 1
            with open(os.path.join(OUT, f"{name}.csv"), "w") as g:
                g.write("freq_hz,pxx,pyy,pxy_re,pxy_im,h1_re,h1_im,coherence\n")
                for row in zip(freq, pxx, pyy, pxy.real, pxy.imag, h1.real, h1.imag, coh):
                    g.write(",".join("%.10g" % v for v in row) + "\n")
    print(f"wrote {len(CASES)} cases to {os.path.normpath(OUT)} (scipy {scipy.__version__}, "
          f"numpy {np.__version__})")


if __name__ == "__main__":
    main()
