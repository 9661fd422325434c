"""The binding gives what the C++ library gives, bit for bit: compared with `curvestereo
run` (the library's Stereo::compute behind its own PNG reader) on rendered pairs."""
import numpy as np
import pytest

import curvestereo as cs
from conftest import run_cli, same_bits


def read_flo(path):
    raw = np.fromfile(path, np.float32)
    w, h = raw[1:3].view(np.int32)
    return raw[3:].reshape(h, w, 2)


def cli_run(cli, calib, left, right, out, *extra):
    run_cli(cli, "run", "--calib", calib, left, right, "-o", out, "--backend", "cpu", *extra)
    return out


@pytest.mark.parametrize("preset", ["realtime", "quality"])
def test_same_as_cli_on_a_rendered_pair(cli, synth_pair, tmp_path, preset):
    d = synth_pair
    extra = ["--preset", preset] + (["--init-level", "1"] if preset == "quality" else [])
    out = cli_run(cli, d / "camchain.yaml", d / "left.png", d / "right.png", tmp_path, *extra)
    overrides = {"init_level": 1} if preset == "quality" else {}
    stereo = cs.Stereo(cs.load_calibration(str(d / "camchain.yaml")), preset, "cpu", **overrides)
    r = stereo.compute(cs.read_image(str(d / "left.png")), cs.read_image(str(d / "right.png")))
    assert same_bits(r.depth, cs.read_image(str(out / "depth.exr")))
    assert same_bits(r.disparity, cs.read_image(str(out / "disparity.exr")))
    flo = read_flo(out / "flow.flo")
    assert same_bits(r.warp[r.valid], flo[r.valid])
    assert (flo[~r.valid] == 1e10).all()
    if preset == "quality":
        assert same_bits(r.confidence, cs.read_image(str(out / "confidence.exr")))
    # The point cloud: same points, in the same order, coloured by the left image.
    left = cs.read_image(str(d / "left.png"))
    cs.write_ply(str(tmp_path / "mine.ply"), r.points, left)
    assert (tmp_path / "mine.ply").read_bytes() == (out / "points.ply").read_bytes()
    # And the depth picture.
    cs.write_png(str(tmp_path / "mine.png"), cs.depth_picture(r.depth))
    assert (tmp_path / "mine.png").read_bytes() == (out / "depth.png").read_bytes()


@pytest.mark.parametrize("kind", ["uint8", "uint16", "rgb8", "rgb16"])
def test_integer_and_colour_arrays_equal_their_png(cli, small, tmp_path, kind):
    """An array gives what `curvestereo run` gives on the PNG holding the same pixels."""
    calib, left, right = small
    rng = np.random.default_rng(5)
    if kind == "uint16":
        left, right = (img.astype(np.uint16) * 257 + rng.integers(0, 257, img.shape).astype(np.uint16)
                       for img in (left, right))
    if kind.startswith("rgb"):
        left, right = (np.stack([img, img // 2 + 60, 255 - img], axis=2) for img in (left, right))
        if kind == "rgb16":
            left, right = (img.astype(np.uint16) * 257 for img in (left, right))
    for name, img in (("l.png", left), ("r.png", right)):
        if kind == "rgb16":  # write_png has no 16-bit colour: numpy writes a tiny PNG itself
            write_png16_rgb(tmp_path / name, img)
        else:
            cs.write_png(str(tmp_path / name), img)
    out = cli_run(cli, calib, tmp_path / "l.png", tmp_path / "r.png", tmp_path / "out", "--preset", "realtime")
    r = cs.Stereo(cs.load_calibration(calib), "realtime", "cpu").compute(left, right)
    assert np.isfinite(r.depth).mean() > 0.5
    assert same_bits(r.depth, cs.read_image(str(out / "depth.exr")))
    assert same_bits(r.disparity, cs.read_image(str(out / "disparity.exr")))


def write_png16_rgb(path, rgb):
    import struct
    import zlib

    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].astype(">u2").tobytes() for y in range(h))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
    path.write_bytes(png)


def test_any_strides(small):
    """Views (crops, flips, channel-last slices, Fortran order) give the packed array's result."""
    calib, left, right = small
    stereo = cs.Stereo(cs.load_calibration(calib), "realtime", "cpu")
    ref = stereo.compute(left, right).depth
    big_l = np.zeros((80, 90), np.uint8)
    big_r = np.zeros((80, 90), np.uint8)
    big_l[5:69, 7:71], big_r[5:69, 7:71] = left, right
    assert same_bits(stereo.compute(big_l[5:69, 7:71], big_r[5:69, 7:71]).depth, ref)
    assert same_bits(stereo.compute(np.asfortranarray(left), np.asfortranarray(right)).depth, ref)
    flipped = stereo.compute(left[::-1, ::-1].copy()[::-1, ::-1], right[::-1, ::-1].copy()[::-1, ::-1])
    assert same_bits(flipped.depth, ref)
    interleaved = np.stack([left, right], axis=2)  # a pixel's two bytes side by side
    assert same_bits(stereo.compute(interleaved[:, :, 0], interleaved[:, :, 1]).depth, ref)
    # float32 in [0, 1] as the reader scales: the same input, the same bits.
    f = (left / 255.0).astype(np.float32), (right / 255.0).astype(np.float32)
    assert same_bits(stereo.compute(*f).depth, ref)
    # BGR (OpenCV) reversed by a negative stride is the RGB result.
    rgb = np.stack([left, left // 3, 255 - left], axis=2), np.stack([right, right // 3, 255 - right], axis=2)
    bgr = [img[..., ::-1].copy() for img in rgb]
    assert same_bits(stereo.compute(bgr[0][..., ::-1], bgr[1][..., ::-1]).depth, stereo.compute(*rgb).depth)
