#!/usr/bin/env python3
"""Writes the hand-made part of the seed corpus (tests/fuzz/corpus/): small PNGs of every
colour type / bit depth / interlace, .flo files, camchains of every camera model, Basalt
calibration.json files of every camera_type and OpenCV stereo FileStorage files (YAML, XML).
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

# Basalt calibration.json and OpenCV FileStorage seeds (the basalt, opencv and calib targets):
# every Basalt camera_type, both OpenCV models in YAML and XML. Camera 1 sits 6.4 cm to
# the right, turned 0.02 rad about y (the camchain seeds' pose, as a pose in camera 0's frame).
half = 0.01  # half the turn: quaternion (0, sin, 0, cos) of 0.02 rad
QY, QW = math.sin(half), math.cos(half)
basalt_types = {
    "kb4": "\"fx\": 280.0, \"fy\": 281.0, \"cx\": 320.5, \"cy\": 239.5, \"k1\": 0.01, \"k2\": -0.002, \"k3\": 0.0003, \"k4\": -0.0001",
    "ds": "\"fx\": 300.0, \"fy\": 300.0, \"cx\": 320.0, \"cy\": 240.0, \"xi\": -0.2, \"alpha\": 0.59",
    "eucm": "\"fx\": 380.0, \"fy\": 380.0, \"cx\": 320.0, \"cy\": 240.0, \"alpha\": 0.62, \"beta\": 1.1",
    "ucm": "\"fx\": 370.0, \"fy\": 370.0, \"cx\": 320.0, \"cy\": 240.0, \"alpha\": 0.47",
    "pinhole": "\"fx\": 458.6, \"fy\": 457.3, \"cx\": 319.5, \"cy\": 239.5",
    "pinhole-radtan8": "\"fx\": 458.6, \"fy\": 457.3, \"cx\": 319.5, \"cy\": 239.5, \"k1\": -0.28, \"k2\": 0.07, "
                       "\"p1\": 0.0002, \"p2\": -0.0001, \"k3\": 0.0, \"k4\": 0.0, \"k5\": 0.0, \"k6\": 0.0, \"rpmax\": 1.5",
}
def basalt(params):
    pose0 = '{"px": 0.0, "py": 0.0, "pz": 0.0, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0}'
    pose1 = f'{{"px": 0.064, "py": 0.0, "pz": 0.0, "qx": 0.0, "qy": {QY!r}, "qz": 0.0, "qw": {QW!r}}}'
    cam = f'{{"camera_type": "{params[0]}", "intrinsics": {{{params[1]}}}}}'
    return (f'{{\n    "value0": {{\n        "T_imu_cam": [{pose0}, {pose1}],\n'
            f'        "intrinsics": [{cam}, {cam}],\n        "resolution": [[640, 480], [640, 480]],\n'
            f'        "cam_time_offset_ns": 0\n    }}\n}}\n')
for key, params in basalt_types.items():
    out("basalt", f"{key}.json", basalt((key, params)).encode())

opencv_models = {
    "fisheye": ("fisheye", 4, 1, "[ 0.01, -0.002, 0.0003, -0.0001 ]"),
    "plumb_bob": ("plumb_bob", 1, 5, "[ -0.28, 0.07, 0.0002, -0.0001, 0. ]"),
}
R = [c, 0.0, s_, 0.0, 1.0, 0.0, -s_, 0.0, c]
def cv_yaml(model, rows, cols, d):
    m = lambda name, r, k, data: (f"{name}: !!opencv-matrix\n   rows: {r}\n   cols: {k}\n   dt: d\n"
                                  f"   data: {data}\n")
    K = "[ 458.6, 0., 319.5, 0., 457.3, 239.5, 0., 0., 1. ]"
    return ("%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n" + f"distortion_model: {model}\n" +
            m("K1", 3, 3, K) + m("D1", rows, cols, d) + m("K2", 3, 3, K) + m("D2", rows, cols, d) +
            m("R", 3, 3, "[ " + ", ".join(repr(v) for v in R) + " ]") + m("T", 3, 1, "[ -0.064, 0.0001, 0.0002 ]"))
def cv_xml(model, rows, cols, d):
    m = lambda name, r, k, data: (f'<{name} type_id="opencv-matrix">\n  <rows>{r}</rows>\n  <cols>{k}</cols>\n'
                                  f'  <dt>d</dt>\n  <data>\n    {data}</data></{name}>\n')
    K = "458.6 0. 319.5 0. 457.3 239.5 0. 0. 1."
    d = d.strip("[] ").replace(",", "")
    return ('<?xml version="1.0"?>\n<opencv_storage>\n<image_width>640</image_width>\n'
            f'<image_height>480</image_height>\n<distortion_model>{model}</distortion_model>\n' +
            m("M1", 3, 3, K) + m("D1", rows, cols, d) + m("M2", 3, 3, K) + m("D2", rows, cols, d) +
            m("R", 3, 3, " ".join(repr(v) for v in R)) + m("T", 3, 1, "-0.064 0.0001 0.0002") + "</opencv_storage>\n")
for key, (model, rows, cols, d) in opencv_models.items():
    out("opencv", f"{key}.yaml", cv_yaml(model, rows, cols, d).encode())
    out("opencv", f"{key}.xml", cv_xml(model, rows, cols, d).encode())

# The calib target (format detection in front): one file of each format.
out("calib", "kalibr_kb4.yaml", (cam("cam0", *models["kb4"]) + cam("cam1", *models["kb4"], pose=True)).encode())
out("calib", "basalt_ds.json", basalt(("ds", basalt_types["ds"])).encode())
out("calib", "opencv_fisheye.yaml", cv_yaml(*opencv_models["fisheye"]).encode())
out("calib", "opencv_plumb_bob.xml", cv_xml(*opencv_models["plumb_bob"]).encode())

# The camera_rig target: rigs of N cameras. Cameras k = 0..N-1 yawed by k * 360/N degrees on a
# ring of radius 8 cm (x right, y down, z forward), with equidistant lenses of `fov` degrees
# whose image circle fills a 400 x 400 image; Kalibr chains (T_cn_cnm1 of camK maps camK-1 to
# camK) and a Basalt file (T_imu_cam of every camera).
def ring_pose(k, n):
    a = 2 * math.pi * k / n
    R = [[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0], [-math.sin(a), 0.0, math.cos(a)]]  # camera to body
    p = [0.08 * math.sin(a), 0.0, 0.08 * math.cos(a)]
    return R, p
def relative(k, n):  # T_cn_cnm1 = inv(T_body_camK) T_body_camK-1
    Rb, pb = ring_pose(k, n)
    Ra, pa = ring_pose(k - 1, n)
    Rt = [[Rb[c][r] for c in range(3)] for r in range(3)]
    R = [[sum(Rt[r][m] * Ra[m][c] for m in range(3)) for c in range(3)] for r in range(3)]
    t = [sum(Rt[r][m] * (pa[m] - pb[m]) for m in range(3)) for r in range(3)]
    return R, t
def ring_camera(k, n, fov):
    f = 200.0 / math.radians(fov / 2)
    s = f"cam{k}:\n"
    if k > 0:
        R, t = relative(k, n)
        s += "  T_cn_cnm1:\n" + "".join(f"  - [{R[r][0]!r}, {R[r][1]!r}, {R[r][2]!r}, {t[r]!r}]\n" for r in range(3))
        s += "  - [0.0, 0.0, 0.0, 1.0]\n"
    s += ("  camera_model: pinhole\n  distortion_coeffs: [0.0, 0.0, 0.0, 0.0]\n  distortion_model: equidistant\n"
          f"  intrinsics: [{f!r}, {f!r}, 199.5, 199.5]\n  resolution: [400, 400]\n")
    return s
out("camera_rig", "ring4_200deg.yaml", "".join(ring_camera(k, 4, 200.0) for k in range(4)).encode())
out("camera_rig", "back_to_back_220deg.yaml", "".join(ring_camera(k, 2, 220.0) for k in range(2)).encode())
def rig_basalt(n, fov):
    f = 200.0 / math.radians(fov / 2)
    poses, cams = [], []
    for k in range(n):
        a = 2 * math.pi * k / n
        _, p = ring_pose(k, n)
        poses.append(f'{{"px": {p[0]!r}, "py": 0.0, "pz": {p[2]!r}, "qx": 0.0, "qy": {math.sin(a / 2)!r}, '
                     f'"qz": 0.0, "qw": {math.cos(a / 2)!r}}}')
        cams.append(f'{{"camera_type": "kb4", "intrinsics": {{"fx": {f!r}, "fy": {f!r}, "cx": 199.5, "cy": 199.5, '
                    '"k1": 0.0, "k2": 0.0, "k3": 0.0, "k4": 0.0}}')
    return (f'{{\n    "value0": {{\n        "T_imu_cam": [{", ".join(poses)}],\n'
            f'        "intrinsics": [{", ".join(cams)}],\n'
            f'        "resolution": [{", ".join(["[400, 400]"] * n)}]\n    }}\n}}\n')
out("camera_rig", "ring3_basalt.json", rig_basalt(3, 200.0).encode())
