#!/usr/bin/env python3
"""The Python binding's cost per frame on the CUDA backend, against the C++ APIs.

    PYTHONPATH=build/python python3 python/bench_gpu.py [--build build] [--runs 100]
        [--preset realtime] [--calib camchain.yaml left.png right.png] [--array cupy|torch]

Runs, on the same pair and settings (default: the T265 robot pair if ../shared/data has
it, else an 800x800 pair rendered by `curvestereo synth`):

  C++  curvestereo_cuda_bench   device API: pinned pair up, solve (graph replay), depth down
  C++  curvestereo bench        host API (Stereo::compute), depth only
  Py   device in, device out    CuPy/PyTorch pair on the GPU -> compute(return_device=True)
  Py   host in, device out      NumPy pair -> compute(..., return_device=True) via DeviceStereo
  Py   host API                 NumPy pair -> compute() through cs::Stereo (outputs=[])

and prints the medians and the binding's overhead per frame (Python minus the matching
C++ number) as a Markdown table for docs/accuracy.md. Every Python frame returns synchronised
(compute() waits for its results), as the C++ benches do.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

# Python puts this script's folder first on sys.path, and it holds the package's sources
# (python/curvestereo) without the compiled module: import the built one instead.
sys.path = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]
import curvestereo as cs  # noqa: E402

REPO = Path(__file__).resolve().parents[1]


def median_ms(fn, runs, warmup=5):
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(1000 * (time.perf_counter() - t0))
    return statistics.median(times), min(times), max(times)


def run(cmd):
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"{cmd[0]} failed:\n{proc.stdout}\n{proc.stderr}")
    return proc.stdout


def cpp_numbers(build, calib, left, right, preset, runs):
    out = {}
    bench = build / "backend_cuda" / "curvestereo_cuda_bench"
    if bench.exists():
        text = run([bench, "--calib", calib, left, right, "--preset", preset, "--runs", runs])
        out["cpp_device_frame"] = float(re.search(r"frame:\s+median ([\d.]+) ms", text).group(1))
        out["cpp_device_solve"] = float(re.search(r"solve:\s+median ([\d.]+) ms", text).group(1))
    else:
        print(f"note: {bench} not built; no device-API numbers")
    cli = build / "tools" / "curvestereo"
    text = run([cli, "bench", "--calib", calib, left, right, "--preset", preset, "--runs", runs, "--backend", "cuda"])
    out["cpp_host_frame"] = float(re.search(r"frame:\s+median ([\d.]+) ms", text).group(1))
    return out


def gpu_arrays(kind, left, right):
    """The pair as float32 GPU arrays of `kind`, and a synchronise function."""
    if kind == "cupy":
        import cupy

        return cupy.asarray(left), cupy.asarray(right), cupy.cuda.runtime.deviceSynchronize
    import torch

    return torch.from_numpy(left).cuda(), torch.from_numpy(right).cuda(), torch.cuda.synchronize


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", type=Path, default=REPO / "build")
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--preset", default="realtime")
    ap.add_argument("--calib", nargs=3, metavar=("CAMCHAIN", "LEFT", "RIGHT"))
    ap.add_argument("--array", choices=["cupy", "torch"], default=None)
    args = ap.parse_args()

    if "cuda" not in cs.available_backends(usable=True):
        sys.exit("no usable CUDA backend (build with nvcc, run on a machine with an NVIDIA GPU)")
    tmp = tempfile.TemporaryDirectory()
    if args.calib:
        calib, left_path, right_path = args.calib
    else:
        t265 = Path(os.environ.get("CURVESTEREO_SHARED_DATA", REPO.parent / "shared" / "data")) / "t265" / "robot"
        if (t265 / "camchain.yaml").exists():
            calib, left_path, right_path = t265 / "camchain.yaml", t265 / "left.png", t265 / "right.png"
        else:
            run([args.build / "tools" / "curvestereo", "synth", "-o", tmp.name, "--size", 800])
            calib, left_path, right_path = (Path(tmp.name) / n for n in ("camchain.yaml", "left.png", "right.png"))
    kind = args.array
    if kind is None:
        try:
            import cupy  # noqa: F401

            kind = "cupy"
        except ImportError:
            kind = "torch"

    rig = cs.load_calibration(str(calib))
    left, right = cs.read_image(str(left_path)), cs.read_image(str(right_path))
    print(f"input:  {calib} ({rig.width}x{rig.height}), preset {args.preset}, {args.runs} runs, arrays: {kind}")

    py = {}
    # The device path with only depth + valid out, like the C++ benches (depth only).
    dev = cs.Stereo(rig, args.preset, "cuda", outputs=[])
    print(f"device: {dev.device}")
    gl, gr, sync = gpu_arrays(kind, left, right)
    py["py_device"] = median_ms(lambda: dev.compute(gl, gr, return_device=True), args.runs)
    # NumPy in with return_device=True is what reaches DeviceStereo with host inputs (NumPy in
    # and out goes through cs::Stereo, the last row).
    py["py_host_via_device"] = median_ms(lambda: dev.compute(left, right, return_device=True), args.runs)
    # All outputs left on the GPU (what a PyTorch pipeline would take).
    full = cs.Stereo(rig, args.preset, "cuda")
    py["py_device_all_outputs"] = median_ms(lambda: full.compute(gl, gr, return_device=True), args.runs)
    py["py_host_api"] = median_ms(lambda: dev.compute(left, right), args.runs)
    sync()

    cpp = cpp_numbers(args.build, calib, left_path, right_path, args.preset, args.runs)

    def row(label, key, ref_key, ref_label):
        m, lo, hi = py[key]
        ref = cpp.get(ref_key)
        over = f"{m - ref:+.3f} ms vs {ref_label} {ref:.3f}" if ref is not None else "n/a"
        print(f"| {label} | {m:.3f} ({lo:.3f}..{hi:.3f}) | {over} |")

    print()
    for k, v in cpp.items():
        print(f"{k}: {v:.3f} ms")
    print("\n| Python path (median ms, min..max) | per frame | binding overhead |\n|---|---|---|")
    row("GPU arrays in, GPU arrays out (depth, valid)", "py_device", "cpp_device_solve", "C++ device API solve")
    row("GPU arrays in, all outputs on the GPU", "py_device_all_outputs", "cpp_device_solve", "C++ device API solve")
    row("NumPy in, GPU arrays out (device path)", "py_host_via_device", "cpp_device_frame", "C++ device API frame")
    row("NumPy in/out through cs::Stereo", "py_host_api", "cpp_host_frame", "C++ Stereo::compute")


if __name__ == "__main__":
    main()
