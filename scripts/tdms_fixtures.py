#!/usr/bin/env python3
"""Writes the TDMS fixtures of tests/data/tdms with npTDMS and how npTDMS reads them back
(expected.json), for the Rust reader's test (tests/daq.rs) to compare value by value.

hammer.tdms: group `Hammer` with `force` (float64, 51.2 kHz, unit N) and `acc` (float32, unit
m/s^2), group `Other` with an int16 channel also named `force` and a uint8 `flags`, written in
three segments (the second with new data for the Hammer channels only, the third again for
all). npTDMS writes little-endian contiguous data; the reader's interleaved and big-endian
paths are checked by its unit test on bytes built by hand.

Needs npTDMS and numpy (`pip install npTDMS`):

    python3 scripts/tdms_fixtures.py
"""

import json
import os

import numpy as np
from nptdms import ChannelObject, GroupObject, RootObject, TdmsFile, TdmsWriter

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "tdms")


def main():
    path = os.path.join(HERE, "hammer.tdms")
    fs = 51200.0
    t = np.arange(400) / fs
    force = np.where(t < 1e-3, 220.0 * np.sin(np.pi * t / 1e-3), 0.0) + 0.01 * np.sin(3e3 * t)
    acc = (-4.0 * np.exp(-30.0 * t) * np.sin(2 * np.pi * 812.0 * t)).astype(np.float32)
    props = {"wf_increment": 1.0 / fs, "wf_start_offset": 0.0}
    with TdmsWriter(path) as w:
        w.write_segment([
            RootObject({"title": "hammer test"}),
            GroupObject("Hammer"),
            ChannelObject("Hammer", "force", force[:150], dict(props, unit_string="N")),
            ChannelObject("Hammer", "acc", acc[:150], dict(props, unit_string="m/s^2")),
            GroupObject("Other"),
            ChannelObject("Other", "force", np.arange(-5, 45, dtype=np.int16)),
            ChannelObject("Other", "flags", np.arange(50, dtype=np.uint8)),
        ])
        w.write_segment([
            ChannelObject("Hammer", "force", force[150:300]),
            ChannelObject("Hammer", "acc", acc[150:300]),
        ])
        w.write_segment([
            ChannelObject("Hammer", "force", force[300:]),
            ChannelObject("Hammer", "acc", acc[300:]),
            ChannelObject("Other", "force", np.arange(45, 55, dtype=np.int16)),
            ChannelObject("Other", "flags", np.arange(50, 60, dtype=np.uint8)),
        ])
    out = {"files": {}}
    f = TdmsFile.read(path)
    chans = []
    for g in f.groups():
        for c in g.channels():
            chans.append({
                "group": g.name, "channel": c.name,
                "values": [float(v) for v in c[:]],
                "wf_increment": c.properties.get("wf_increment"),
                "unit": c.properties.get("unit_string"),
            })
    out["files"]["hammer.tdms"] = chans
    with open(os.path.join(HERE, "expected.json"), "w") as fh:
        json.dump(out, fh)
        fh.write("\n")


if __name__ == "__main__":
    main()
