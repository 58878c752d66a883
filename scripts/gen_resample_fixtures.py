#!/usr/bin/env python3
"""Generate the scipy reference fixtures of firmware-core's Fourier upsampler.

Run from the repository root (needs numpy and scipy: `pip install numpy scipy`):

    python3 scripts/gen_resample_fixtures.py

It writes, under firmware-core/tests/fixtures/resample/:

* cases.csv      name,n,m
* <name>_x.csv   the input record (one value per line; float32 values written with 9
                 significant digits, so the Rust test and scipy see the same numbers):
                 deterministic (numpy PCG64, seed 2016) smooth random content, a sum of
                 sinusoids at random frequencies below n/2 plus white noise.
* <name>_y.csv   scipy.signal.resample(x, m) (float64, 12 significant digits)

The fixtures are consumed by firmware-core/tests/resample_scipy.rs.
"""

import os

import numpy as np
import scipy.signal as sig

OUT = os.path.join("firmware-core", "tests", "fixtures", "resample")
CASES = [
    ("n15_m256", 15, 256),
    ("n16_m256", 16, 256),
    ("n120_m2048", 120, 2048),
    ("n121_m363", 121, 363),
    ("n75_m128", 75, 128),
    ("n100_m101", 100, 101),
    ("n1200_m20480", 1200, 20480),
]


FS_IN = 120.0  # camera rate for the acceleration fixtures, Hz


def main():
    os.makedirs(OUT, exist_ok=True)
    rng = np.random.Generator(np.random.PCG64(2016))
    with open(os.path.join(OUT, "cases.csv"), "w") as f:
        f.write("name,n,m\n")
        for name, n, m in CASES:
            f.write(f"{name},{n},{m}\n")
            t = np.arange(n)
            x = np.zeros(n)
            for _ in range(5):
                k = rng.uniform(0, n / 2)
                x += rng.normal() * np.sin(2 * np.pi * k * t / n + rng.uniform(0, 6.3))
            x += 0.3 * rng.normal(size=n) + 2.0
            x = x.astype(np.float32)
            np.savetxt(os.path.join(OUT, f"{name}_x.csv"), x, fmt="%.9g")
            y = sig.resample(x.astype(np.float64), m)
            np.savetxt(os.path.join(OUT, f"{name}_y.csv"), y, fmt="%.12g")
            # acceleration (method.md §2.3) of the resampled signal for a camera at FS_IN Hz:
            # FFT derivative in numpy, -omega^2 per bin (fftfreq), DC zeroed
            fs_out = FS_IN * m / n
            w = 2 * np.pi * np.fft.fftfreq(m, 1.0 / fs_out)
            spec = -(w**2) * np.fft.fft(y)
            spec[0] = 0.0
            a = np.fft.ifft(spec).real
            np.savetxt(os.path.join(OUT, f"{name}_a.csv"), a, fmt="%.9g")


if __name__ == "__main__":
    main()
