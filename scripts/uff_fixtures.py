#!/usr/bin/env python3
"""Writes the universal file fixtures of tests/data/uff with pyuff and how pyuff reads them back
(expected.json), for the Rust reader's test (tests/daq.rs) to compare value by value.

- time_ascii.uff: two time records (dataset 58, function type 1, double precision, even
  spacing): a hammer-like force at node 1 +Z and a decaying response at node 2 +Z, 2048 Hz;
- time_binary.uff: the same as 58b (binary, little-endian);
- time_single.uff: the same in single precision (ordinate type 2, 13-character fields);
- frf_uneven.uff: a complex FRF (function type 4, double) on an uneven abscissa.

Needs pyuff and numpy (`pip install pyuff`):

    python3 scripts/uff_fixtures.py
"""

import json
import os

import numpy as np
import pyuff

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "uff")


def time_sets():
    fs, n = 2048.0, 300
    t = np.arange(n) / fs
    force = np.where(t < 2e-3, 150.0 * np.sin(np.pi * t / 2e-3), 0.0) + 1e-3 * np.cos(7 * t)
    resp = -3.2e-4 * np.exp(-8.0 * t) * np.sin(2 * np.pi * 41.5 * t) + 1.25e-7 * (t * 1e3) ** 2
    sets = []
    for node, data, unit in ((1, force, "N"), (2, resp, "m/s^2")):
        sets.append({
            "type": 58, "func_type": 1, "rsp_node": node, "rsp_dir": 3, "ref_node": 1,
            "ref_dir": 3, "x": t, "data": data, "abscissa_spacing": 1,
            "id1": f"time record node {node}", "ordinate_axis_units_lab": unit,
            "abscissa_axis_units_lab": "s", "orddenom_spec_data_type": 0,
        })
    return sets


def write(name, sets, **kw):
    path = os.path.join(HERE, name)
    if os.path.exists(path):
        os.remove(path)
    uff = pyuff.UFF(path)
    uff.write_sets(sets, mode="add", **kw)


def main():
    write("time_ascii.uff", time_sets())
    write("time_binary.uff", [dict(s, binary=1) for s in time_sets()])
    single = [dict(s, ord_data_type=2) for s in time_sets()]
    write("time_single.uff", single, force_double=False)
    f = np.array([1.0, 1.5, 2.5, 4.0, 6.5, 10.0, 16.0])
    h = 1.0 / (20.0**2 - f**2 + 2j * 0.02 * 20.0 * f)
    write("frf_uneven.uff", [{
        "type": 58, "func_type": 4, "rsp_node": 3, "rsp_dir": -2, "ref_node": 1, "ref_dir": 3,
        "x": f, "data": h, "abscissa_spacing": 0, "id1": "uneven FRF",
        "ordinate_axis_units_lab": "m/N", "orddenom_spec_data_type": 0,
    }])
    out = {"pyuff": pyuff.__version__, "files": {}}
    for name in sorted(os.listdir(HERE)):
        if not name.endswith(".uff"):
            continue
        sets = pyuff.UFF(os.path.join(HERE, name)).read_sets()
        if isinstance(sets, dict):
            sets = [sets]
        out["files"][name] = [{
            "func_type": int(s["func_type"]), "rsp_node": int(s["rsp_node"]),
            "rsp_dir": int(s["rsp_dir"]), "ref_node": int(s["ref_node"]),
            "ref_dir": int(s["ref_dir"]), "x": [float(v) for v in s["x"]],
            "re": [float(v) for v in np.real(s["data"])],
            "im": [float(v) for v in np.imag(s["data"])],
        } for s in sets]
    with open(os.path.join(HERE, "expected.json"), "w") as fh:
        json.dump(out, fh)
        fh.write("\n")


if __name__ == "__main__":
    main()
