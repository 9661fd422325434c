"""python3 -m curvestereo.batch on a local CPU cluster: logs written by the project's own
writer (synth --sequence, log write), one corrupt; every good recording's depth log is
written whole, the corrupt one fails alone with its one-line error, and a rerun skips what
is done and redoes what a crash left half-written."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

import curvestereo as cs
from conftest import run_cli

pytest.importorskip("distributed", reason="Dask's distributed is not installed (apt-get install python3-distributed)")

TOPICS = "/cam0/image_raw,/cam1/image_raw"


@pytest.fixture(scope="module")
def logs(tmp_path_factory, cli):
    root = tmp_path_factory.mktemp("batch")
    run_cli(cli, "synth", "--sequence", "-o", root / "walk", "--frames", "3", "--size", "128", "--samples", "1",
            "--quiet")
    run_cli(cli, "log", "write", "--sequence", root / "walk", "-o", root / "a.mcap")
    (root / "b.mcap").write_bytes((root / "a.mcap").read_bytes())
    corrupt = bytearray((root / "a.mcap").read_bytes())
    corrupt[len(corrupt) // 2] ^= 0xFF  # inside a chunk: its CRC fails
    (root / "bad.mcap").write_bytes(bytes(corrupt))
    return root


def batch(root, cli, *extra):
    env = dict(os.environ, PYTHONPATH=str(Path(cs.__file__).parent.parent), CURVESTEREO_CLI=cli)
    command = [sys.executable, "-m", "curvestereo.batch", *extra, "-o", root / "out", "--calib",
               root / "walk" / "camchain.yaml", "--topics", TOPICS, "--workers", "2", "--", "--preset", "fast"]
    return subprocess.run(list(map(str, command)), capture_output=True, text=True, env=env, cwd=root, timeout=600)


def test_batch_writes_each_recording_and_a_corrupt_log_fails_alone(logs, cli):
    r = batch(logs, cli, logs / "a.mcap", logs / "bad.mcap", logs / "b.mcap")
    assert r.returncode == 1, r.stderr
    out = logs / "out"
    for name in ("a", "b"):
        info = cs.log_info(out / f"{name}.mcap")
        depth = [t for t in info["topics"] if t["name"] == "/curvestereo/depth"]
        assert depth and depth[0]["messages"] == 3 and info["cut"] == ""
    assert not (out / "bad.mcap").exists()
    assert sorted(p.name for p in out.iterdir()) == ["a.mcap", "b.mcap"]  # no temporary file left
    failed = [line for line in r.stdout.splitlines() if line.startswith("failed:")]
    assert len(failed) == 1 and "bad.mcap" in failed[0] and "bad CRC" in failed[0], r.stdout
    assert "2 recordings done, 0 skipped (already written), 1 failed; 6 frames in" in r.stdout
    assert "frames/s overall" in r.stdout
    assert "3/3" in r.stderr  # the progress bar reached the end

    # A rerun: the finished outputs are skipped untouched; a half-written one (a crash's
    # temporary file) does not count, and the corrupt log fails again.
    mtime = (out / "a.mcap").stat().st_mtime_ns
    (out / "b.mcap").unlink()
    (out / ".b.mcap.partial.mcap").write_bytes(b"half")
    r = batch(logs, cli, logs / "a.mcap", logs / "bad.mcap", logs / "b.mcap")
    assert r.returncode == 1, r.stderr
    assert "1 recordings done, 1 skipped (already written), 1 failed; 3 frames in" in r.stdout
    assert (out / "a.mcap").stat().st_mtime_ns == mtime
    assert cs.log_info(out / "b.mcap")["cut"] == ""
    assert sorted(p.name for p in out.iterdir()) == ["a.mcap", "b.mcap"]


def test_batch_refuses_bad_arguments_in_one_line(logs, cli):
    r = batch(logs, cli, logs / "missing.mcap")
    assert r.returncode == 2 and r.stderr.strip().endswith("missing.mcap does not exist")
    (logs / "twin").mkdir(exist_ok=True)
    (logs / "twin" / "a.mcap").write_bytes((logs / "a.mcap").read_bytes())
    r = batch(logs, cli, logs / "a.mcap", logs / "twin" / "a.mcap")
    assert r.returncode == 2 and "would both write a.mcap" in r.stderr


def test_batch_gives_each_gpu_worker_its_own_gpu(logs, cli, tmp_path):
    # --gpus 2 on a machine without GPUs: the command (a wrapper noting what it was given)
    # solves on the CPU; what is checked is that the two workers' tasks saw GPU 0 and GPU 1.
    seen = tmp_path / "seen.txt"
    wrapper = tmp_path / "curvestereo"
    wrapper.write_text(f'#!/bin/sh\necho "$CUDA_VISIBLE_DEVICES" >> {seen}\nexec {cli} "$@"\n')
    wrapper.chmod(0o755)
    env = dict(os.environ, PYTHONPATH=str(Path(cs.__file__).parent.parent))
    command = [sys.executable, "-m", "curvestereo.batch", logs / "a.mcap", logs / "b.mcap", "-o", tmp_path / "out",
               "--calib", logs / "walk" / "camchain.yaml", "--topics", TOPICS, "--gpus", "2", "--cli", wrapper,
               "--", "--preset", "fast", "--backend", "cpu"]
    r = subprocess.run(list(map(str, command)), capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "2 recordings done" in r.stdout
    assert sorted(seen.read_text().split()) == ["0", "1"]


def test_batch_cuts_recordings_into_parts_and_a_rerun_skips_the_parts_done(logs, cli, tmp_path):
    out = tmp_path / "parts"
    extra = ["--frames-per-task", "2"]

    def run():
        env = dict(os.environ, PYTHONPATH=str(Path(cs.__file__).parent.parent), CURVESTEREO_CLI=cli)
        command = [sys.executable, "-m", "curvestereo.batch", logs / "a.mcap", logs / "bad.mcap", "-o", out,
                   "--calib", logs / "walk" / "camchain.yaml", "--topics", TOPICS, "--workers", "2", *extra,
                   "--", "--preset", "fast"]
        return subprocess.run(list(map(str, command)), capture_output=True, text=True, env=env, timeout=600)

    r = run()
    assert r.returncode == 1, r.stderr
    assert sorted(p.name for p in out.iterdir()) == ["a.0-2.mcap", "a.2-3.mcap"]
    for name, frames in (("a.0-2.mcap", 2), ("a.2-3.mcap", 1)):
        depth = [t for t in cs.log_info(out / name)["topics"] if t["name"] == "/curvestereo/depth"]
        assert depth[0]["messages"] == frames
    assert "2 parts done, 0 skipped (already written), 1 failed; 3 frames in" in r.stdout
    assert "bad CRC" in r.stdout and "3/3" in r.stderr
    (out / "a.2-3.mcap").unlink()
    r = run()
    assert "1 parts done, 1 skipped (already written), 1 failed; 1 frames in" in r.stdout, r.stdout
