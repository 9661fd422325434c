"""Recorded logs: curvestereo.Sequence.from_log over an MCAP file written here byte by byte
(uncompressed chunk, no summary: the reader's plain scan), log_info, and DepthLogWriter
writing Stereo.next's results, read back by log_info."""
import struct

import numpy as np
import pytest

import curvestereo as cs
from conftest import same_bits, texture_pair, write_camchain

N = 64
T0 = 1_000_000_000_000
STEP = 33_333_333


def record(op, content):
    return struct.pack("<BQ", op, len(content)) + content


def mcap_string(s):
    return struct.pack("<I", len(s)) + s


def cdr_image(stamp, pixels):
    sec, nsec = divmod(stamp, 1_000_000_000)
    out = b"\0\1\0\0" + struct.pack("<iI", sec, nsec) + struct.pack("<I", 5) + b"cam0\0"
    out += b"\0" * 3 + struct.pack("<II", pixels.shape[0], pixels.shape[1]) + struct.pack("<I", 6) + b"mono8\0"
    out += b"\0"  # is_bigendian; step is aligned to 4 next
    pad = (4 - (len(out) - 4) % 4) % 4
    out += b"\0" * pad + struct.pack("<I", pixels.shape[1]) + struct.pack("<I", pixels.size) + pixels.tobytes()
    return out


def write_mcap(path, frames, cut=None):
    """MCAP with one uncompressed chunk per frame and no summary (a plain scan's input)."""
    body = b"\x89MCAP0\r\n" + record(1, mcap_string(b"ros2") + mcap_string(b"pytest"))
    body += record(3, struct.pack("<H", 1) + mcap_string(b"sensor_msgs/msg/Image") + mcap_string(b"ros2msg") +
                   mcap_string(b""))
    for cid, topic in enumerate([b"/left", b"/right"]):
        body += record(4, struct.pack("<HH", cid, 1) + mcap_string(topic) + mcap_string(b"cdr") + struct.pack("<I", 0))
    for k, (left, right) in enumerate(frames):
        t = T0 + k * STEP
        records = b"".join(
            record(5, struct.pack("<HIQQ", cid, k, t + 2_000_000, t) + cdr_image(t, img))
            for cid, img in enumerate([left, right]))
        body += record(6, struct.pack("<QQQI", t, t, len(records), 0) + mcap_string(b"") +
                       struct.pack("<Q", len(records)) + records)
    body += record(0x0F, struct.pack("<I", 0))
    body += record(2, struct.pack("<QQI", 0, 0, 0)) + b"\x89MCAP0\r\n"
    path.write_bytes(body[:cut] if cut else body)


@pytest.fixture(scope="module")
def logged(tmp_path_factory):
    root = tmp_path_factory.mktemp("log")
    left, right = texture_pair(N, shift=2, seed=5)
    frames = [(np.roll(left, k, axis=1), np.roll(right, k, axis=1)) for k in range(3)]
    write_mcap(root / "stereo.mcap", frames)
    write_camchain(root / "camchain.yaml", N)
    return root, frames


def test_from_log_gives_the_frames_and_log_info_the_topics(logged):
    root, frames = logged
    seq = cs.Sequence.from_log(root / "stereo.mcap", ("/left", "/right"))
    assert len(seq) == 3 and seq.warnings == []
    assert list(seq.timestamps_ns) == [T0 + k * STEP for k in range(3)]  # header.stamp, not log time
    for k, f in enumerate(seq):
        assert same_bits(f.left, (frames[k][0] / 255.0).astype(np.float32))
        assert same_bits(f.right, (frames[k][1] / 255.0).astype(np.float32))
        assert f.left_path.endswith(f"stereo.mcap:/left#{k}")
    info = cs.log_info(root / "stereo.mcap")
    assert info["messages"] == 6 and info["cut"] == ""
    assert [t["name"] for t in info["topics"]] == ["/left", "/right"]
    assert info["topics"][0]["type"] == "sensor_msgs/msg/Image"
    assert "no index" in info["format"]


def test_cut_log_and_bad_topics(logged, tmp_path):
    root, frames = logged
    whole = (root / "stereo.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole[: len(whole) * 3 // 4])
    seq = cs.Sequence.from_log(cut, ("/left", "/right"))
    assert len(seq) == 2
    assert "cut short at byte" in seq.warnings[0]
    with pytest.raises(cs.Error, match=r"has no topic '/nope' \(its image topics: /left, /right\)"):
        cs.Sequence.from_log(root / "stereo.mcap", ("/nope", "/right"))


def test_depth_log_writer_writes_every_frame(logged, tmp_path):
    root, frames = logged
    rig = cs.load_calibration(root / "camchain.yaml")
    stereo = cs.Stereo(rig, "fast", backend="cpu", levels=3, min_width=16)
    out = tmp_path / "depth.mcap"
    with cs.DepthLogWriter(out, rig, compression="lz4", pinhole=90.0) as w:
        for f in cs.Sequence.from_log(root / "stereo.mcap", ("/left", "/right")):
            w.write(f.timestamp_ns, stereo.next(f.left, f.right))
        assert w.frames == 3
    info = cs.log_info(out)
    counts = {t["name"]: t["messages"] for t in info["topics"]}
    assert counts == {"/curvestereo/depth": 3, "/curvestereo/camera_info": 3, "/curvestereo/points": 3,
                      "/curvestereo/confidence": 3, "/curvestereo/depth_pinhole": 3,
                      "/curvestereo/depth_pinhole/camera_info": 3}
    assert info["start_ns"] == T0 and "lz4" in info["format"]
    with pytest.raises(cs.Error, match="compression must be zstd, lz4 or none"):
        cs.DepthLogWriter(tmp_path / "x.mcap", rig, compression="gzip")
