"""Shared fixtures: a tiny synthetic rig and pair (no files needed), and the CLI when the
tests run from a build tree (CURVESTEREO_CLI, set by ctest; else build*/tools/curvestereo)."""
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import curvestereo as cs

REPO = Path(__file__).resolve().parents[2]

# An ideal 180-degree equidistant pair, 12 cm apart: a copy of what `curvestereo synth
# --size N` writes, so the Python-only tests need no binary.
CAMCHAIN = """cam0:
  camera_model: pinhole
  distortion_coeffs: [0, 0, 0, 0]
  distortion_model: equidistant
  intrinsics: [{f}, {f}, {c}, {c}]
  resolution: [{n}, {n}]
cam1:
  T_cn_cnm1:
  - [1, 0, 0, -0.12]
  - [0, 1, 0, 0]
  - [0, 0, 1, 0]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: pinhole
  distortion_coeffs: [0, 0, 0, 0]
  distortion_model: equidistant
  intrinsics: [{f}, {f}, {c}, {c}]
  resolution: [{n}, {n}]
"""


def write_camchain(path, n):
    f = n / np.pi  # 180 degrees across the image
    Path(path).write_text(CAMCHAIN.format(f=f, c=0.5 * (n - 1), n=n))
    return str(path)


def texture_pair(n, shift=1, seed=0):
    """A smooth random texture and the same shifted left by `shift` px (uint8, n x n): a
    wall at one depth, seen by the rig below (camera 1 to the right of camera 0)."""
    rng = np.random.default_rng(seed)
    small = rng.random((n // 4 + 2, n // 4 + 2))
    big = np.kron(small, np.ones((4, 4)))[: n + shift, : n + shift]
    # Blur a little so the coarse-to-fine warping has gradients to follow.
    k = np.array([1, 4, 6, 4, 1], float) / 16
    big = np.apply_along_axis(lambda r: np.convolve(r, k, "same"), 1, big)
    big = np.apply_along_axis(lambda c: np.convolve(c, k, "same"), 0, big)
    left = big[:n, :n]
    right = big[:n, shift : n + shift]
    to8 = lambda a: np.clip(a * 255, 0, 255).astype(np.uint8)  # noqa: E731
    return to8(left), to8(right)


@pytest.fixture(scope="session")
def tiny(tmp_path_factory):
    """(rig path, left uint8, right uint8) at 32 x 32: one pyramid level, about 1 ms a frame."""
    d = tmp_path_factory.mktemp("tiny")
    left, right = texture_pair(32)
    return write_camchain(d / "camchain.yaml", 32), left, right


@pytest.fixture(scope="session")
def small(tmp_path_factory):
    """(rig path, left uint8, right uint8) at 64 x 64."""
    d = tmp_path_factory.mktemp("small")
    left, right = texture_pair(64, seed=1)
    return write_camchain(d / "camchain.yaml", 64), left, right


def find_cli():
    env = os.environ.get("CURVESTEREO_CLI")
    if env and Path(env).is_file():
        return env
    for build in sorted(REPO.glob("build*/tools/curvestereo")):
        if os.access(build, os.X_OK):
            return str(build)
    return shutil.which("curvestereo")


@pytest.fixture(scope="session")
def cli():
    path = find_cli()
    if not path:
        pytest.skip("the curvestereo command is not built (set CURVESTEREO_CLI)")
    return path


def run_cli(cli, *args):
    proc = subprocess.run([cli, *map(str, args)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return proc


@pytest.fixture(scope="session")
def synth_pair(cli, tmp_path_factory):
    """A pair rendered by `curvestereo synth` (real scene, ground truth), 96 x 96."""
    d = tmp_path_factory.mktemp("synth")
    run_cli(cli, "synth", "-o", d, "--size", 96)
    return d


def same_bits(a, b):
    """Arrays equal bit for bit (NaN payloads included)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    return a.tobytes() == b.tobytes()
