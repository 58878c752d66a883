"""Checks host-harness's frame decoding against independent readers, pixel for pixel.

- Photron: the sample recordings shipped in the pyMRAW source package (a 16-bit .cih, a 16-bit
  .cihx, a 12-bit packed Bayer .cihx), and 8-, 12- and 16-bit recordings written here (8 and
  16 by pyMRAW's own save_mraw, 12-bit packed by this script), read by pyMRAW.load_video and
  by host-harness (examples/frame_dump.rs): every pixel equal.
- Phantom cine: 8-, 16-bit and packed 10-bit files written here with pycine's own header
  structures (ctypes), read by host-harness: 8/16-bit upright as written and as pycine reads
  16-bit frames; packed 10-bit equal to pycine's unpacked codes through pycine's linLUT. A
  second reader, cine-handler (cine_reader): the packed 10-bit values equal its table's, and
  8/16-bit frames equal its rows (which it returns as stored) turned upright as the bitmap
  header's positive height says. The real camera file in pycine's source package
  (testfiles/chart1.cine, a packed 10-bit colour sensor's mosaic, 2048 x 1080) when its
  directory is given: equal to cine-handler's frame and to pycine's codes through linLUT.
- JPEG and colour PNG/TIFF: frames written by PIL (a colour scene with noise; baseline and
  progressive JPEG), host-harness's grey against PIL's convert("L"): within 1 grey level.

usage: python scripts/check_frames.py FRAME_DUMP_BINARY PYMRAW_DATA_DIR WORKDIR [PYCINE_TESTFILES]
"""
import os
import subprocess
import sys

import ctypes
import struct

import numpy as np
import pyMRAW
from PIL import Image
from pycine import cine
from pycine.file import read_header as cine_header
from pycine.linLUT import linLUT
from pycine.raw import create_raw_array, unpack_10bit
from cine_reader import Cine

dump, data_dir, work = sys.argv[1], sys.argv[2], sys.argv[3]
pycine_files = sys.argv[4] if len(sys.argv) > 4 else None
os.makedirs(work, exist_ok=True)
failures = []


def ours(path):
    out = os.path.join(work, "dump.bin")
    line = subprocess.run([dump, path, out], check=True, capture_output=True, text=True).stdout
    w, h, bits, n = map(int, line.split())
    dtype = np.uint8 if bits == 8 else np.dtype("<u2")
    return np.fromfile(out, dtype=dtype).reshape(n, h, w)


def compare(name, got, want, tol=0):
    want = np.asarray(want)
    if got.shape != want.shape:
        failures.append(f"{name}: shape {got.shape} != {want.shape}")
        return
    d = np.abs(got.astype(np.int64) - want.astype(np.int64))
    if d.max() > tol:
        failures.append(f"{name}: {int((d > tol).sum())} pixels differ by more than {tol} "
                        f"(max {int(d.max())})")
    print(f"{name}: {got.shape[0]} frame(s) {got.shape[2]}x{got.shape[1]}, max difference "
          f"{int(d.max())} (allowed {tol})")


# Photron: pyMRAW's sample files
for f in ["sample_60k_16bit.cih", "beam.cihx", "ball_12bit.cihx"]:
    p = os.path.join(data_dir, f)
    images, cih = pyMRAW.load_video(p)
    compare(f"pyMRAW sample {f}", ours(p), images)

# Photron: recordings written here, 8 and 16 bit by pyMRAW, 12-bit packed by this script
rng = np.random.default_rng(7)
for bits in [8, 16]:
    top = 255 if bits == 8 else 4095
    seq = rng.integers(0, top + 1, size=(5, 24, 40)).astype(np.uint16)
    _, cih = pyMRAW.save_mraw(seq, os.path.join(work, f"w{bits}.cih"), bit_depth=bits)
    images, _ = pyMRAW.load_video(cih)
    compare(f"save_mraw {bits}-bit", ours(cih), images)
seq = rng.integers(0, 4096, size=(3, 10, 16)).astype(np.uint16)
flat = seq.reshape(-1, 2)
packed = np.stack([flat[:, 0] >> 4, ((flat[:, 0] & 15) << 4) | (flat[:, 1] >> 8),
                   flat[:, 1] & 255], axis=1).astype(np.uint8)
base = os.path.join(work, "w12")
packed.tofile(base + ".mraw")
with open(base + ".cih", "w") as fh:
    fh.write("#Camera Information Header\nRecord Rate(fps) : 1000\nShutter Speed(s) : 1/2000\n"
             "Total Frame : 3\nImage Width : 16\nImage Height : 10\nColor Type : Mono\n"
             "Color Bit : 12\nFile Format : MRaw\nEffectiveBit Depth : 12\n"
             "EffectiveBit Side : Lower\n\n")
images, _ = pyMRAW.load_video(base + ".cih")
compare("12-bit packed (written here)", ours(base + ".cih"), images)
compare("12-bit packed against the values written", ours(base + ".cih"), seq)

# Phantom cine files written with pycine's structures
def write_cine(path, frames, bits, compression, fps=2000, shutter_ns=250000):
    n, h, w = frames.shape
    if compression == 256:
        images = []
        for f in frames:
            c = f.reshape(-1, 4).astype(np.uint64)
            word = (c[:, 0] << 30) | (c[:, 1] << 20) | (c[:, 2] << 10) | c[:, 3]
            b = np.stack([(word >> s) & 255 for s in (32, 24, 16, 8, 0)], axis=1)
            images.append(b.astype(np.uint8).tobytes())
        real = 10  # as Phantom's own packed files state the sensor (chart1.cine: 10)
    else:
        dt = np.uint8 if bits == 8 else np.dtype("<u2")
        images = [np.flipud(f).astype(dt).tobytes() for f in frames]
        real = 8 if bits == 8 else 12
    setup = cine.SETUP()
    setup.Length = ctypes.sizeof(setup)
    setup.FrameRate, setup.ShutterNs, setup.RealBPP = fps, shutter_ns, real
    setup.BlackLevel, setup.WhiteLevel = 0, 2 ** real - 1
    fh = cine.CINEFILEHEADER()
    fh.Type, fh.Headersize, fh.Version = 0x4943, 44, 1
    fh.ImageCount = fh.TotalImageCount = n
    fh.OffImageHeader, fh.OffSetup = 44, 84
    fh.OffImageOffsets = 84 + ctypes.sizeof(setup)
    bmi = cine.BITMAPINFOHEADER()
    bmi.biSize, bmi.biWidth, bmi.biHeight, bmi.biPlanes = 40, w, h, 1
    # packed frames state 16 bits per pixel, as the cameras write them (chart1.cine)
    stored_bits = 16 if compression == 256 else bits
    bmi.biBitCount, bmi.biCompression, bmi.biSizeImage = stored_bits, compression, len(images[0])
    with open(path, "wb") as f:
        f.write(bytes(fh))
        f.write(bytes(bmi))
        f.write(bytes(setup))
        first = fh.OffImageOffsets + 8 * n
        offsets = [first + k * (8 + len(images[0])) for k in range(n)]
        f.write(struct.pack(f"<{n}q", *offsets))
        for img in images:
            f.write(struct.pack("<II", 8, len(img)))
            f.write(img)


def cine_handler_frames(path):
    """Every frame as cine-handler decodes it (no dead-pixel repair, no debayering)."""
    c = Cine(path, keep_annotations=False)
    out = []
    for k in range(c.total_frames):
        c.load_frame(c.first_frame_number + k)
        out.append(np.array(c.pixel_array))
    c.close_file()
    return np.stack(out)


def pycine_images(path):
    """Each frame's stored bytes, found through pycine's header and image offsets."""
    h = cine_header(path)
    out = []
    with open(path, "rb") as f:
        for off in h["pImage"]:
            f.seek(off)
            ann = struct.unpack("<I", f.read(4))[0]
            f.seek(off + ann - 4)
            size = struct.unpack("<I", f.read(4))[0]
            out.append(f.read(size))
    return h, out


for bits, comp, top in [(8, 0, 256), (16, 0, 4096), (10, 256, 1024)]:
    seq = rng.integers(0, top, size=(4, 6, 12)).astype(np.uint16)
    p = os.path.join(work, f"p{bits}.cine")
    write_cine(p, seq, bits, comp)
    got = ours(p)
    h, images = pycine_images(p)
    w, hh = h["bitmapinfoheader"].biWidth, h["bitmapinfoheader"].biHeight
    handler = cine_handler_frames(p)
    if comp == 256:
        codes = np.stack([unpack_10bit(img, w, hh) for img in images])
        compare("cine packed 10-bit: pycine's codes before the table", seq, codes)
        compare("cine packed 10-bit vs pycine's codes through linLUT", got, linLUT[codes])
        compare("cine packed 10-bit vs cine-handler's table values", got, handler)
    else:
        if bits == 16:
            want = np.stack([create_raw_array(img, h) for img in images])
            compare("cine 16-bit vs pycine (upright)", got, want)
        else:
            compare("cine 8-bit, upright as written", got, seq)
        # cine-handler returns the rows as stored: bottom row first for a positive height
        assert hh > 0
        compare(f"cine {bits}-bit vs cine-handler's stored rows turned upright", got,
                handler[:, ::-1, :])

# A real camera file: pycine's test recording (its source package's testfiles/)
if pycine_files:
    p = os.path.join(pycine_files, "chart1.cine")
    got = ours(p)
    h, images = pycine_images(p)
    w, hh = h["bitmapinfoheader"].biWidth, h["bitmapinfoheader"].biHeight
    codes = np.stack([unpack_10bit(img, w, hh) for img in images])
    compare("pycine's chart1.cine (camera file, packed 10-bit) vs pycine's codes through linLUT",
            got, linLUT[codes])
    compare("pycine's chart1.cine vs cine-handler", got, cine_handler_frames(p))

# JPEG and colour images against PIL's luma
yy, xx = np.mgrid[0:60, 0:80]
scene = np.stack([(xx * 3) % 256, (yy * 4) % 256, (xx + yy) % 256], axis=2).astype(np.float64)
scene += rng.normal(0, 20, scene.shape)
scene = np.clip(scene, 0, 255).astype(np.uint8)
for name, kw in [("baseline.jpg", dict(quality=90)),
                 ("progressive.jpg", dict(quality=85, progressive=True)),
                 ("colour.png", {}), ("colour.tif", {})]:
    d = os.path.join(work, "img_" + name.replace(".", "_"))
    os.makedirs(d, exist_ok=True)
    p = os.path.join(d, "frame_0." + name.split(".")[1])
    Image.fromarray(scene).save(p, **kw)
    want = np.asarray(Image.open(p).convert("L"))[None]
    compare(f"{name} luma vs PIL convert('L')", ours(d), want, tol=1)
rgba = np.concatenate([scene, np.full(scene.shape[:2] + (1,), 128, np.uint8)], axis=2)
d = os.path.join(work, "img_rgba")
os.makedirs(d, exist_ok=True)
Image.fromarray(rgba, "RGBA").save(os.path.join(d, "frame_0.png"))
compare("RGBA PNG (alpha ignored) vs PIL", ours(d),
        np.asarray(Image.fromarray(scene).convert("L"))[None], tol=1)

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("all frame decoders agree")
