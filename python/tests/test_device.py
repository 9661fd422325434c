"""GPU arrays with the CUDA backend (CuPy, PyTorch): device inputs read in place, device
outputs wrapped without copies, results equal to the host path bit for bit. Every test
skips without a CUDA build, a CUDA device, or the array library it uses."""
import gc
import sys

import numpy as np
import pytest

import curvestereo as cs
from conftest import same_bits, texture_pair, write_camchain


def cuda_ready():
    return cs.build_info()["cuda_arrays"] and "cuda" in cs.available_backends(usable=True)


pytestmark = pytest.mark.skipif(not cuda_ready(), reason="no CUDA backend in this build or no CUDA device")

OUTPUTS = ("depth", "valid", "z", "points", "disparity", "warp", "confidence")


@pytest.fixture(scope="module")
def cp():
    return pytest.importorskip("cupy")


@pytest.fixture(scope="module")
def torch():
    torch = pytest.importorskip("torch")
    if not torch.cuda.is_available():
        pytest.skip("PyTorch has no CUDA")
    return torch


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """(rig, left uint8, right uint8) at 256 x 256: five pyramid levels on the GPU."""
    d = tmp_path_factory.mktemp("gpu")
    left, right = texture_pair(256, shift=3, seed=7)
    return cs.load_calibration(write_camchain(d / "camchain.yaml", 256)), left, right


@pytest.fixture(scope="module")
def stereo(pair):
    return cs.Stereo(pair[0], "realtime", "cuda")


def host(x):
    """A result field as NumPy, whatever it came as."""
    if x is None:
        return None
    return x.get() if isinstance(x, cs.DeviceArray) else np.asarray(x)


def assert_same(a, b):
    for name in OUTPUTS:
        x, y = host(getattr(a, name)), host(getattr(b, name))
        if x is None or y is None:
            assert x is None and y is None, name
            continue
        if not same_bits(x, y):
            diff = np.nanmax(np.abs(x.astype(np.float64) - y.astype(np.float64))) if x.shape == y.shape else "shape"
            pytest.fail(f"{name} differs (max |diff| {diff}, shapes {x.shape} {y.shape})")


def test_stereo_on_cuda(stereo, pair):
    assert stereo.backend == "cuda" and stereo.device
    r = stereo.compute(pair[1], pair[2])
    assert isinstance(r.depth, np.ndarray) and r.valid.mean() > 0.5


def test_cupy_inputs_equal_host_path(cp, stereo, pair):
    _, left, right = pair
    ref = stereo.compute(left, right)  # cs::Stereo on the CUDA backend
    for l, r in [
        (cp.asarray(left), cp.asarray(right)),  # uint8
        (cp.asarray(left / 255.0, dtype=cp.float32), cp.asarray(right / 255.0, dtype=cp.float32)),
        (cp.asarray(left.astype(np.uint16) * 257), cp.asarray(right.astype(np.uint16) * 257)),
    ]:
        assert_same(stereo.compute(l, r), ref)


def test_cupy_strides_and_colour(cp, stereo, pair):
    _, left, right = pair
    rgb = [np.stack([img, img // 3, 255 - img], axis=2) for img in (left, right)]
    ref = stereo.compute(*rgb)
    assert_same(stereo.compute(cp.asarray(rgb[0]), cp.asarray(rgb[1])), ref)
    # BGR reversed through a negative stride, and a crop out of a larger array.
    bgr = [cp.asarray(img[..., ::-1].copy()) for img in rgb]
    assert_same(stereo.compute(bgr[0][..., ::-1], bgr[1][..., ::-1]), ref)
    big = cp.zeros((300, 320), cp.uint8)
    big[10:266, 20:276] = cp.asarray(left)
    gray_ref = stereo.compute(left, right)
    assert_same(stereo.compute(big[10:266, 20:276], cp.asarray(right)), gray_ref)
    assert_same(stereo.compute(cp.asfortranarray(cp.asarray(left)), cp.asarray(right)), gray_ref)


def test_return_device_cupy_without_copy(cp, stereo, pair):
    _, left, right = pair
    ref = stereo.compute(left, right)
    r = stereo.compute(cp.asarray(left), cp.asarray(right), return_device=True)
    assert isinstance(r.depth, cs.DeviceArray) and r.depth.shape == left.shape
    assert r.valid.dtype == np.bool_ and r.points.shape == left.shape + (3,)
    assert_same(r, ref)
    d = cp.asarray(r.depth)  # __cuda_array_interface__: a view, not a copy
    assert d.data.ptr == r.depth.ptr and d.dtype == cp.float32
    assert same_bits(cp.asnumpy(d), ref.depth)
    v = cp.from_dlpack(r.valid)
    assert v.dtype == cp.bool_ and v.data.ptr == r.valid.ptr
    assert bool((v == cp.asarray(ref.valid)).all())
    # Host inputs may ask for device outputs too.
    assert_same(stereo.compute(left, right, return_device=True), ref)


def test_torch_in_and_out(torch, stereo, pair):
    _, left, right = pair
    ref = stereo.compute(left, right)
    tl = torch.from_numpy(left).cuda()
    tr = torch.from_numpy(right).cuda()
    r = stereo.compute(tl, tr, return_device=True)  # DLPack in
    assert_same(r, ref)
    t = torch.from_dlpack(r.depth)
    assert t.data_ptr() == r.depth.ptr and t.dtype == torch.float32 and t.is_cuda
    a = torch.as_tensor(r.points, device="cuda")  # __cuda_array_interface__
    assert a.data_ptr() == r.points.ptr and tuple(a.shape) == left.shape + (3,)
    assert same_bits(t.cpu().numpy(), ref.depth)
    # float32 tensors, and a column-major view.
    lf, rf = (img.astype(np.float32) / np.float32(255) for img in (left, right))
    col = torch.from_numpy(lf).cuda().t().contiguous().t()
    assert not col.is_contiguous()
    assert_same(stereo.compute(col, torch.from_numpy(rf).cuda()), stereo.compute(lf, rf))


def test_torch_side_stream_is_waited_for(torch, stereo, pair):
    """An input still being written on another stream is read only once it is ready."""
    _, left, right = pair
    ref = stereo.compute(left, right)
    src = torch.from_numpy(left).cuda()
    side = torch.cuda.Stream()
    with torch.cuda.stream(side):
        torch.cuda._sleep(50_000_000)  # keep the stream busy (~tens of ms) before the copy lands
        late = src.clone()
        r = stereo.compute(late, torch.from_numpy(right).cuda())
    assert_same(r, ref)


def test_device_results_outlive_stereo_and_result(cp, pair):
    _, left, right = pair
    stereo = cs.Stereo(pair[0], "realtime", "cuda")
    expected = stereo.compute(left, right).depth
    r = stereo.compute(cp.asarray(left), cp.asarray(right), return_device=True)
    view = cp.asarray(r.depth)
    tensor_like = r.disparity
    del r, stereo
    gc.collect()
    junk = [cp.ones((256, 256), cp.float32) for _ in range(64)]  # would reuse freed memory
    del junk
    assert same_bits(cp.asnumpy(view), expected)
    assert tensor_like.get().shape == left.shape


def test_no_growth_over_frames(cp, stereo, pair):
    _, left, right = pair
    l, r = cp.asarray(left), cp.asarray(right)

    def frames(n):
        for _ in range(n):
            res = stereo.compute(l, r, return_device=True)
            cp.asarray(res.depth).sum()

    frames(20)
    cp.get_default_memory_pool().free_all_blocks()
    cp.cuda.runtime.deviceSynchronize()
    gc.collect()
    free_before = cp.cuda.runtime.memGetInfo()[0]
    refs = sys.getrefcount(l), sys.getrefcount(r), sys.getrefcount(stereo)
    frames(500)
    cp.get_default_memory_pool().free_all_blocks()
    cp.cuda.runtime.deviceSynchronize()
    gc.collect()
    assert (sys.getrefcount(l), sys.getrefcount(r), sys.getrefcount(stereo)) == refs
    # cudaFreeAsync returns memory to the stream-ordered pool, which may keep some.
    assert free_before - cp.cuda.runtime.memGetInfo()[0] < 64 << 20


def test_device_errors(cp, stereo, pair):
    _, left, right = pair
    bad = cp.asarray(left / 255.0, dtype=cp.float32)
    bad[3, 4] = cp.nan
    with pytest.raises(cs.Error, match="left image contains NaN or infinite pixels"):
        stereo.compute(bad, cp.asarray(right))
    with pytest.raises(cs.Error, match="right image has dtype float64"):
        stereo.compute(cp.asarray(left), cp.asarray(right, dtype=cp.float64))
    with pytest.raises(cs.Error, match="left image is 255x256 but the calibration says 256x256"):
        stereo.compute(cp.asarray(left)[:, :255], cp.asarray(right))
    with pytest.raises(cs.Error, match="has shape"):
        stereo.compute(cp.asarray(left)[0], cp.asarray(right))
    # Still fine afterwards.
    assert_same(stereo.compute(cp.asarray(left), cp.asarray(right)), stereo.compute(left, right))


def test_pose_and_mask_reach_the_device_path(cp, pair):
    rig, left, right = pair
    stereo = cs.Stereo(rig, "realtime", "cuda")
    stereo.compute(cp.asarray(left), cp.asarray(right))  # device path set up
    stereo.set_pose(np.eye(3), [-0.2, 0.01, 0])
    mask = np.zeros(left.shape, np.uint8)
    mask[40:200, 30:220] = 1
    stereo.set_mask(mask)
    assert_same(stereo.compute(cp.asarray(left), cp.asarray(right)), stereo.compute(left, right))


def test_outputs_subset_on_device(cp, pair):
    rig, left, right = pair
    stereo = cs.Stereo(rig, "realtime", "cuda", outputs=[])
    r = stereo.compute(cp.asarray(left), cp.asarray(right), return_device=True)
    assert r.points is None and r.disparity is None and r.warp is None and r.z is None
    assert_same(r, stereo.compute(left, right))


def test_quality_confidence_on_device(cp, pair):
    rig, left, right = pair
    stereo = cs.Stereo(rig, "quality", "cuda", init_level=1)
    r = stereo.compute(cp.asarray(left), cp.asarray(right), return_device=True)
    assert isinstance(r.confidence, cs.DeviceArray)
    assert_same(r, stereo.compute(left, right))


def test_host_results_of_device_inputs_stay_valid(cp, pair):
    # Device inputs, NumPy outputs: downloaded through the path's pinned buffer into recycled
    # host storage; a result kept must not change when later frames reuse storage.
    rig, left, right = pair
    stereo = cs.Stereo(rig, "realtime", "cuda")
    ref = cs.Stereo(rig, "realtime", "cuda").compute(left, right)
    other = (right[:, ::-1].copy(), left[:, ::-1].copy())
    r1 = stereo.compute(cp.asarray(left), cp.asarray(right))
    assert isinstance(r1.depth, np.ndarray)
    assert_same(r1, ref)
    keep = {n: getattr(r1, n).copy() for n in OUTPUTS if getattr(r1, n) is not None}
    for i in range(4):
        r = stereo.compute(cp.asarray(other[0]), cp.asarray(other[1])) if i % 2 == 0 else \
            stereo.compute(cp.asarray(left), cp.asarray(right))
        if i % 2:
            assert_same(r, ref)
        for n, v in keep.items():
            assert same_bits(getattr(r1, n), v), n
    # NumPy inputs through the device path (return_device=True): pinned upload, same results.
    assert_same(stereo.compute(left, right, return_device=True), ref)


def test_next_on_the_device_path_equals_host_next(pair):
    # Stereo.next through the device path (DeviceStereo::next; here host inputs with
    # return_device=True, no array library needed) against cs::Stereo::next on the same
    # backend: the same kernels, so the same bits, and the same cold / warm schedule. The
    # device path has no warm-failure check: with warm_fail_ratio 0 neither redoes a frame.
    rig, left, right = pair
    params = dict(cold_every=3, warm_fail_ratio=0.0, min_width=20)
    on_host, on_device = cs.Stereo(rig, "realtime", "cuda", **params), cs.Stereo(rig, "realtime", "cuda", **params)
    pose = np.eye(4)  # a static camera
    for k, warm in enumerate([False, True, True, False, True]):
        ref = on_host.next(left, right, pose=pose)
        r = on_device.next(left, right, pose=pose, return_device=True)
        assert isinstance(r.depth, cs.DeviceArray)
        assert (ref.warm, r.warm) == (warm, warm), k
        assert not ref.redone and not r.redone
        # warm_fail_ratio 0 skips the check and the read it needs: no share on either path.
        assert np.isnan(r.consistent_share) and np.isnan(ref.consistent_share)
        assert_same(r, ref)
    on_device.reset_sequence()
    assert [on_device.next(left, right, return_device=True).warm for _ in range(2)] == [False, True]
    # Switching between host and device arrays: each pipeline carries its own previous
    # frame, so the side switched to starts cold.
    assert [on_device.next(left, right).warm for _ in range(2)] == [False, True]
    assert not on_device.next(left, right, return_device=True).warm


def test_next_with_cupy_inputs(cp, pair):
    rig, left, right = pair
    stereo = cs.Stereo(rig, "realtime", "cuda", min_width=20)
    ref = cs.Stereo(rig, "realtime", "cuda", min_width=20, warm_fail_ratio=0.0)
    for _ in range(2):
        r = stereo.next(cp.asarray(left), cp.asarray(right), pose=(np.eye(3), np.zeros(3)))
        assert isinstance(r.depth, np.ndarray)
        assert_same(r, ref.next(left, right))
    assert r.warm
