"""Reference counts and memory: nothing grows over 1,000 frames; arrays outlive their
Stereo; a result's arrays own their memory."""
import gc
import sys
import tracemalloc

import numpy as np

import curvestereo as cs


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


def test_no_growth_over_1000_frames(tiny):
    calib, left, right = tiny
    # The realtime preset cut to one warp and one iteration, 32 x 32: ~0.6 ms a frame
    # without its plane sweep, ~9 ms with it (every tenth frame: the confidence output).
    rig = cs.load_calibration(calib)
    fast = cs.Stereo(rig, "realtime", "cpu", warps=1, iterations=1, init="none")
    sweep = cs.Stereo(rig, "realtime", "cpu", warps=1, iterations=1, init="planesweep")
    progress = lambda f: None  # noqa: E731
    left_f = (left / 255.0).astype(np.float32)
    objects = (fast, sweep, left, right, left_f, progress)

    def frames(n):
        for i in range(n):
            stereo = sweep if i % 10 == 0 else fast
            r = stereo.compute(left if i % 2 else left_f, right, progress=progress if i % 3 == 0 else None)
            _ = (r.depth, r.points, r.valid, r.stages, r.warp, r.disparity, r.z, r.confidence)

    frames(50)  # warm-up: allocator pools, first-use caches
    gc.collect()
    refs = [sys.getrefcount(o) for o in objects]
    n_objects = len(gc.get_objects())
    rss = rss_bytes()
    tracemalloc.start()
    before = tracemalloc.take_snapshot()
    frames(1000)
    gc.collect()
    after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    grown = sum(s.size_diff for s in after.compare_to(before, "filename"))
    del before, after  # the snapshots are objects too
    gc.collect()
    assert [sys.getrefcount(o) for o in objects] == refs
    assert len(gc.get_objects()) <= n_objects + 10
    assert grown < 64 * 1024, f"Python allocations grew by {grown} bytes"
    # One frame's arrays are ~40 KB: a leak of them all would be ~40 MB.
    assert rss_bytes() - rss < 4 * 1024 * 1024


def test_errors_do_not_leak(tiny):
    calib, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    bad = np.full(left.shape, np.nan, np.float32)
    for _ in range(20):
        try:
            stereo.compute(bad, right)
        except cs.Error:
            pass
    gc.collect()
    refs = sys.getrefcount(bad), sys.getrefcount(right)
    for _ in range(500):
        for call in (lambda: stereo.compute(bad, right), lambda: stereo.compute(left[:3], right),
                     lambda: cs.Stereo(stereo.rig, "nonsense")):
            try:
                call()
            except cs.Error:
                pass
    gc.collect()
    assert (sys.getrefcount(bad), sys.getrefcount(right)) == refs


def test_arrays_outlive_their_stereo(tiny):
    calib, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    r = stereo.compute(left, right)
    depth, points = r.depth, r.points
    expected = depth.copy()
    del stereo, r
    gc.collect()
    _ = [np.ones(depth.shape, np.float32) for _ in range(100)]  # reuse freed memory, if any was freed
    assert depth.tobytes() == expected.tobytes()
    assert points.shape[-1] == 3 and points.flags.owndata is False and points.base is not None


def test_results_are_independent(tiny):
    calib, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    a = stereo.compute(left, right)
    keep = a.depth.copy()
    a.depth[:] = 0  # results are writable and the caller's
    b = stereo.compute(left, right)
    assert b.depth.tobytes() == keep.tobytes()


def test_results_stay_valid_after_later_frames(small):
    # The binding recycles the storage of dropped results: arrays still held must never be
    # written by a later frame, and recycled storage (an old frame's contents) must give the
    # same results as fresh storage.
    calib, left, right = small
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    other = (right[:, ::-1].copy(), left[:, ::-1].copy())
    names = ("depth", "valid", "z", "points", "disparity", "warp", "confidence")

    def snapshot(r):
        return {n: getattr(r, n).tobytes() for n in names if getattr(r, n) is not None}

    r1 = stereo.compute(left, right)
    first = snapshot(r1)
    kept_depth = r1.depth  # only one array of frame 1 kept, beyond r1 itself
    r2 = stereo.compute(*other)
    second = snapshot(r2)
    assert second != first
    assert snapshot(r1) == first
    float_ptrs = {getattr(r1, n).__array_interface__["data"][0] for n in ("z", "disparity", "confidence")}
    del r1
    gc.collect()
    used = set()
    for i in range(6):  # frame 1's other arrays are recycled into these
        r = stereo.compute(left, right) if i % 2 == 0 else stereo.compute(*other)
        assert snapshot(r) == (first if i % 2 == 0 else second)
        assert kept_depth.tobytes() == first["depth"]
        assert snapshot(r2) == second
        used |= {getattr(r, n).__array_interface__["data"][0] for n in ("depth", "z", "disparity", "confidence")}
    # Recycled, not freshly allocated: later frames took the storage r1's arrays gave back,
    # never the storage of the array still held.
    assert used & float_ptrs
    assert kept_depth.__array_interface__["data"][0] not in used


def test_results_outlive_recycling_stereo(small):
    calib, left, right = small
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    results = [stereo.compute(left, right) for _ in range(3)]
    expected = results[0].depth.tobytes()
    del results[1]
    del stereo  # the pool goes; arrays dropped later free their storage
    gc.collect()
    assert all(r.depth.tobytes() == expected for r in results)
    del results
    gc.collect()
