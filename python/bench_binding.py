#!/usr/bin/env python3
"""What the binding itself costs per frame on the host (NumPy) path, on any machine (CPU
backend, no GPU needed).

    PYTHONPATH=build/python python3 python/bench_binding.py [--runs 200] [--calib camchain.yaml left.png right.png]

The solve is cut to almost nothing (one level, one warp, one iteration, no initialiser, no
median) so that the frame is dominated by what surrounds it, and for each input dtype
(float32 as read_image gives it, uint8 as a camera gives it) and each output selection it
prints the medians of:

  outside   compute()'s wall time minus Result.total_ms: converting the two input arrays,
            wrapping the results as NumPy arrays, and dropping the previous frame's result
            (the loop keeps one result alive while computing the next, as a real one does);
  library   Result.total_ms: Stereo::compute itself, which includes allocating (or, when
            the binding recycles them, reusing) the result images.

The binding's overhead is `outside` plus whatever `library` costs above the same solve into
a reused DepthResult (compare two builds of the binding on the same machine: the solve is
the same). Default input: the T265 robot pair (848x800) if ../shared/data has it, else a
random 848x800 pair.
"""
import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]
import curvestereo as cs  # noqa: E402

REPO = Path(__file__).resolve().parents[1]


def pair():
    t265 = Path(os.environ.get("CURVESTEREO_SHARED_DATA", REPO.parent / "shared" / "data")) / "t265" / "robot"
    if (t265 / "camchain.yaml").exists():
        return (cs.load_calibration(str(t265 / "camchain.yaml")), cs.read_image(str(t265 / "left.png")),
                cs.read_image(str(t265 / "right.png")))
    sys.path.insert(0, str(REPO / "python" / "tests"))
    from conftest import write_camchain  # noqa: E402

    d = tempfile.mkdtemp()
    rig = cs.load_calibration(write_camchain(Path(d) / "camchain.yaml", 800))
    rng = np.random.default_rng(0)
    return rig, rng.random((800, 800), dtype=np.float32), rng.random((800, 800), dtype=np.float32)


def measure(stereo, left, right, runs):
    outside, library = [], []
    r = stereo.compute(left, right)  # warm-up (first-touch allocations, caches)
    r = stereo.compute(left, right)
    for _ in range(runs):
        t0 = time.perf_counter()
        r = stereo.compute(left, right)  # the previous result is dropped here, as in a loop
        wall = 1000 * (time.perf_counter() - t0)
        outside.append(wall - r.total_ms)
        library.append(r.total_ms)
    return statistics.median(outside), statistics.median(library)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--calib", nargs=3, metavar=("CAMCHAIN", "LEFT", "RIGHT"))
    args = ap.parse_args()
    if args.calib:
        rig = cs.load_calibration(args.calib[0])
        left, right = cs.read_image(args.calib[1]), cs.read_image(args.calib[2])
    else:
        rig, left, right = pair()
    inputs = {
        "float32": (left, right),
        "uint8": tuple(np.round(a * 255).astype(np.uint8) for a in (left, right)),
        "uint8 BGR view": tuple(np.repeat(np.round(a * 255).astype(np.uint8)[..., None], 3, 2)[..., ::-1]
                                for a in (left, right)),
    }
    cheap = dict(levels=1, warps=1, iterations=1, init="none", median=False)
    print(f"{rig.width}x{rig.height}, CPU backend, solve cut to {cheap}, medians of {args.runs}")
    print("| input | outputs | outside compute (ms) | Stereo::compute (ms) |\n|---|---|---|---|")
    for outputs, label in ((None, "all"), ([], "depth + valid")):
        stereo = cs.Stereo(rig, "realtime", "cpu", outputs=outputs, profile=False, **cheap)
        for name, (l, r) in inputs.items():
            out, lib = measure(stereo, l, r, args.runs)
            print(f"| {name} | {label} | {out:.3f} | {lib:.3f} |")


if __name__ == "__main__":
    main()
