#!/usr/bin/env python3
"""Writes the .npy fixtures of tests/data/npy with NumPy and their values as NumPy reads them
(expected.json), for the Rust reader's test (tests/daq.rs).

- pyidi.npy: a displacement array as pyidi returns it, shape (3 points, 40 samples, 2), float64;
- fortran_f4_be.npy: shape (2 points, 25 samples), big-endian float32, Fortran order;
- int16.npy: shape (30,), int16 with negative values.

Needs numpy:

    python3 scripts/npy_fixtures.py
"""

import json
import os

import numpy as np

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "npy")


def main():
    t = np.arange(40) / 500.0
    disp = np.zeros((3, 40, 2))
    for p in range(3):
        disp[p, :, 0] = (p + 1) * 0.31 * np.sin(2 * np.pi * 17.0 * t + p)
        disp[p, :, 1] = -0.05 * p * np.cos(2 * np.pi * 43.0 * t)
    np.save(os.path.join(HERE, "pyidi.npy"), disp)
    f = np.asfortranarray((np.arange(50).reshape(2, 25) * 0.37 - 4.1).astype(">f4"))
    np.save(os.path.join(HERE, "fortran_f4_be.npy"), f)
    np.save(os.path.join(HERE, "int16.npy"), (np.arange(30) * 997 - 15000).astype(np.int16))
    out = {}
    for name in sorted(os.listdir(HERE)):
        if name.endswith(".npy"):
            a = np.load(os.path.join(HERE, name))
            out[name] = {"shape": list(a.shape), "values": [float(v) for v in a.ravel(order="C")]}
    with open(os.path.join(HERE, "expected.json"), "w") as fh:
        json.dump(out, fh)
        fh.write("\n")


if __name__ == "__main__":
    main()
