"""Threads: two Stereo objects in two threads give what they give one after the other;
compute() releases the GIL; one Stereo used by two threads at once is refused."""
import threading

import numpy as np
import pytest

import curvestereo as cs
from conftest import texture_pair


def test_two_threads_two_objects_match_sequential(small):
    calib, _, _ = small
    rig = cs.load_calibration(calib)
    pairs = [texture_pair(64, shift=1, seed=s) for s in (10, 11)]
    presets = ["realtime", "variational"]
    sequential = [cs.Stereo(rig, p, "cpu").compute(*pair) for p, pair in zip(presets, pairs)]

    results = [[None] * 3 for _ in range(2)]
    errors = []

    def work(k):
        try:
            stereo = cs.Stereo(rig, presets[k], "cpu")
            for i in range(3):
                results[k][i] = stereo.compute(*pairs[k])
        except Exception as e:  # reported by the main thread
            errors.append(e)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for k in range(2):
        for r in results[k]:
            for name in ("depth", "disparity", "points", "warp", "valid"):
                assert getattr(r, name).tobytes() == getattr(sequential[k], name).tobytes(), name


def test_compute_releases_the_gil(small):
    calib, left, right = small
    stereo = cs.Stereo(cs.load_calibration(calib), "variational", "cpu")  # ~60 ms a frame
    started, done = threading.Event(), threading.Event()
    count = 0

    def work():
        started.set()
        stereo.compute(left, right)
        done.set()

    t = threading.Thread(target=work)
    t.start()
    started.wait()
    while not done.is_set():  # runs only while compute() has let go of the GIL
        count += 1
    t.join()
    assert count > 1000


def test_one_object_two_threads_is_refused(tiny):
    calib, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    inside, release = threading.Event(), threading.Event()

    def hold(fraction):  # keeps the first compute() busy until the second has tried
        inside.set()
        release.wait(10)

    t = threading.Thread(target=lambda: stereo.compute(left, right, progress=hold))
    t.start()
    inside.wait(10)
    try:
        with pytest.raises(cs.Error, match="in use by another thread"):
            stereo.compute(left, right)
        with pytest.raises(cs.Error, match="in use"):
            stereo.set_mask(np.ones(left.shape, np.uint8))
    finally:
        release.set()
        t.join()
    stereo.compute(left, right)  # free again
