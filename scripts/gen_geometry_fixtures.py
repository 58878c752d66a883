"""Fixtures for host-harness's geometry fits (tests/data/geometry/opencv.json): point pairs
with noise and the map OpenCV fits to them, an independent implementation:
``cv2.estimateAffinePartial2D`` (rotation, uniform scale and shift, refined by
Levenberg-Marquardt on the reprojection error over every pair: with all pairs inliers, the
least-squares similarity) and ``cv2.findHomography`` with method 0 (least squares over all
pairs, refined the same way).

    python3 scripts/gen_geometry_fixtures.py   # needs numpy and opencv-python-headless
"""

import json
from pathlib import Path

import cv2
import numpy as np

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "geometry" / "opencv.json"


def main():
    rng = np.random.default_rng(47)
    cases = []
    for i in range(6):
        n = [3, 4, 6, 8, 12, 20][i]
        src = rng.uniform(0, 640, size=(n, 2))
        # a camera's small roll, zoom and shift; then a view turned a little
        a, s = rng.normal(0, 0.01), 1 + rng.normal(0, 0.002)
        sim = np.array([[s * np.cos(a), -s * np.sin(a), rng.normal(0, 2)],
                        [s * np.sin(a), s * np.cos(a), rng.normal(0, 2)]])
        dst = src @ sim[:, :2].T + sim[:, 2] + rng.normal(0, 0.05, size=(n, 2))
        m, inl = cv2.estimateAffinePartial2D(
            src.astype(np.float64), dst.astype(np.float64), method=cv2.RANSAC,
            ransacReprojThreshold=1e6, maxIters=2000, confidence=0.999, refineIters=50,
        )
        assert int(inl.sum()) == n
        cases.append({"model": "similarity", "src": src.tolist(), "dst": dst.tolist(),
                      "h": m.ravel().tolist() + [0.0, 0.0, 1.0]})
    for i in range(5):
        n = [4, 5, 6, 9, 16][i]
        src = rng.uniform(0, 640, size=(n, 2))
        h = np.array([[1.1, 0.05, 20], [-0.03, 0.95, 10], [2e-4, -1e-4, 1.0]])
        p = np.c_[src, np.ones(n)] @ h.T
        dst = p[:, :2] / p[:, 2:] + rng.normal(0, 0.05, size=(n, 2))
        m, _ = cv2.findHomography(src, dst, 0)
        cases.append({"model": "homography", "src": src.tolist(), "dst": dst.tolist(),
                      "h": (m / m[2, 2]).ravel().tolist()})
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps({"opencv": cv2.__version__, "cases": cases}, indent=1) + "\n")
    print(f"wrote {len(cases)} cases to {OUT}")


if __name__ == "__main__":
    main()
