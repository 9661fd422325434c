"""Sequences: curvestereo.Sequence over a tiny ASL folder written here, Stereo.next's warm
start on the CPU backend, the pose argument's forms and errors, reset_sequence."""
from pathlib import Path

import numpy as np
import pytest

import curvestereo as cs
from conftest import same_bits, texture_pair, write_camchain

N = 128  # warm frames need the band sweep: 128 px with levels=4, min_width=16 (as tests/test_sequence.cpp)
T0 = 1_000_000_000_000
STEP = 50_000_000  # 20 Hz
FRAMES = 4


def sequence_stereo(rig, **more):
    return cs.Stereo(rig, "realtime", backend="cpu", levels=4, min_width=16, **more)


def write_asl_camera(mav0, cam, stamps, image):
    data = mav0 / cam / "data"
    data.mkdir(parents=True)
    lines = ["#timestamp [ns],filename"]
    for t in stamps:
        cs.write_png(data / f"{t}.png", image)
        lines.append(f"{t},{t}.png")
    (mav0 / cam / "data.csv").write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def asl(tmp_path_factory):
    """An ASL folder: FRAMES frames of a static textured wall (the same pair each frame),
    cam1 logged 0.2 ms late plus one cam1 frame without a cam0 partner, poses_cam0.csv with
    the rig moving 1 cm along x per frame; camchain.yaml beside mav0/."""
    root = tmp_path_factory.mktemp("asl")
    left, right = texture_pair(N, shift=2, seed=3)
    stamps = [T0 + k * STEP for k in range(FRAMES)]
    write_asl_camera(root / "mav0", "cam0", stamps, left)
    write_asl_camera(root / "mav0", "cam1", [t + 200_000 for t in stamps] + [T0 + 10 * STEP], right)
    poses = ["#timestamp, p_x, p_y, p_z, q_x, q_y, q_z, q_w"]
    poses += [f"{t},{0.01 * k},0,0,0,0,0,1" for k, t in enumerate(stamps)]
    (root / "poses_cam0.csv").write_text("\n".join(poses) + "\n")
    write_camchain(root / "camchain.yaml", N)
    return root, left, right


# ---------------------------------------------------------------- curvestereo.Sequence


def test_asl_frames_timestamps_poses_and_warnings(asl):
    root, left, right = asl
    seq = cs.Sequence(root)  # a pathlib.Path; str works too
    assert len(seq) == FRAMES
    assert list(seq.timestamps_ns) == [T0 + k * STEP for k in range(FRAMES)]
    assert "4 stereo frames" in seq.summary and "ASL" in seq.summary
    # The cam1 frame without a partner is reported, not dropped silently.
    assert any("cam1" in w and "no cam0 frame" in w for w in seq.warnings), seq.warnings
    assert "Sequence" in repr(seq)

    f = seq[1]
    assert isinstance(f, cs.Frame)
    assert f.index == 1 and f.timestamp_ns == T0 + STEP
    assert f.left_path.endswith(f"cam0/data/{T0 + STEP}.png")
    assert f.pose.shape == (4, 4) and f.pose.dtype == np.float64
    np.testing.assert_allclose(f.pose[:3, 3], [0.01, 0, 0])
    np.testing.assert_allclose(f.pose[:3, :3], np.eye(3))
    np.testing.assert_array_equal(f.pose[3], [0, 0, 0, 1])
    # The images: float32 gray in [0, 1], exactly as read_image reads the files.
    assert f.left.dtype == np.float32 and f.left.shape == (N, N)
    assert same_bits(f.left, cs.read_image(f.left_path))
    assert same_bits(f.right, cs.read_image(f.right_path))
    np.testing.assert_allclose(f.left, left / 255.0, atol=1e-6)
    assert f.left is f.left  # read once, then kept by the frame

    assert seq[-1].index == FRAMES - 1
    with pytest.raises(IndexError):
        seq[FRAMES]
    with pytest.raises(IndexError):
        seq[-FRAMES - 1]
    assert [f.index for f in seq] == list(range(FRAMES))
    assert [f.timestamp_ns for f in seq] == list(seq.timestamps_ns)


def test_frames_are_read_when_used(asl, tmp_path):
    # A copy whose frame 2 loses its left image after opening: the listing and the other
    # frames are unaffected; frame 2 fails when its images are used, naming the file.
    import shutil

    root = tmp_path / "copy"
    shutil.copytree(asl[0], root)
    seq = cs.Sequence(str(root / "mav0"))  # mav0/ itself works too
    missing = root / "mav0" / "cam0" / "data" / f"{T0 + 2 * STEP}.png"
    missing.unlink()
    frames = list(seq)  # no image read yet
    assert frames[0].left.shape == (N, N)
    assert frames[2].timestamp_ns == T0 + 2 * STEP
    with pytest.raises(cs.Error, match=f"{T0 + 2 * STEP}"):
        frames[2].left
    assert frames[3].right.shape == (N, N)


def test_read_ahead_gives_every_frame_read_and_an_error_at_its_turn(asl, tmp_path):
    import shutil

    seq = cs.Sequence(asl[0])
    ahead = seq.read_ahead(threads=2)
    frames = list(ahead)
    assert [f.index for f in frames] == list(range(len(seq))) and ahead.threads == 2
    for f in frames:
        assert same_bits(f.left, seq[f.index].left) and same_bits(f.right, seq[f.index].right)
    assert ahead.read_ms > 0 and ahead.waited_ms >= 0 and ahead.first_wait_ms >= 0

    root = tmp_path / "copy"
    shutil.copytree(asl[0], root)
    (root / "mav0" / "cam1" / "data" / f"{T0 + 2 * STEP + 200_000}.png").unlink()  # cam1 is 0.2 ms late
    ahead = cs.Sequence(root).read_ahead(threads=3)
    assert [next(ahead).index for _ in range(2)] == [0, 1]
    with pytest.raises(cs.Error, match=f"frame 2 \\(t {T0 + 2 * STEP} ns\\), right image"):
        next(ahead)
    assert list(ahead) == []  # iteration ends at the unreadable frame


def test_folder_pairs_and_explicit_poses(tmp_path):
    left, right = texture_pair(32)
    for side, img in (("L", left), ("R", right)):
        (tmp_path / side).mkdir()
        for k in (9, 10, 11):  # natural order: 9 before 10
            cs.write_png(tmp_path / side / f"{k}.png", img)
    poses = tmp_path / "traj.txt"  # TUM: seconds, position, quaternion x y z w
    poses.write_text("# t tx ty tz qx qy qz qw\n0.000000009 1 2 3 0 0 0 1\n0.00000001 1 2 3 0 0 0.7071068 0.7071068\n")
    for source in ((tmp_path / "L", tmp_path / "R"), f"{tmp_path / 'L'},{tmp_path / 'R'}"):
        seq = cs.Sequence(source, poses=poses, pose_tolerance_ms=0.0)
        assert len(seq) == 3
        assert [f.timestamp_ns for f in seq] == [9, 10, 11]  # the stems are integer ns
        np.testing.assert_allclose(seq[0].pose[:3, 3], [1, 2, 3])
        np.testing.assert_allclose(seq[1].pose[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-6)
        assert seq[2].pose is None  # no pose within 0 ms
        assert any("pose" in w for w in seq.warnings), seq.warnings


def test_sequence_errors(tmp_path):
    with pytest.raises(cs.Error):
        cs.Sequence(tmp_path / "nowhere")
    (tmp_path / "mav0" / "cam0").mkdir(parents=True)
    (tmp_path / "mav0" / "cam0" / "data.csv").write_text("#timestamp [ns],filename\n12,a.png\nnot a line\n")
    (tmp_path / "mav0" / "cam1").mkdir()
    (tmp_path / "mav0" / "cam1" / "data.csv").write_text("12,a.png\n")
    with pytest.raises(cs.Error, match="line 3"):
        cs.Sequence(tmp_path)
    with pytest.raises(cs.Error, match="pair_tolerance_ms"):
        cs.Sequence(tmp_path, pair_tolerance_ms=-1)
    with pytest.raises(cs.Error, match="source"):
        cs.Sequence(("a", "b", "c"))


# ---------------------------------------------------------------- Stereo.next


def test_next_cold_then_warm_on_cpu(asl):
    root, _, _ = asl
    seq = cs.Sequence(root)
    rig = cs.load_calibration(root / "camchain.yaml")
    stereo = sequence_stereo(rig)
    results = []
    for k, f in enumerate(seq):
        if k == 3:
            break
        results.append(stereo.next(f.left, f.right, pose=f.pose))
        if k == 1:
            # compute() between next() calls solves a pair without touching the sequence.
            single = stereo.compute(f.left, f.right)
            assert not single.warm and not single.redone and np.isnan(single.consistent_share)
            assert np.isnan(single.mean_confidence)
    assert [r.warm for r in results] == [False, True, True]
    assert not any(r.redone for r in results)
    for r in results:
        assert r.depth.dtype == np.float32 and r.depth.shape == (N, N)
        assert r.valid.dtype == np.bool_ and r.valid.mean() > 0.5
        assert 0.5 < r.consistent_share <= 1.0
        assert 0.0 < r.mean_confidence <= 1.0
        assert r.confidence is not None
    # The wall: 2 px of shift at the centre of a 180-degree image of 128 px.
    centre = results[2].depth[N // 2 - 8 : N // 2 + 8, N // 2 - 8 : N // 2 + 8]
    cold_centre = results[0].depth[N // 2 - 8 : N // 2 + 8, N // 2 - 8 : N // 2 + 8]
    assert abs(np.nanmedian(centre) / np.nanmedian(cold_centre) - 1) < 0.1
    # The first frame of a sequence is the cold solve itself, bit for bit.
    reference = sequence_stereo(rig).compute(seq[0].left, seq[0].right)
    assert same_bits(results[0].depth, reference.depth)


def test_reset_sequence_and_cold_every(asl):
    root, left, right = asl
    rig = cs.load_calibration(root / "camchain.yaml")
    stereo = sequence_stereo(rig, cold_every=2)
    assert stereo.params["cold_every"] == 2
    # uint8 arrays work as in compute(); poses are optional.
    assert [stereo.next(left, right).warm for _ in range(3)] == [False, True, False]
    assert stereo.next(left, right).warm
    stereo.reset_sequence()
    assert not stereo.next(left, right).warm
    assert stereo.next(left, right).warm


def test_sequence_parameters_through_overrides(tiny):
    rig = cs.load_calibration(tiny[0])
    s = cs.Stereo(
        rig,
        backend="cpu",
        warm_start=False,
        cold_every=5,
        warm_fail_ratio=0.5,
        temporal_strength=0.25,
        temporal_gate=2.5,
    )
    p = s.params
    assert p["warm_start"] is False and p["cold_every"] == 5
    assert p["warm_fail_ratio"] == 0.5 and p["temporal_strength"] == 0.25 and p["temporal_gate"] == 2.5
    for name in ("warm_start", "cold_every", "warm_fail_ratio", "temporal_strength", "temporal_gate"):
        assert name in cs.preset_params("realtime")
    with pytest.raises(cs.Error, match="warm_fail_ratio|warmFailRatio"):  # validate() names the field
        cs.Stereo(rig, backend="cpu", warm_fail_ratio=2.0)
    # warm_start off: every frame cold.
    assert not any(s.next(tiny[1], tiny[2]).warm for _ in range(2))


def test_pose_forms(tiny):
    rig_path, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(rig_path), backend="cpu")
    R = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], float)  # 90 degrees about z
    t = np.array([0.1, 0.2, 0.3])
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    for pose in (None, T, T.astype(np.float32), T.tolist(), (R, t), [R.tolist(), list(t)], (R, t.reshape(3, 1))):
        r = stereo.next(left, right, pose=pose)
        assert r.depth.shape == left.shape
    assert stereo.next(left, right, T).depth.shape == left.shape  # positional


@pytest.mark.parametrize(
    "pose, message",
    [
        (np.eye(3), r"pose must be None, a 4 x 4 array \(T_world_cam0\) or an \(R, t\) pair.*shape \(3, 3\)"),
        (np.eye(4)[:3], r"shape \(3, 4\)"),
        (np.zeros(16), r"shape \(16,\)"),
        ("pose.txt", "got str"),
        ({"R": np.eye(3)}, "got dict"),
        (np.diag([1.0, 1, 1, 2]), r"last row .* must be \[0, 0, 0, 1\]"),
        (np.diag([2.0, 2, 2, 1]), "not a rotation"),
        (np.diag([1.0, 1, -1, 1]), "not a rotation"),  # a reflection
        (np.full((4, 4), np.nan), "last row|NaN"),
        ((np.eye(3), [0, 0]), r"t of an \(R, t\) pair must hold 3 numbers, got shape \(2,\)"),
        ((np.eye(4), [0, 0, 0]), r"R of an \(R, t\) pair must be a 3 x 3 array of numbers, got shape \(4, 4\)"),
        ((np.eye(3), "abc"), "t of an .* got str"),
        ((np.eye(3), [0, np.inf, 0]), "NaN or infinite"),
    ],
)
def test_bad_pose_raises(tiny, pose, message):
    rig_path, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(rig_path), backend="cpu")
    with pytest.raises(cs.Error, match=message):
        stereo.next(left, right, pose=pose)


def test_next_checks_images_as_compute(tiny):
    rig_path, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(rig_path), backend="cpu")
    with pytest.raises(cs.Error, match="left image"):
        stereo.next(left[:16], right)
    bad = left.astype(np.float32) / 255
    bad[3, 3] = np.nan
    with pytest.raises(cs.Error, match="NaN"):
        stereo.next(bad, right)
    # A failed frame leaves the sequence usable: the next good one is its first, cold.
    assert not stereo.next(left, right).warm


def test_next_progress(tiny):
    rig_path, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(rig_path), backend="cpu")
    seen = []
    stereo.next(left, right, progress=seen.append)
    assert seen and seen[-1] == 1.0


def test_gpu_arrays_need_cuda_for_next(tiny):
    if cs.build_info()["cuda_arrays"]:
        pytest.skip("this build has the CUDA device path (tested in test_device.py)")
    rig_path, left, right = tiny
    stereo = cs.Stereo(cs.load_calibration(rig_path), backend="cpu")
    with pytest.raises(cs.Error, match="CUDA"):
        stereo.next(left, right, return_device=True)


def test_example_in_the_module_docstring_runs(asl):
    root = Path(asl[0])
    seq = cs.Sequence(root)
    stereo = cs.Stereo(cs.load_calibration(root / "camchain.yaml"), backend="cpu", levels=4, min_width=16)
    warm = [stereo.next(f.left, f.right, pose=f.pose).warm for f in seq]
    assert warm == [False] + [True] * (FRAMES - 1)
    assert "stereo.next(f.left, f.right, pose=f.pose)" in cs.__doc__
