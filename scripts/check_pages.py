#!/usr/bin/env python3
"""The pages host-harness writes, opened in a real headless browser (Debian's chromium and
chromedriver, driven by selenium): every report.html (track, analyze with and without an
accelerometer, with one target and several, modal, ema) loads with no
console error and no network request, holds what it should (the frame, one marker per target,
one animation per mode, the table of modes) and its animations advance; on pick.html scripted
clicks add windows, a drag moves one, Delete removes one, "save points.csv" downloads a file, and
`track --points` with that file gives the same tracks as with the hand-written one; on ema's
and modal's pages clicked poles are saved as poles.csv and `--poles` with it gives exactly those
modes.

    python3 scripts/check_pages.py --harness target/debug/host-harness --work target/pages

Needs `chromium` and `chromedriver` on the PATH (apt-get install chromium chromium-driver) and
selenium (pip). Exit status 0 when every check passes, 1 otherwise.
"""
import argparse
import csv
import hashlib
import json
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what, flush=True)
    if not ok:
        failures.append(what)


def run(harness, *args):
    p = subprocess.run([harness, *map(str, args)], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(map(str, args))}: exit {p.returncode}\n{p.stderr}")
    return p.stdout


def browser(download_dir):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1400,1200",
              "--disable-dev-shm-usage"):
        opts.add_argument(a)
    opts.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    drv = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)
    drv.execute_cdp_cmd("Browser.setDownloadBehavior",
                        {"behavior": "allow", "downloadPath": str(download_dir)})
    return drv


def network_requests(drv):
    """URLs the page asked the network for (the performance log's Network events; data: and
    blob: URLs are not the network)."""
    urls = []
    for entry in drv.get_log("performance"):
        msg = json.loads(entry["message"])["message"]
        if msg.get("method") == "Network.requestWillBeSent":
            url = msg["params"]["request"]["url"]
            if not url.startswith(("data:", "blob:", "file:")):
                urls.append(url)
    return urls


def console_errors(drv):
    return [e["message"] for e in drv.get_log("browser") if e["level"] == "SEVERE"]


def open_page(drv, path):
    drv.get_log("performance")
    drv.get_log("browser")
    drv.get(Path(path).resolve().as_uri())
    time.sleep(0.5)


def sha256_of(path):
    """SHA-256 of a file, or of a folder as ``sha256sum`` lists its files (not hidden ones, in
    name order, ``digest  name`` lines), hashed again: what the report's header states."""
    path = Path(path)
    if path.is_file():
        return hashlib.sha256(path.read_bytes()).hexdigest()
    lines = "".join(f"{sha256_of(f)}  {f.name}\n" for f in sorted(path.iterdir())
                    if f.is_file() and not f.name.startswith("."))
    return hashlib.sha256(lines.encode()).hexdigest()


def check_header(drv, command, inputs, what):
    """The page's header: the version with a commit, the command as typed, every input's
    SHA-256 (computed here, independently), the settings with the defaults marked."""
    from selenium.webdriver.common.by import By

    head = drv.find_elements(By.CSS_SELECTOR, "section#provenance")
    check(len(head) == 1, f"{what}: the header")
    if not head:
        return
    version = head[0].find_element(By.CSS_SELECTOR, "tr.version td").text
    check(version.startswith("vibcam ") and "commit" in version, f"{what}: version {version}")
    typed = head[0].find_element(By.CSS_SELECTOR, "tr.command td").text
    check(typed.startswith(f"host-harness {command} "), f"{what}: the command {typed[:60]}")
    got = sorted(r.get_attribute("data-sha256")
                 for r in head[0].find_elements(By.CSS_SELECTOR, "tr.input"))
    want = sorted(sha256_of(p) for p in inputs)
    check(got == want, f"{what}: the inputs' SHA-256 {got} (want {want})")
    given = drv.find_elements(By.CSS_SELECTOR, "#settings li.setting:not(.default)")
    defaults = drv.find_elements(By.CSS_SELECTOR, "#settings li.setting.default")
    check(len(given) >= 1 and len(defaults) >= 1,
          f"{what}: settings given ({len(given)}) and default ({len(defaults)}) marked")


def check_labels(drv, what, at_least=1):
    """No two labels on the frame overlap (their bounding rectangles as the browser lays them
    out), and at least ``at_least`` are drawn."""
    rects = drv.execute_script(
        "return Array.from(document.querySelectorAll('svg#frame text')).map(function(t){"
        "var r=t.getBoundingClientRect();return [r.left,r.top,r.right,r.bottom];});")
    hits = [(i, j) for i in range(len(rects)) for j in range(i + 1, len(rects))
            if rects[i][0] < rects[j][2] and rects[j][0] < rects[i][2]
            and rects[i][1] < rects[j][3] and rects[j][1] < rects[i][3]]
    check(len(rects) >= at_least, f"{what}: {len(rects)} labels drawn")
    check(hits == [], f"{what}: no two labels overlap ({len(hits)} pairs do)")


def check_print(drv, path, what):
    """The page printed by Chromium (A4, its print stylesheet): a PDF with a page per section
    (each `h2` starts one); written beside the output folder as ``FOLDER.pdf`` (never inside
    it: a file the command did not write keeps ``--force`` from replacing the folder)."""
    import base64
    from selenium.webdriver.common.print_page_options import PrintOptions

    open_page(drv, path)
    sections = len(drv.find_elements("css selector", "h2"))
    opts = PrintOptions()
    opts.page_width, opts.page_height = 21.0, 29.7
    pdf = base64.b64decode(drv.print_page(opts))
    Path(path).parent.with_suffix(".pdf").write_bytes(pdf)
    pages = len(re.findall(rb"/Type\s*/Page[^s]", pdf))
    check(pdf.startswith(b"%PDF"), f"{what}: printed to PDF ({len(pdf)} bytes)")
    check(pages >= sections >= 2, f"{what}: {pages} printed pages for {sections} sections")


def check_svd_range(drv, folder, what):
    """The singular-value figure of the page in ``folder``: at most four curves, and a dB axis
    from no lower than 40 dB under the first singular value's 5th percentile (10 dB for the
    ticks' rounding; ``svd.csv`` read here) to its peak."""
    import math

    with open(folder / "svd.csv", newline="") as f:
        rows = list(csv.DictReader(f))[1:]
    s1 = sorted(10 * math.log10(max(float(r["s1"]), 1e-300)) for r in rows)
    floor, top = s1[len(s1) // 20] - 40.0, s1[-1]
    ticks = drv.execute_script(
        "var out=[];document.querySelectorAll('figure').forEach(function(f){"
        "var c=f.querySelector('figcaption');if(c&&c.textContent==='svd'){"
        "f.querySelectorAll('text[text-anchor=end]').forEach(function(t){"
        "out.push(t.textContent.trim());});}});return out;")
    values = [float(t) for t in ticks if re.fullmatch(r"-?[0-9.]+", t)]
    check(len(values) >= 2, f"{what}: {len(values)} dB ticks on the singular values")
    if values:
        check(min(values) >= floor - 10 and max(values) <= top + 10,
              f"{what}: singular values drawn from {min(values)} to {max(values)} dB "
              f"(floor {floor:.1f}, peak {top:.1f})")
    legend = drv.execute_script(
        "var n=0;document.querySelectorAll('figure').forEach(function(f){"
        "var c=f.querySelector('figcaption');if(c&&c.textContent==='svd'){"
        "f.querySelectorAll('text').forEach(function(t){"
        "if(/^s[0-9]+$/.test(t.textContent.trim())){n++;}});}});return n;")
    check(1 <= legend <= 4, f"{what}: {legend} singular values drawn (at most 4)")


def check_report(drv, path, markers, modes, what, rows=None, header=None):
    """A report page: size, no console error or request, the frame and markers, the modes'
    table and animations, the report's text; with ``header`` (command, inputs) its header."""
    from selenium.webdriver.common.by import By

    open_page(drv, path)
    if header is not None:
        check_header(drv, *header, what)
    size = Path(path).stat().st_size
    check(size < 5_000_000, f"{what}: {size / 1e6:.2f} MB")
    check(console_errors(drv) == [], f"{what}: no console error {console_errors(drv)}")
    check(network_requests(drv) == [], f"{what}: no network request")
    if markers is not None:
        check(len(drv.find_elements(By.CSS_SELECTOR, "svg#frame image")) == 1,
              f"{what}: the frame")
        n = len(drv.find_elements(By.CSS_SELECTOR, "svg#frame g.marker"))
        check(n == markers, f"{what}: {n} markers, {markers} targets")
        check_labels(drv, what)
    if modes is not None:
        shapes = drv.find_elements(By.CSS_SELECTOR, "svg.mode-shape")
        check(len(shapes) == modes, f"{what}: {len(shapes)} animations, {modes} modes")
        got = drv.find_elements(By.CSS_SELECTOR, "table#modes tr")
        want = modes if rows is None else rows
        check(len(got) == want + 1, f"{what}: the table of modes has {len(got) - 1} rows")
        if shapes:
            def places():
                dots = shapes[0].find_elements(By.CSS_SELECTOR, "circle.shape-dot")
                wires = shapes[0].find_elements(By.CSS_SELECTOR, "line.wire")
                return [(e.get_attribute("cx"), e.get_attribute("cy")) for e in dots] + \
                    [tuple(e.get_attribute(k) for k in ("x1", "y1", "x2", "y2")) for e in wires]
            a = places()
            time.sleep(0.35)
            b = places()
            check(a != b, f"{what}: the first shape's animation advances")
            drv.find_element(By.ID, "play").click()
            c = places()
            time.sleep(0.35)
            check(places() == c, f"{what}: pause stops it")
            check(drv.find_element(By.ID, "wire").text.strip() != "",
                  f"{what}: the page says where the shapes' lines come from")
    if drv.find_elements(By.ID, "mac"):
        out = drv.execute_script(
            "var s=document.getElementById('mac').getBoundingClientRect();"
            "return Array.from(document.querySelectorAll('svg#mac text')).filter(function(t){"
            "var r=t.getBoundingClientRect();return r.left<s.left-0.5||r.right>s.right+0.5||"
            "r.top<s.top-0.5||r.bottom>s.bottom+0.5;}).map(function(t){return t.textContent;});")
        check(out == [], f"{what}: every MAC label within its figure {out}")
    check(drv.find_element(By.ID, "report-text").text.strip() != "", f"{what}: the report")


def check_scrubber(drv, path, targets, lost_target, lost_frames, what):
    """The frame scrubber: one window per target; moving the slider shows another frame and
    moves the windows; a frame where `lost_target` is lost (0-based frame in `lost_frames`)
    draws it as lost."""
    from selenium.webdriver.common.by import By

    open_page(drv, path)
    gs = drv.find_elements(By.CSS_SELECTOR, "svg#scrub g.scrub-target")
    check(len(gs) == targets, f"{what}: scrubber has {len(gs)} windows, {targets} targets")
    slider = drv.find_element(By.ID, "frame-slider")
    data = json.loads(drv.find_element(By.ID, "scrub-data").get_attribute("textContent"))
    frames = [f["index"] for f in data["frames"]]

    def show(i):
        drv.execute_script(
            "arguments[0].value=arguments[1];arguments[0].dispatchEvent(new Event('input'));",
            slider, i)
        img = drv.find_element(By.ID, "scrub-image").get_attribute("href")
        where = [(g.get_attribute("data-x"), g.get_attribute("data-y")) for g in gs]
        lost = [g.find_element(By.CSS_SELECTOR, "rect").get_attribute("class") == "lost"
                for g in gs]
        return img, where, lost

    img0, where0, lost0 = show(0)
    check(not any(lost0), f"{what}: nothing lost in the first frame")
    img1, where1, _ = show(len(frames) - 1)
    check(img1 != img0, f"{what}: the slider shows another frame")
    check(where1 != where0, f"{what}: the slider moves the windows")
    check(drv.find_element(By.ID, "frame-label").text.startswith(f"frame {frames[-1] + 1}"),
          f"{what}: the label names the frame")
    inside = [i for i, f in enumerate(frames) if f in lost_frames]
    check(bool(inside), f"{what}: a frame of the loss is among the scrubber's")
    if inside:
        _, _, lost = show(inside[0])
        check(lost[lost_target] and sum(lost) == 1,
              f"{what}: frame {frames[inside[0]] + 1} draws target {lost_target + 1} as lost")
    check(len(drv.find_elements(By.CSS_SELECTOR, "svg#scores polyline.score-line")) == targets,
          f"{what}: a score line per target")
    check(console_errors(drv) == [], f"{what}: no console error {console_errors(drv)}")


def occluded(rec, work, target, frames):
    """A copy of `rec`'s frames with `target`'s window (0-based, points.csv) painted black in
    `frames` (0-based): a loss anyone can see."""
    from PIL import Image

    with open(rec / "points.csv", newline="") as f:
        p = list(csv.DictReader(f))[target]
    x, y, w, h = (float(p[k]) for k in ("x", "y", "w", "h"))
    out = work / "occluded"
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    for k, src in enumerate(sorted((rec / "frames").iterdir())):
        im = Image.open(src)
        if k in frames:
            im = im.copy()
            im.paste(0, (int(x - w // 2 - 2), int(y - h // 2 - 2), int(x + w // 2 + 3),
                         int(y + h // 2 + 3)))
        im.save(out / src.name)
    return out


def click_at(drv, svg, x_px, y_px):
    """A real mouse click at image pixel (x, y) (origin at the top-left pixel's centre)."""
    from selenium.webdriver.common.action_chains import ActionChains

    cx, cy = drv.execute_script(
        "var s=arguments[0],p=s.createSVGPoint();p.x=arguments[1]+0.5;p.y=arguments[2]+0.5;"
        "var q=p.matrixTransform(s.getScreenCTM());var r=s.getBoundingClientRect();"
        "return [q.x-r.left-r.width/2,q.y-r.top-r.height/2];", svg, x_px, y_px)
    ActionChains(drv).move_to_element_with_offset(svg, cx, cy).click().perform()
    return cx, cy


def downloads_into(drv, folder):
    """An empty `folder`, where the browser's downloads go from now on."""
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    drv.execute_cdp_cmd("Browser.setDownloadBehavior",
                        {"behavior": "allow", "downloadPath": str(folder)})
    return folder


def downloaded(path, what):
    """Whether the download `path` arrived within 5 s (checked as `what`)."""
    for _ in range(50):
        if path.exists() and path.stat().st_size > 0:
            break
        time.sleep(0.1)
    check(path.exists(), what)
    return path.exists()


def check_pick(drv, harness, work, rec):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    hand = rec / "points.csv"
    with open(hand, newline="") as f:
        rows = list(csv.DictReader(f))
    # the hand-written file: the recording's targets at whole pixels, 31 px windows
    written = work / "hand.csv"
    with open(written, "w") as f:
        f.write("target,x,y,w,h\n")
        for r in rows:
            f.write(f"{r['target']},{round(float(r['x']))},{round(float(r['y']))},31,31\n")
    page = work / "pick.html"
    run(harness, "pick", "--frames", rec / "frames", "--out", page, "--force")
    downloads = downloads_into(drv, work / "downloads")
    open_page(drv, page)
    check(console_errors(drv) == [], "pick.html: no console error")
    check(network_requests(drv) == [], "pick.html: no network request")
    for k, v in (("size-w", "31"), ("size-h", "31")):
        el = drv.find_element(By.ID, k)
        el.clear()
        el.send_keys(v)
    svg = drv.find_element(By.ID, "pick")
    with open(written, newline="") as f:
        want = list(csv.DictReader(f))
    for r in want:
        click_at(drv, svg, float(r["x"]), float(r["y"]))
    n = len(drv.find_elements(By.CSS_SELECTOR, "svg#pick g.window"))
    check(n == len(want), f"pick.html: {n} windows after {len(want)} clicks")
    # one more, dragged, then deleted
    click_at(drv, svg, 80, 80)
    rect = drv.find_elements(By.CSS_SELECTOR, "svg#pick g.window rect")[-1]
    before = float(rect.get_attribute("x"))
    ActionChains(drv).click_and_hold(rect).move_by_offset(40, 0).release().perform()
    rect = drv.find_elements(By.CSS_SELECTOR, "svg#pick g.window rect")[-1]
    check(float(rect.get_attribute("x")) > before + 2, "pick.html: a drag moves a window")
    ActionChains(drv).send_keys(Keys.DELETE).perform()
    n = len(drv.find_elements(By.CSS_SELECTOR, "svg#pick g.window"))
    check(n == len(want), "pick.html: Delete removes the selected window")
    drv.find_element(By.ID, "save").click()
    saved = downloads / "points.csv"
    if not downloaded(saved, "pick.html: save downloads points.csv"):
        return
    # the same tracks from the saved file as from the hand-written one
    out_a, out_b = work / "track-saved", work / "track-hand"
    run(harness, "track", "--frames", rec / "frames", "--fps", "120", "--points", saved,
        "--threshold", "127", "--out", out_a, "--force", "--no-plots")
    run(harness, "track", "--frames", rec / "frames", "--fps", "120", "--points", written,
        "--threshold", "127", "--out", out_b, "--force", "--no-plots")

    def tracks(d):
        with open(d / "displacement.csv", newline="") as f:
            return [(r["frame"], r["target"], r["cx"], r["cy"]) for r in csv.DictReader(f)]

    a, b = tracks(out_a), tracks(out_b)
    check(a == b and len(a) > 0,
          f"pick.html: track --points with the saved file equals the hand-written one "
          f"({len(a)} rows)")
    # and the page shows an existing file's points
    run(harness, "pick", "--frames", rec / "frames", "--points", written, "--out", page,
        "--force")
    open_page(drv, page)
    n = len(drv.find_elements(By.CSS_SELECTOR, "svg#pick g.window"))
    check(n == len(want), f"pick.html --points: {n} windows shown")
    # a polygon drawn around the first target (clicks on its window add vertices, not
    # select it; a click lands within 2 px of where it was aimed, the page being scaled), its
    # text taken by `pick --region`, whose points lie inside it
    from selenium.webdriver.support.ui import Select

    Select(drv.find_element(By.ID, "tool")).select_by_value("polygon")
    svg = drv.find_element(By.ID, "pick")
    x0, y0 = float(want[0]["x"]), float(want[0]["y"])
    # 24 px across, inside the frame (the first target is near its left edge)
    lo_x, lo_y = max(x0 - 12, 1.0), max(y0 - 12, 1.0)
    corners = [(lo_x, lo_y), (lo_x + 24, lo_y), (lo_x + 24, lo_y + 24), (lo_x, lo_y + 24)]
    for x, y in corners:
        click_at(drv, svg, x, y)
    text = drv.execute_script("return window.vibcamRegion();")
    shown = drv.find_element(By.ID, "region").get_attribute("value")
    vertices = [tuple(float(v) for v in q.split(",")) for q in text.split(";")] if text else []
    check(len(vertices) == 4 and shown == text
          and all(abs(a - x) <= 2 and abs(b - y) <= 2 for (a, b), (x, y) in zip(vertices, corners))
          and len(drv.find_elements(By.CSS_SELECTOR, "svg#pick polygon.region")) == 1,
          f"pick.html: four clicks draw the polygon {text!r} (clicked {corners})")
    n = len(drv.find_elements(By.CSS_SELECTOR, "svg#pick g.window"))
    check(n == len(want), f"pick.html: clicks in polygon mode add no window ({n})")
    region_points = work / "region.csv"
    run(harness, "pick", "--frames", rec / "frames", "--region", text, "--spacing", "4",
        "--points-out", region_points, "--out", work / "region.html", "--force")
    with open(region_points, newline="") as f:
        got = [(float(r["x"]), float(r["y"])) for r in csv.DictReader(f)]
    inside = [v[0] for v in vertices], [v[1] for v in vertices]
    check(len(got) > 0
          and all(min(inside[0]) <= x <= max(inside[0]) and min(inside[1]) <= y <= max(inside[1])
                  for x, y in got),
          f"pick --region with the page's polygon: {len(got)} points, all inside it")


def check_pole_picker(drv, harness, work, name, args, method=None):
    """On the page of `name` (ema, modal): hover shows a pole, clicks pick one pole per mode
    (of `method`, every mode without) but the last, "save poles.csv" downloads them, and the
    command (`args` without --out) with `--poles` and that file gives exactly those modes."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    what = f"{name} pole picker"
    downloads = downloads_into(drv, work / f"downloads-{name}-poles")
    open_page(drv, work / name / "report.html")
    data = json.loads(drv.find_element(By.ID, "pole-data").get_attribute("textContent"))["poles"]
    circles = drv.find_elements(By.CSS_SELECTOR, "svg#pole-picker circle.pole")
    check(len(circles) > 0 and len(circles) <= len(data),
          f"{what}: {len(circles)} poles drawn of {len(data)}")
    check("<figcaption>stabilisation</figcaption>" not in drv.page_source,
          f"{what}: the diagram is drawn once (the picker, not also the static figure)")

    def modes_of(d):
        with open(d / "modes.csv", newline="") as f:
            return [(float(r["f_hz"]), float(r["damping"])) for r in csv.DictReader(f)
                    if method is None or r["method"] == method]

    def pole(c):
        return data[int(c.get_attribute("data-i"))]

    found = modes_of(work / name)
    # per mode found but the last, the highest-order pole of its cluster nearest to it
    in_modes = [c for c in circles if "mode" in c.get_attribute("class").split()]
    chosen = [min(in_modes, key=lambda c: (round(abs(pole(c)[0] - f) / f, 3), -pole(c)[2]))
              for f, _ in found[:-1]]
    check(len(found) >= 2 and len(chosen) == len(found) - 1,
          f"{what}: {len(chosen)} poles to pick of {len(found)} modes")
    if not chosen:
        return
    ActionChains(drv).move_to_element(chosen[0]).perform()
    hover = drv.find_element(By.ID, "pole-hover").text
    check(f"{pole(chosen[0])[0]:.3f} Hz, damping" in hover,
          f"{what}: hover shows the pole ({hover!r})")
    for c in chosen:
        ActionChains(drv).move_to_element(c).click().perform()
    picked = drv.find_elements(By.CSS_SELECTOR, "svg#pole-picker circle.pole.picked")
    rows = drv.find_elements(By.CSS_SELECTOR, "table#picked tbody tr")
    check(len(picked) == len(chosen) and len(rows) == len(chosen),
          f"{what}: {len(picked)} circles and {len(rows)} rows picked by {len(chosen)} clicks")
    # a click more and the same click again leave the choice as it was
    extra = next(c for c in circles if c not in chosen)
    ActionChains(drv).move_to_element(extra).click().click().perform()
    n = drv.find_element(By.ID, "save-poles").get_attribute("data-count")
    check(n == str(len(chosen)), f"{what}: a second click drops a pole ({n} kept)")
    drv.find_element(By.ID, "save-poles").click()
    saved = downloads / "poles.csv"
    if not downloaded(saved, f"{what}: save downloads poles.csv"):
        return
    with open(saved, newline="") as f:
        given = [(float(r["f_hz"]), float(r["damping"])) for r in csv.DictReader(f)]
    want = sorted((pole(c)[0], pole(c)[1]) for c in chosen)
    check(given == want, f"{what}: poles.csv holds the picked poles at full precision")
    out = work / f"{name}-picked"
    run(harness, *args, "--poles", saved, "--out", out, "--force")
    got = modes_of(out)
    close = len(got) == len(want) and all(
        abs(a[0] - b[0]) <= 1e-9 * b[0] and abs(a[1] - b[1]) <= 1e-9 * b[1]
        for a, b in zip(got, want))
    check(close, f"{name} --poles with the saved file: exactly the {len(want)} poles picked "
                 f"({got} vs {want})")


def check_wire(drv, path, geometry, what):
    """Every mode shape of the page is drawn with the geometry's lines: as many `line.wire` as
    the file has lines, each between the nodes the file names (`data-a`/`data-b`, 0-based)."""
    from selenium.webdriver.common.by import By

    text = Path(geometry).read_text().splitlines()
    rows = [r.split(",") for r in text if r and not r.startswith("#")]
    start = [i for i, r in enumerate(rows) if r == ["from", "to"]][0]
    want = sorted((int(a) - 1, int(b) - 1) for a, b in rows[start + 1:])
    open_page(drv, path)
    shapes = drv.find_elements(By.CSS_SELECTOR, "svg.mode-shape")
    check(len(shapes) > 0, f"{what}: shapes drawn")
    for k, svg in enumerate(shapes):
        got = sorted((int(e.get_attribute("data-a")), int(e.get_attribute("data-b")))
                     for e in svg.find_elements(By.CSS_SELECTOR, "line.wire"))
        check(got == want, f"{what}: mode {k + 1} has {len(got)} lines, the geometry "
                           f"{len(want)}: {got} vs {want}")
    check(Path(geometry).name in drv.find_element(By.ID, "wire").text,
          f"{what}: the page names the geometry")


VIDEO_FRAMES_JS = """
const [id, done] = arguments;
const v = document.getElementById(id);
const grab = () => {
  const c = document.createElement('canvas');
  c.width = v.videoWidth; c.height = v.videoHeight;
  const g = c.getContext('2d');
  g.drawImage(v, 0, 0);
  return g.getImageData(0, 0, c.width, c.height).data;
};
const at = (t) => new Promise(r => { v.onseeked = () => r(grab()); v.currentTime = t; });
(async () => {
  v.pause();
  if (v.readyState < 2) {
    await new Promise(r => v.addEventListener('loadeddata', r, {once: true}));
  }
  const a = await at(0.0), b = await at(0.5);
  let diff = 0;
  for (let i = 0; i < a.length; i += 4) diff = Math.max(diff, Math.abs(a[i] - b[i]));
  done({w: v.videoWidth, h: v.videoHeight, diff: diff, duration: v.duration});
})().catch(e => done({error: String(e)}));
"""


def check_videos(drv, path, count, what):
    """Each magnified video on the page loads and plays: its frame at 0 s and at 0.5 s (a
    quarter period) differ."""
    from selenium.webdriver.common.by import By

    open_page(drv, path)
    videos = drv.find_elements(By.CSS_SELECTOR, "video.magnified")
    check(len(videos) == count, f"{what}: {len(videos)} magnified videos, {count} modes")
    drv.set_script_timeout(30)
    for v in videos:
        got = drv.execute_async_script(VIDEO_FRAMES_JS, v.get_attribute("id"))
        ok = "error" not in got and got["w"] > 0 and got["diff"] >= 20 and got["duration"] > 1
        check(ok, f"{what}: {v.get_attribute('id')} loads and moves ({got})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--harness", default="target/debug/host-harness")
    ap.add_argument("--work", default="target/pages")
    ap.add_argument("--screenshots", default=None,
                    help="also save screenshots of the analyze report and the picker here")
    args = ap.parse_args()
    h = str(Path(args.harness).resolve())
    work = Path(args.work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    rec = work / "rec"
    run(h, "render", "--preset", "cantilever", "--recording", rec, "--targets", "5",
        "--exposure-ms", "2", "--force")
    run(h, "track", "--frames", rec / "frames", "--fps", "120", "--points", rec / "points.csv",
        "--threshold", "127", "--out", work / "track", "--force")
    run(h, "analyze", "--frames", rec / "frames", "--fps", "120", "--threshold", "127",
        "--mm-per-px", "0.1266", "--targets", "5", "--out", work / "analyze", "--force")
    modal = ["modal", "--displacement", work / "analyze" / "displacement.csv"]
    run(h, *modal, "--out", work / "modal", "--force")
    run(h, "analyze", "--frames", rec / "frames", "--fps", "120", "--accel", rec / "accel.csv",
        "--fs", "2048", "--time-col", "t_s", "--threshold", "127", "--mm-per-px", "0.1266",
        "--exposure-ms", "2", "--targets", "5", "--window", "rect", "--out", work / "accel5",
        "--force")
    run(h, "analyze", "--frames", rec / "frames", "--fps", "120", "--accel", rec / "accel.csv",
        "--fs", "2048", "--time-col", "t_s", "--threshold", "127", "--mm-per-px", "0.1266",
        "--exposure-ms", "2", "--window", "rect", "--out", work / "accel1", "--force")
    # sixteen windows 8 px apart: their numbers cannot all stand beside them
    crowded = work / "crowded.csv"
    crowded.write_text("target,x,y,w,h\n" + "".join(
        f"{k + 1},{12 + 8 * k},35,9,9\n" for k in range(16)))
    run(h, "track", "--frames", rec / "frames", "--fps", "120", "--points", crowded,
        "--tracker", "lk", "--out", work / "track-crowded", "--force")
    occluded_frames = occluded(rec, work, 1, set(range(300, 330)))
    run(h, "track", "--frames", occluded_frames, "--fps", "120", "--points", rec / "points.csv",
        "--tracker", "lk", "--out", work / "track-occluded", "--force")
    shaken = work / "shaken"
    run(h, "simulate-field", "--render", "--minutes", "0.5", "--references", "4",
        "--shake-px", "0.5", "--roll-deg", "0.2", "--out", shaken, "--force")
    run(h, "analyze", "--frames", shaken / "frames", "--fps", "60", "--points",
        shaken / "points.csv", "--threshold", "127", "--tracker", "weighted", "--reference",
        shaken / "references.csv", "--out", work / "reference", "--force")
    run(h, "simulate-hammer", "--out", work / "hammer", "--force")
    ema = ["ema", "--response", work / "hammer" / "camera.csv", "--excitation",
           work / "hammer" / "force.csv", "--excitation-col", "force_n", "--impact",
           "--f-max-hz", "200"]
    run(h, *ema, "--out", work / "ema", "--force")
    # a geometry with a branch (not the number order): five nodes in mm, five lines
    geometry = work / "geometry.csv"
    geometry.write_text("node,x_mm,y_mm\n1,0,0\n2,100,0\n3,200,0\n4,300,0\n5,200,150\n"
                        "from,to\n1,2\n2,3\n3,4\n3,5\n5,1\n")
    run(h, *modal, "--geometry", geometry, "--out", work / "modal-geometry", "--force")
    # a full field: hundreds of points on a speckled beam, each mode magnified into a video
    beam = work / "beam"
    run(h, "simulate-field", "--render", "--scene", "speckle", "--minutes", "0.134", "--fps",
        "50", "--exposure-ms", "1", "--out", beam, "--force")
    run(h, "pick", "--frames", beam / "frames", "--region",
        (beam / "region.txt").read_text().strip(), "--spacing", "3", "--window-px", "11", "--direction", "y", "--points-out",
        work / "beam-points.csv", "--out", work / "beam-pick.html", "--force")
    run(h, "analyze", "--frames", beam / "frames", "--fps", "50", "--points",
        work / "beam-points.csv",
        "--tracker", "lk", "--out", work / "beam-analysis", "--force")
    run(h, *ema, "--geometry", geometry, "--out", work / "ema-geometry", "--force")

    def mode_rows(d):
        with open(d / "modes.csv", newline="") as f:
            return len(list(csv.DictReader(f)))

    from selenium.webdriver.common.by import By

    drv = browser(work)
    try:
        check_report(drv, work / "track" / "report.html", 5, None, "track",
                     header=("track", [rec / "frames", rec / "points.csv"]))
        check_scrubber(drv, work / "track-occluded" / "report.html", 5, 1, set(range(300, 330)),
                       "track, scrubber")
        check_report(drv, work / "track-crowded" / "report.html", 16, None, "track, crowded")
        check_labels(drv, "track, crowded", at_least=6)
        check_report(drv, work / "analyze" / "report.html", 5, mode_rows(work / "analyze"),
                     "analyze", header=("analyze", [rec / "frames"]))
        check_report(drv, work / "modal" / "report.html", None, mode_rows(work / "modal"),
                     "modal", header=("modal", [work / "analyze" / "displacement.csv"]))
        check_svd_range(drv, work / "modal", "modal")
        check_report(drv, work / "ema" / "report.html", None, mode_rows(work / "ema"), "ema",
                     header=("ema", [work / "hammer" / "camera.csv",
                                     work / "hammer" / "force.csv"]))
        check_wire(drv, work / "modal-geometry" / "report.html", geometry, "modal --geometry")
        check_wire(drv, work / "ema-geometry" / "report.html", geometry, "ema --geometry")
        check_report(drv, work / "ema-geometry" / "report.html", None,
                     mode_rows(work / "ema-geometry"), "ema --geometry",
                     header=("ema", [work / "hammer" / "camera.csv",
                                     work / "hammer" / "force.csv", geometry]))
        check_print(drv, work / "modal" / "report.html", "modal, printed")
        # `--pdf`: the command prints its own page through headless Chromium
        run(h, *modal, "--pdf", "--out", work / "modal-pdf", "--force")
        pdf = (work / "modal-pdf" / "report.pdf").read_bytes()
        open_page(drv, work / "modal-pdf" / "report.html")
        sections = len(drv.find_elements(By.CSS_SELECTOR, "h2"))
        pages = len(re.findall(rb"/Type\s*/Page[^s]", pdf))
        check(pdf.startswith(b"%PDF") and pages >= sections >= 2,
              f"modal --pdf: report.pdf of {pages} pages for {sections} sections")
        check_print(drv, work / "ema" / "report.html", "ema, printed")
        check_pole_picker(drv, h, work, "ema", ema)
        check_pole_picker(drv, h, work, "modal", modal, method="ssi")
        # with the accelerometer: one shape per band over the five targets, a row per target
        # and mode; one target: its marker and the modes of both systems, no shapes
        check_report(drv, work / "accel5" / "report.html", 5, 2, "analyze --targets --accel",
                     rows=mode_rows(work / "accel5"),
                     header=("analyze", [rec / "frames", rec / "accel.csv"]))
        check_report(drv, work / "accel1" / "report.html", 1, 0, "analyze --accel",
                     rows=mode_rows(work / "accel1"))
        # the camera's motion: the references on the frame, its spectrum among the figures
        check_report(drv, work / "reference" / "report.html", 5,
                     mode_rows(work / "reference"), "analyze --reference")
        n = len(drv.find_elements(By.CSS_SELECTOR, "svg#frame g.reference"))
        check(n == 4, f"analyze --reference: {n} references drawn, 4 given")
        check("camera_motion" in drv.page_source, "analyze --reference: the camera's spectrum")
        check_pick(drv, h, work, rec)
        ssi = sum(1 for r in csv.DictReader(open(work / "beam-analysis" / "modes.csv"))
                  if r["method"] == "ssi")
        check_videos(drv, work / "beam-analysis" / "report.html", ssi, "analyze, a full field")
        if args.screenshots:
            shots = Path(args.screenshots)
            shots.mkdir(parents=True, exist_ok=True)
            open_page(drv, work / "analyze" / "report.html")
            drv.save_screenshot(str(shots / "report.png"))
            open_page(drv, work / "pick.html")
            drv.save_screenshot(str(shots / "pick.png"))
    finally:
        drv.quit()
    print(f"{len(failures)} failed" if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
