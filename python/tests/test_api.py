"""The module's API on the CPU backend: calibration, solver, results, I/O."""
import numpy as np
import pytest

import curvestereo as cs
from conftest import same_bits


def test_module_basics():
    assert issubclass(cs.Error, RuntimeError)
    assert {"realtime", "fast", "variational", "quality", "paper"} <= set(cs.presets())
    assert "cpu" in cs.available_backends()
    assert cs.available_backends(usable=True)[-1] == "cpu"
    info = cs.build_info()
    assert info["version"] == cs.__version__
    assert "warps" in info["parameters"] and "lambda" in info["parameters"]
    assert cs.preset_params("realtime")["warps_taper"] == 10


def test_rig(tiny):
    rig = cs.load_calibration(tiny[0])
    assert (rig.width, rig.height) == (32, 32)
    assert rig.R.shape == (3, 3) and rig.t.shape == (3,)
    assert rig.baseline == pytest.approx(0.12)
    assert rig.cam0["model"] == "kannala-brandt4" and len(rig.cam0["params"]) == 8
    half = rig.scaled(0.5)
    assert (half.width, half.height) == (16, 16)
    assert "32x32" in repr(rig)


@pytest.mark.parametrize("fmt, name", [("kalibr", "camchain.yaml"), ("basalt", "calibration.json"),
                                       ("opencv", "stereo.yaml"), ("opencv", "stereo.xml")])
def test_every_calibration_format(tiny, tmp_path, fmt, name):
    rig = cs.load_calibration(tiny[0])
    rig.save(tmp_path / name, format=fmt)  # pathlib paths are fine
    again = cs.load_calibration(tmp_path / name)
    assert np.allclose(again.t, rig.t) and np.allclose(again.R, rig.R)
    assert again.cam1["model"] == rig.cam1["model"] and np.allclose(again.cam1["params"], rig.cam1["params"])


def test_compute_outputs(small):
    calib, left, right = small
    stereo = cs.Stereo(cs.load_calibration(calib), "realtime", "cpu", device=0)  # the CPU takes any device
    assert stereo.backend == "cpu" and stereo.device and "cpu" in stereo.backend_choice
    # the sweep's volumes: realtime holds more than the solver alone
    assert stereo.buffer_bytes > cs.Stereo(cs.load_calibration(calib), "variational", "cpu").buffer_bytes > 0
    r = stereo.compute(left, right)
    h, w = left.shape
    assert r.depth.dtype == np.float32 and r.depth.shape == (h, w)
    assert r.z.shape == (h, w) and r.disparity.shape == (h, w)
    assert r.points.shape == (h, w, 3) and r.points.dtype == np.float32
    assert r.warp.shape == (h, w, 2)
    assert r.valid.dtype == np.bool_ and r.valid.any()
    # The confidence comes with the plane-sweep initialiser only.
    assert (r.confidence is None) == (stereo.params["init"] == "none")
    # The output contract: invalid is NaN everywhere, valid depth is positive or +inf.
    assert np.isnan(r.depth[~r.valid]).all() and np.isnan(r.points[~r.valid]).all()
    assert (r.depth[r.valid] > 0).all()
    assert np.isfinite(r.disparity[r.valid]).all()
    assert isinstance(r.stages, dict) and r.stages and all(v >= 0 for v in r.stages.values())
    assert r.total_ms > 0
    assert "Result" in repr(r)


def test_outputs_subset_and_profile(small):
    calib, left, right = small
    full = cs.Stereo(cs.load_calibration(calib), backend="cpu").compute(left, right)
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu", outputs=[], profile=False)
    assert stereo.outputs == []
    r = stereo.compute(left, right)
    assert r.points is None and r.z is None and r.disparity is None and r.warp is None
    assert r.stages == {}
    assert same_bits(r.depth, full.depth) and same_bits(r.valid, full.valid)
    only = cs.Stereo(cs.load_calibration(calib), backend="cpu", outputs=["points"]).compute(left, right)
    assert only.points is not None and only.disparity is None


def test_overrides_reach_params(tiny):
    rig = cs.load_calibration(tiny[0])
    s = cs.Stereo(rig, "variational", "cpu", warps=7, lambda_=2.5, du_max=0.3, median=False,
                  **{"init-level": 0, "max_fov": 170})
    p = s.params
    assert p["warps"] == 7 and p["lambda"] == 2.5 and p["du_max"] == 0.3
    assert p["median_filter"] is False and p["init_level"] == 0 and p["max_fov_deg"] == 170
    # 'lambda' through a dict, and data_term first whatever the order: lambda wins.
    s = cs.Stereo(rig, backend="cpu", **{"lambda": 11.0, "data_term": "brightness"})
    assert s.params["lambda"] == 11.0 and s.params["data_term"] == "brightness"
    # Every reported parameter can be passed back unchanged.
    again = cs.Stereo(rig, backend="cpu", **p)
    assert again.params == p


def test_progress_callback(tiny):
    calib, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    seen = []
    stereo.compute(left, right, progress=seen.append)
    assert seen and seen == sorted(seen) and seen[-1] == pytest.approx(1.0)
    assert all(0 <= f <= 1 for f in seen)


def test_progress_exception_stops_the_frame(tiny):
    calib, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    expected = stereo.compute(left, right)
    calls = []

    def stop(fraction):
        calls.append(fraction)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        stereo.compute(left, right, progress=stop)
    assert len(calls) == 1  # not called again once it raised; the CPU frame stopped
    # The object is still usable and gives the same result.
    assert same_bits(stereo.compute(left, right).depth, expected.depth)


def test_set_pose_and_mask(small):
    calib, left, right = small
    rig = cs.load_calibration(calib)
    stereo = cs.Stereo(rig, backend="cpu")
    before = stereo.compute(left, right)
    stereo.set_pose(np.eye(3), [-0.24, 0, 0])  # twice the baseline: depths double
    assert stereo.rig.t[0] == pytest.approx(-0.24)
    after = stereo.compute(left, right)
    both = before.valid & after.valid & np.isfinite(before.depth) & np.isfinite(after.depth)
    assert np.allclose(after.depth[both], 2 * before.depth[both], rtol=1e-3)
    mask = np.zeros(left.shape, bool)
    mask[16:48, 16:48] = True
    stereo.set_mask(mask)
    masked = stereo.compute(left, right)
    assert not masked.valid[~mask].any()


def test_read_write_roundtrips(tmp_path):
    rng = np.random.default_rng(3)
    g8 = rng.integers(0, 256, (20, 30), dtype=np.uint8)
    cs.write_png(str(tmp_path / "g8.png"), g8)
    assert same_bits(cs.read_image(str(tmp_path / "g8.png")), (g8 / 255.0).astype(np.float32))
    g16 = rng.integers(0, 65536, (20, 30), dtype=np.uint16)
    cs.write_png(str(tmp_path / "g16.png"), g16)
    assert same_bits(cs.read_image(str(tmp_path / "g16.png")), (g16 / 65535.0).astype(np.float32))
    f = rng.random((20, 30), dtype=np.float32)
    f[3, 4] = np.nan
    cs.write_exr(str(tmp_path / "f.exr"), f)
    assert same_bits(cs.read_image(str(tmp_path / "f.exr")), f)


def test_colour_png_reads_as_the_array_converts(tmp_path, tiny):
    """A colour array and the colour PNG made from it give the same gray input."""
    calib, left, right = tiny
    rng = np.random.default_rng(4)
    rgb = [np.stack([img, rng.integers(0, 256, img.shape, np.uint8), img[::-1]], axis=2) for img in (left, right)]
    for k, img in enumerate(rgb):
        cs.write_png(str(tmp_path / f"{k}.png"), img)
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    from_arrays = stereo.compute(rgb[0], rgb[1])
    from_files = stereo.compute(cs.read_image(str(tmp_path / "0.png")), cs.read_image(str(tmp_path / "1.png")))
    assert same_bits(from_arrays.depth, from_files.depth)
    # RGBA: alpha is dropped, as the PNG reader does.
    rgba = [np.concatenate([img, np.full(img.shape[:2] + (1,), 7, np.uint8)], axis=2) for img in rgb]
    assert same_bits(stereo.compute(rgba[0], rgba[1]).depth, from_arrays.depth)


def test_uint8_frames_solve_as_their_float_conversion(tiny):
    """8-bit frames go to the library as bytes: the same bits as the float images, for a
    pair, for warm sequence frames, and for a strided view."""
    calib, left, right = tiny
    as_float = lambda a: (a / 255.0).astype(np.float32)  # noqa: E731  the PNG reader's scaling
    stereo = cs.Stereo(cs.load_calibration(calib), backend="cpu")
    assert same_bits(stereo.compute(left, right).depth, stereo.compute(as_float(left), as_float(right)).depth)
    runs = []
    for frames in ((left, right), (as_float(left), as_float(right))):
        stereo.reset_sequence()
        runs.append([stereo.next(*frames) for _ in range(2)])
    assert runs[0][1].warm == runs[1][1].warm and same_bits(runs[0][1].depth, runs[1][1].depth)
    wide = [np.repeat(img, 2, axis=1) for img in (left, right)]
    assert same_bits(stereo.compute(wide[0][:, ::2], wide[1][:, ::2]).depth, stereo.compute(left, right).depth)


def test_write_ply(tmp_path):
    pts = np.array([[[0, 0, 1], [np.nan, 0, 0]], [[1, 2, 3], [4, 5, np.inf]]], np.float32)
    cs.write_ply(str(tmp_path / "a.ply"), pts)
    data = (tmp_path / "a.ply").read_bytes()
    assert b"element vertex 2\n" in data and data.endswith(np.array([1, 2, 3], "<f4").tobytes() + b"\xff\xff\xff")
    gray = np.array([[0.0, 1.0], [0.5, 1.0]], np.float32)
    cs.write_ply(str(tmp_path / "g.ply"), pts, gray)
    assert (tmp_path / "g.ply").read_bytes().endswith(b"\x80\x80\x80")
    rgb = np.zeros((2, 2, 3), np.uint8)
    rgb[1, 0] = [10, 20, 30]
    cs.write_ply(str(tmp_path / "c.ply"), pts.reshape(-1, 3), rgb.reshape(-1, 3))
    c = (tmp_path / "c.ply").read_bytes()
    assert b"element vertex 2\n" in c and c.endswith(bytes([10, 20, 30]))


def test_pictures():
    depth = np.array([[1, 2], [np.nan, np.inf]], np.float32)
    pic = cs.depth_picture(depth)
    assert pic.shape == (2, 2, 3) and pic.dtype == np.uint8
    assert (pic[1, 0] == 0).all()  # invalid is black
    c = cs.colorize(np.array([[0.0, 1.0]], np.float32), 0, 1)
    assert c.shape == (1, 2, 3) and not (c[0, 0] == c[0, 1]).all()


def test_stubs_match_the_module():
    """curvestereo/__init__.pyi names exactly what the module has (a drift check)."""
    import ast
    from pathlib import Path

    stub_path = Path(cs.__file__).with_name("__init__.pyi")
    tree = ast.parse(stub_path.read_text())
    top = {n.name: n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    public = {n for n in cs.__all__}
    assert public <= set(top), sorted(public - set(top))
    # DeviceArray is stubbed always but exists only in builds with the CUDA backend.
    cuda_only = set() if hasattr(cs, "DeviceArray") else {"DeviceArray"}
    assert {n for n in top if not n.startswith("_")} - cuda_only <= public
    classes = ("Rig", "Stereo", "Result", "Sequence", "Frame", "CameraRig", "RigStereo", "RigResult", "Panorama",
               "RigSequence", "RigFrame")
    for name in classes + (("DeviceArray",) if hasattr(cs, "DeviceArray") else ()):
        members = {m for m in dir(getattr(cs, name)) if not m.startswith("_")}
        stubbed = {n.name for n in top[name].body if isinstance(n, ast.FunctionDef) and not n.name.startswith("_")}
        assert members == stubbed, (name, sorted(members ^ stubbed))
    # Every parameter the table knows is a keyword of Stereo.__init__ in the stub.
    init = next(n for n in top["Stereo"].body if isinstance(n, ast.FunctionDef) and n.name == "__init__")
    keywords = {a.arg for a in init.args.kwonlyargs}
    assert {p if p != "lambda" else "lambda_" for p in cs.build_info()["parameters"]} <= keywords
