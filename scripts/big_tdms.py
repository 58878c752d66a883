"""Writes a TDMS file of one segment holding N one-value float64 channels (`ch0`, `ch1`, ...,
each with `wf_increment`): the reader's speed in the channel count (docs/performance.md,
"Reading DAQ files").

    python3 scripts/big_tdms.py 120000 big.tdms
"""

import struct
import sys


def text(t):
    b = t.encode()
    return struct.pack("<I", len(b)) + b


def main(n, out):
    meta = struct.pack("<I", n)
    for k in range(n):
        meta += text(f"/'g'/'ch{k}'") + struct.pack("<IIIQ", 20, 10, 1, 1)
        meta += struct.pack("<I", 1) + text("wf_increment") + struct.pack("<Id", 10, 1e-3)
    raw = b"".join(struct.pack("<d", float(k)) for k in range(n))
    toc = (1 << 1) | (1 << 2) | (1 << 3)
    lead = b"TDSm" + struct.pack("<II", toc, 4713) + struct.pack("<QQ", len(meta) + len(raw), len(meta))
    with open(out, "wb") as f:
        f.write(lead + meta + raw)


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2])
