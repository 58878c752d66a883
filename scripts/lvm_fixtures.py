#!/usr/bin/env python3
"""Writes tests/data/lvm/expected.json: how lvm_read (the ladisk LabVIEW reader, MIT) reads each
of its own test files in tests/data/lvm, for the Rust reader's test to compare value by value.

Per file, per segment: the column names lvm_read gives (`Channel names`) and its data matrix by
column (NaN, where a field is empty or not a number, written as null). Run with lvm_read
installed (`pip install lvm_read`):

    python3 scripts/lvm_fixtures.py
"""

import json
import math
import os

import lvm_read

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "lvm")


def main():
    out = {"lvm_read": lvm_read.__version__, "files": {}}
    for name in sorted(os.listdir(HERE)):
        if not name.endswith(".lvm"):
            continue
        d = lvm_read.read(os.path.join(HERE, name), read_from_pickle=False, dump_file=False)
        segments = []
        for s in range(d["Segments"]):
            seg = d[s]
            data = seg["data"]
            cols = data.shape[1] if data.ndim == 2 else 0
            columns = []
            for c in range(cols):
                columns.append([None if math.isnan(v) else float(v) for v in data[:, c]])
            segments.append({"names": list(seg["Channel names"]), "columns": columns})
        out["files"][name] = segments
    with open(os.path.join(HERE, "expected.json"), "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
