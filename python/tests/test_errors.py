"""Every failure is a curvestereo.Error (a RuntimeError) whose message is one line naming
the problem; nothing crashes or hangs."""
import numpy as np
import pytest

import curvestereo as cs


def raises(match):
    return pytest.raises(cs.Error, match=match)


@pytest.fixture
def stereo(tiny):
    return cs.Stereo(cs.load_calibration(tiny[0]), backend="cpu")


def one_line(excinfo):
    msg = str(excinfo.value)
    assert msg and "\n" not in msg
    return msg


# ---------------------------------------------------------------- files


def test_missing_calibration(tmp_path):
    with raises("no_such.yaml") as e:
        cs.load_calibration(str(tmp_path / "no_such.yaml"))
    one_line(e)


def test_bad_calibration(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("cam0: {camera_model: pinhole}\n")
    with raises("bad.yaml") as e:
        cs.load_calibration(str(p))
    one_line(e)


def test_unknown_calibration_format(tiny, tmp_path):
    with raises("unknown calibration format 'ros'"):
        cs.load_calibration(tiny[0]).save(tmp_path / "x.yaml", format="ros")


def test_missing_image(tmp_path):
    with raises("nope.png") as e:
        cs.read_image(str(tmp_path / "nope.png"))
    one_line(e)
    with raises("nope.exr"):
        cs.read_image(str(tmp_path / "nope.exr"))


def test_not_an_image(tmp_path):
    p = tmp_path / "text.png"
    p.write_text("hello")
    with raises("text.png"):
        cs.read_image(str(p))


def test_unwritable_outputs(tmp_path):
    missing = tmp_path / "no_dir" / "x"
    with raises("no_dir"):
        cs.write_png(str(missing) + ".png", np.zeros((4, 4), np.float32))
    with raises("no_dir"):
        cs.write_exr(str(missing) + ".exr", np.zeros((4, 4), np.float32))
    with raises("no_dir"):
        cs.write_ply(str(missing) + ".ply", np.zeros((4, 3), np.float32))


# ---------------------------------------------------------------- construction


def test_unknown_preset(tiny):
    with raises("nonsense") as e:
        cs.Stereo(cs.load_calibration(tiny[0]), "nonsense", "cpu")
    assert "realtime" in one_line(e)  # lists the known names


def test_unknown_backend(tiny):
    with raises("tpu") as e:
        cs.Stereo(cs.load_calibration(tiny[0]), backend="tpu")
    assert "cpu" in one_line(e)


def test_unusable_backend(tiny):
    missing = [b for b in ("cuda", "vulkan") if b not in cs.available_backends(usable=True)]
    if not missing:
        pytest.skip("every GPU backend is usable here")
    with raises(missing[0]):
        cs.Stereo(cs.load_calibration(tiny[0]), backend=missing[0])


def test_unknown_override(tiny):
    with raises("'warp_count'") as e:
        cs.Stereo(cs.load_calibration(tiny[0]), backend="cpu", warp_count=3)
    assert "warps" in one_line(e)  # lists the known names


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"warps": "five"}, "'warps' expects an integer"),
        ({"warps": 2.5}, "'warps' expects an integer"),
        ({"warps": True}, "'warps' expects an integer"),
        ({"du_max": "big"}, "'du_max' expects a number"),
        ({"median": "maybe"}, "'median' expects"),
        ({"init": "magic"}, "magic"),
        ({"data_term": "colour"}, "colour"),
        ({"warps": 0}, "warps"),  # Params::validate
        ({"lambda": -1.0}, "lambda"),
        ({"lambda": 1.0, "lambda_": 2.0}, "given twice"),
        ({"outputs": ["depth", "normals"]}, "normals"),
        ({"outputs": "points"}, "list"),
    ],
)
def test_bad_override(tiny, overrides, match):
    with raises(match) as e:
        cs.Stereo(cs.load_calibration(tiny[0]), backend="cpu", **overrides)
    one_line(e)


def test_too_small_rig(tmp_path):
    from conftest import write_camchain

    with raises("too small"):
        cs.Stereo(cs.load_calibration(write_camchain(tmp_path / "c.yaml", 8)), backend="cpu")


# ---------------------------------------------------------------- compute inputs


@pytest.mark.parametrize("dtype", [np.float64, np.int32, np.int8, np.bool_, np.complex64, np.float16])
def test_wrong_dtype(stereo, tiny, dtype):
    left = tiny[1].astype(dtype)
    with raises("left image has dtype") as e:
        stereo.compute(left, tiny[2])
    assert "float32" in one_line(e)


@pytest.mark.parametrize("shape", [(32,), (32, 32, 2), (32, 32, 5), (1, 32, 32, 1), ()])
def test_wrong_shape(stereo, tiny, shape):
    with raises("right image has shape"):
        stereo.compute(tiny[1], np.zeros(shape, np.uint8))


def test_not_an_array(stereo, tiny):
    with raises("left image"):
        stereo.compute(None, tiny[2])
    with raises("right image"):
        stereo.compute(tiny[1], "right.png")
    with raises("right image is a object, not an array"):
        stereo.compute(tiny[1], object())


def test_mismatched_sizes(stereo, tiny):
    with raises("left image is 31x32 but the calibration says 32x32"):
        stereo.compute(tiny[1][:, :31], tiny[2])
    with raises("right image is 32x30"):
        stereo.compute(tiny[1], tiny[2][:30])
    with raises("image is"):
        stereo.compute(np.zeros((0, 0), np.float32), tiny[2])


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_pixels(stereo, tiny, bad):
    left = (tiny[1] / 255.0).astype(np.float32)
    left[5, 7] = bad
    with raises("left image contains NaN or infinite pixels"):
        stereo.compute(left, tiny[2])
    colour = np.stack([left, left, left], axis=2)  # NaN survives the colour conversion
    with raises("NaN"):
        stereo.compute(colour, tiny[2])


def test_progress_not_callable(stereo, tiny):
    with raises("callable"):
        stereo.compute(tiny[1], tiny[2], progress=3)


def test_gpu_arrays_need_cuda(stereo, tiny):
    class FakeGpuArray:
        __cuda_array_interface__ = {"shape": (32, 32), "typestr": "<f4", "data": (0, False), "version": 3}

    with raises("CUDA"):
        stereo.compute(FakeGpuArray(), tiny[2])
    with raises("CUDA"):
        stereo.compute(tiny[1], tiny[2], return_device=True)


# ---------------------------------------------------------------- pose and mask


def test_bad_pose(stereo):
    with raises("3 x 3"):
        stereo.set_pose(np.eye(2), [0.1, 0, 0])
    with raises("3 values"):
        stereo.set_pose(np.eye(3), [0.1, 0])
    with raises("baseline|zero|translation"):
        stereo.set_pose(np.eye(3), [0, 0, 0])
    with raises("rotation"):
        stereo.set_pose(2 * np.eye(3), [0.1, 0, 0])
    with raises("3 x 3"):
        stereo.set_pose("R", [0.1, 0, 0])


def test_bad_mask(stereo):
    with raises("mask is 16x16 but the images are 32x32"):
        stereo.set_mask(np.ones((16, 16), np.uint8))
    with raises("mask has shape"):
        stereo.set_mask(np.ones((32, 32, 3), np.uint8))
    with raises("mask"):
        stereo.set_mask(np.array([["a"] * 32] * 32))


def test_state_survives_errors(stereo, tiny):
    """A refused call changes nothing: the next frame is what it would have been."""
    ref = stereo.compute(tiny[1], tiny[2]).depth
    for call in (lambda: stereo.set_pose(np.eye(3), [0, 0, 0]), lambda: stereo.set_mask(np.ones((3, 3))),
                 lambda: stereo.compute(tiny[1][:5], tiny[2])):
        with pytest.raises(cs.Error):
            call()
    assert stereo.compute(tiny[1], tiny[2]).depth.tobytes() == ref.tobytes()


# ---------------------------------------------------------------- writers


def test_bad_writer_inputs(tmp_path):
    with raises("write_png"):
        cs.write_png(str(tmp_path / "a.png"), np.zeros((4, 4, 3), np.float32))
    with raises("write_png"):
        cs.write_png(str(tmp_path / "a.png"), np.zeros((4,), np.uint8))
    with raises("bits"):
        cs.write_png(str(tmp_path / "a.png"), np.zeros((4, 4), np.float32), bits=12)
    with raises("write_exr"):
        cs.write_exr(str(tmp_path / "a.exr"), np.zeros((4, 4), np.uint8))
    with raises("shape"):
        cs.write_ply(str(tmp_path / "a.ply"), np.zeros((4, 2), np.float32))
    with raises("colours"):
        cs.write_ply(str(tmp_path / "a.ply"), np.zeros((4, 3), np.float32), np.zeros(5, np.uint8))
    with raises("depth_picture"):
        cs.depth_picture(np.zeros((4, 4, 2), np.float32))
