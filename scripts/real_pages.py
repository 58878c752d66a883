#!/usr/bin/env python3
"""The pages host-harness writes from the repository's real recordings (tests/data/real: pyidi's
Photron showcase beam and small Phantom file, LADISK's beam filmed through an impact test),
opened in a headless browser as scripts/check_pages.py opens ours: each loads with no console
error and no network request, its header names every input with the SHA-256 computed here, no
two labels on the frame overlap, and the camera's ema page draws the beam's geometry (its lines
counted against the file). With --screenshots DIR, the pages as a user sees them (docs/img).

    python3 scripts/real_pages.py --harness target/release/host-harness --work target/real-pages \
        [--screenshots docs/img]

Needs what check_pages.py needs (chromium, chromedriver, selenium).
"""
import argparse
import sys
from pathlib import Path

import check_pages as cp

REAL = Path(__file__).resolve().parents[1] / "tests" / "data" / "real"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--harness", default="target/debug/host-harness")
    ap.add_argument("--work", default="target/real-pages")
    ap.add_argument("--screenshots", default=None)
    args = ap.parse_args()
    h = str(Path(args.harness).resolve())
    work = Path(args.work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    show, cine, beam = REAL / "pyidi-showcase", REAL / "pyidi-cine", REAL / "ladisk-ema-beam"
    cp.run(h, "track", "--frames", show / "data_showcase.cih", "--points", show / "points.csv",
           "--tracker", "lk", "--out", work / "showcase", "--force")
    cp.run(h, "track", "--frames", cine / "data_small_cine.cine", "--frame-range", "1..234",
           "--points", cine / "points.csv", "--tracker", "lk", "--out", work / "cine", "--force")
    # the 15 points along the free beam, joined in order (lines alone: the file gives no
    # positions, so they stand on a line of their own)
    geometry = work / "beam.csv"
    geometry.write_text("# LADISK's free beam: 15 points along it\nfrom,to\n"
                        + "".join(f"{i},{i + 1}\n" for i in range(1, 15)))
    camera = [beam / "displacements_lk.npy", beam / "camera.lvm"]
    cp.run(h, "ema", "--response", camera[0], "--response-fs", "15000", "--excitation",
           camera[1], "--excitation-col", "Force (Trigger)", "--impact", "--geometry", geometry,
           "--out", work / "beam-camera", "--force")
    accel = beam / "acceleration.lvm"
    cp.run(h, "ema", "--response", accel, "--excitation", accel, "--excitation-col",
           "Force (Trigger)", "--impact", "--out", work / "beam-accel", "--force")

    def rows(d):
        return len((d / "modes.csv").read_text().strip().splitlines()) - 1

    drv = cp.browser(work)
    try:
        cp.check_report(drv, work / "showcase" / "report.html", 15, None, "showcase track",
                        header=("track", [show / "data_showcase.cih", show / "data_showcase.mraw",
                                          show / "points.csv"]))
        cp.check_report(drv, work / "cine" / "report.html", 4, None, "cine track",
                        header=("track", [cine / "data_small_cine.cine", cine / "points.csv"]))
        cp.check_report(drv, work / "beam-camera" / "report.html", None,
                        rows(work / "beam-camera"), "beam ema, camera",
                        header=("ema", camera + [geometry]))
        cp.check_wire(drv, work / "beam-camera" / "report.html", geometry, "beam ema, camera")
        cp.check_report(drv, work / "beam-accel" / "report.html", None, 0, "beam ema, accel",
                        rows=rows(work / "beam-accel"), header=("ema", [accel]))
        from selenium.webdriver.common.by import By
        one = drv.find_elements(By.ID, "one-point")
        cp.check(len(one) == 1, "beam ema, accel: one point measured, no shape animated")
        if args.screenshots:
            shots = Path(args.screenshots)
            shots.mkdir(parents=True, exist_ok=True)
            for page, name, height in (("showcase", "real-track.png", 1100),
                                       ("beam-camera", "real-ema.png", 1500)):
                drv.set_window_size(1200, height)
                cp.open_page(drv, work / page / "report.html")
                drv.save_screenshot(str(shots / name))
    finally:
        drv.quit()
    print(f"{len(cp.failures)} failed" if cp.failures else "all checks passed")
    return 1 if cp.failures else 0


if __name__ == "__main__":
    sys.exit(main())
