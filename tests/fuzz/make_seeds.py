#!/usr/bin/env python3
"""Writes the hand-made part of the seed corpus (tests/fuzz/corpus/): small PNGs of every
colour type / bit depth / interlace, .flo files, and camchains of every camera model.
The real camchains and three EXR seeds are copies of ../shared/data and tests/golden files;
the other EXR seeds come from make_exr_seeds.cpp."""
import os, struct, zlib

HERE = os.path.dirname(os.path.abspath(__file__))

def out(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)

def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xffffffff)

def png(w, h, depth, ctype, rows, interlace=0, extra=b""):
    ihdr = struct.pack(">IIBBBBB", w, h, depth, ctype, 0, 0, interlace)
    raw = b"".join(b"\x00" + r for r in rows)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + extra + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")

w, h = 4, 3
out("png", "gray8.png", png(w, h, 8, 0, [bytes((x * 60 + y * 20) % 256 for x in range(w)) for y in range(h)]))
out("png", "gray16.png", png(w, h, 16, 0, [b"".join(struct.pack(">H", x * 9000 + y * 500) for x in range(w)) for y in range(h)]))
out("png", "gray1.png", png(8, 2, 1, 0, [b"\xa5", b"\x5a"]))
out("png", "gray2.png", png(4, 2, 2, 0, [b"\x1b", b"\xe4"]))
out("png", "gray4.png", png(2, 2, 4, 0, [b"\x0f", b"\xf0"]))
out("png", "rgb8.png", png(w, h, 8, 2, [bytes((x * 50 + c * 70) % 256 for x in range(w) for c in range(3)) for y in range(h)]))
out("png", "rgba16.png", png(2, 2, 16, 6, [b"\x12\x34" * 8, b"\xff\xff" * 8]))
out("png", "graya8.png", png(w, h, 8, 4, [bytes((x * 30) % 256 for x in range(2 * w)) for y in range(h)]))
plte = chunk(b"PLTE", bytes([0, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0, 255]))
trns = chunk(b"tRNS", b"\x00\xff")
out("png", "palette.png", png(w, h, 8, 3, [bytes((x + y) % 4 for x in range(w)) for y in range(h)], extra=plte + trns))
out("png", "interlaced1x1.png", png(1, 1, 8, 0, [b"\x80"], interlace=1))

def flo(w, h, values):
    return b"PIEH" + struct.pack("<ii", w, h) + b"".join(struct.pack("<ff", u, v) for u, v in values)

out("flo", "small.flo", flo(3, 2, [(0.5, -1.0), (1e10, 1e10), (2.0, 3.0), (0.0, 0.0), (-7.5, 0.25), (float("nan"), 1.0)]))
out("flo", "one.flo", flo(1, 1, [(1.0, 2.0)]))
out("flo", "empty.flo", flo(0, 0, []))

import math
c, s_ = math.cos(0.02), math.sin(0.02)  # a small turn about y, written at full precision
POSE = f"""  T_cn_cnm1:
  - [{c!r}, 0.0, {s_!r}, -0.064]
  - [0.0, 1.0, 0.0, 0.0001]
  - [{-s_!r}, 0.0, {c!r}, 0.0002]
  - [0.0, 0.0, 0.0, 1.0]
"""
def cam(name, model, dist, coeffs, intr, pose=False):
    s = f"{name}:\n"
    if pose:
        s += POSE
    s += f"  camera_model: {model}\n  distortion_coeffs: {coeffs}\n  distortion_model: {dist}\n"
    s += f"  intrinsics: {intr}\n  resolution: [640, 480]\n"
    return s
models = {
    "kb4": ("pinhole", "equidistant", "[0.01, -0.002, 0.0003, -0.0001]", "[280.0, 281.0, 320.5, 239.5]"),
    "radtan": ("pinhole", "radtan", "[-0.28, 0.07, 0.0002, -0.0001]", "[458.6, 457.3, 319.5, 239.5]"),
    "pinhole_none": ("pinhole", "none", "[]", "[458.6, 457.3, 319.5, 239.5]"),
    "omni": ("omni", "none", "[]", "[0.9, 700.0, 700.0, 320.0, 240.0]"),
    "eucm": ("eucm", "none", "[]", "[0.62, 1.1, 380.0, 380.0, 320.0, 240.0]"),
    "ds": ("ds", "none", "[]", "[-0.2, 0.59, 300.0, 300.0, 320.0, 240.0]"),
}
for key, m in models.items():
    out("camchain", f"{key}.yaml", (cam("cam0", *m) + cam("cam1", *m, pose=True)).encode())
