"""Rigs of N cameras: load_rig, RigStereo and the panorama, against `curvestereo synth --rig`'s
ground truth and `curvestereo run`'s outputs for the same images (CPU backend)."""
import numpy as np
import pytest

import curvestereo as cs
from conftest import run_cli, same_bits

# Small enough for a test: the settings test_cli_rig.cpp uses for ring4 at 96 px.
SIZE, PANORAMA = 96, 256
SOLVE = ("--backend", "cpu", "--preset", "fast")


@pytest.fixture(scope="module")
def ring4(cli, tmp_path_factory):
    """ring4 rendered at 96 px (cam<k>.png, camchain.yaml, panorama_range.exr), and `run`'s
    outputs for it in out/."""
    d = tmp_path_factory.mktemp("ring4")
    run_cli(cli, "synth", "--rig", "ring4", "-o", d, "--size", SIZE, "--samples", 1,
            "--panorama-width", PANORAMA, "--quiet")
    images = [d / f"cam{k}.png" for k in range(4)]
    run_cli(cli, "run", "--calib", d / "camchain.yaml", *images, "-o", d / "out", *SOLVE,
            "--panorama-width", PANORAMA)
    return d


@pytest.fixture(scope="module")
def solved(ring4):
    rig = cs.load_rig(ring4 / "camchain.yaml")
    stereo = cs.RigStereo(rig, preset="fast", backend="cpu")
    images = [cs.read_image(ring4 / f"cam{k}.png") for k in range(len(rig))]
    return rig, stereo, images, stereo.compute(images)


def test_load_rig(ring4):
    rig = cs.load_rig(ring4 / "camchain.yaml")
    assert len(rig) == 4 and "4 cameras" in repr(rig)
    assert [(c["width"], c["height"]) for c in rig.cameras] == [(SIZE, SIZE)] * 4
    assert len(rig.poses) == 4 and rig.poses[0].shape == (4, 4)
    # A ring: the centre lies between the cameras, not at camera 0.
    assert np.linalg.norm(rig.centre - rig.poses[0][:3, 3]) > 0.01
    table = rig.overlaps()
    assert len(table) == 6 and all(p["i"] < p["j"] for p in table)
    chosen = rig.pairs()
    assert chosen and {(p["i"], p["j"]) for p in chosen} <= {(p["i"], p["j"]) for p in table}
    assert {k for p in chosen for k in (p["i"], p["j"])} == {0, 1, 2, 3}  # every camera in a pair
    pair = rig.pair(0, 1)
    first = next(p for p in table if (p["i"], p["j"]) == (0, 1))
    assert isinstance(pair, cs.Rig) and pair.baseline == pytest.approx(first["baseline"])
    with pytest.raises(cs.Error, match="nope.yaml"):
        cs.load_rig(ring4 / "nope.yaml")


def test_cameras_match_the_cli_bit_for_bit(ring4, solved):
    rig, stereo, _, r = solved
    assert stereo.backend == "cpu"
    assert len(r.cameras) == 4 and len(r.solves) == 2 * len(stereo.pairs)
    for s in r.solves:  # each direction solved the side of its image its partner sees
        x0, y0, w, h = s["window"]
        assert 0 < w < 0.8 * SIZE and h == SIZE and 0 <= x0 <= SIZE - w and y0 == 0, s
    for k, cam in enumerate(r.cameras):
        assert cam.depth.shape == (SIZE, SIZE) and cam.depth.dtype == np.float32
        assert cam.valid.mean() > 0.5, k
        assert same_bits(cam.depth, cs.read_image(ring4 / "out" / f"cam{k}" / "depth.exr")), k


def test_panorama_matches_the_cli_and_the_truth(ring4, solved):
    _, _, _, r = solved
    p = r.panorama(width=PANORAMA)
    assert p.range.shape == p.grey.shape == p.confidence.shape == (PANORAMA // 2, PANORAMA)
    assert same_bits(p.range, cs.read_image(ring4 / "out" / "panorama_range.exr"))
    assert same_bits(p.confidence, cs.read_image(ring4 / "out" / "panorama_confidence.exr"))
    truth = cs.read_image(ring4 / "panorama_range.exr")
    # Where the truth has a finite range (the sky is +inf), the panorama mostly has one too
    # (about 92 %), close to it: at 96 px a pixel of disparity is a large share of the depth
    # (median about 9 %; test_cli_rig's eval allows a mean abs-rel of 25 %).
    finite = np.isfinite(truth)
    both = np.isfinite(p.range) & finite
    assert both.sum() > 0.85 * finite.sum()
    rel = np.abs(p.range[both] - truth[both]) / truth[both]
    assert np.median(rel) < 0.15 and rel.mean() < 0.25, (np.median(rel), rel.mean())
    # Another centre moves every range: the panorama is not cached from the first call.
    moved = r.panorama(width=PANORAMA, centre=p.centre + [0.0, 0.0, 0.5])
    assert not same_bits(moved.range, p.range)
    # Leaving the less confident samples out leaves more holes, never fewer.
    strict = r.panorama(width=PANORAMA, min_confidence=0.9)
    assert np.isfinite(strict.range).sum() < np.isfinite(p.range).sum()
    # The fusion is kept between calls (same width and centre): the same panorama again,
    # and another width or the first centre back gives its own.
    assert same_bits(r.panorama(width=PANORAMA).range, p.range)
    assert r.panorama(width=PANORAMA // 2).range.shape == (PANORAMA // 4, PANORAMA // 2)
    assert same_bits(r.panorama(width=PANORAMA).confidence, p.confidence)
    with pytest.raises(cs.Error, match="panorama width must be even"):
        r.panorama(width=PANORAMA + 1)
    assert same_bits(r.panorama(width=PANORAMA).range, p.range)


def test_uint8_images_and_chosen_pairs(ring4, solved):
    rig, _, images, r = solved
    as_bytes = [np.round(im * 255).astype(np.uint8) for im in images]
    again = cs.RigStereo(rig, "fast", "cpu", pairs=[(p["i"], p["j"]) for p in rig.pairs()]).compute(as_bytes)
    for k in range(4):
        assert same_bits(again.cameras[k].depth, r.cameras[k].depth), k
    ring = cs.RigStereo(rig, "fast", "cpu", pairs="0-1,1-2,2-3,0-3")
    assert sorted((p["i"], p["j"]) for p in ring.pairs) == [(0, 1), (0, 3), (1, 2), (2, 3)]


def test_bad_input_raises(ring4, solved):
    rig, stereo, images, r = solved
    with pytest.raises(cs.Error, match="the rig has 4 cameras: compute\\(\\) needs 4 images.*got 3"):
        stereo.compute(images[:3])
    with pytest.raises(cs.Error, match="cam2 image is 96x80, its camera is 96x96"):
        stereo.compute(images[:2] + [images[2][:80]] + images[3:])
    with pytest.raises(cs.Error, match="list of 4 images"):
        stereo.compute(images[0])
    with pytest.raises(cs.Error, match="0-7"):
        cs.RigStereo(rig, "fast", "cpu", pairs="0-7")
    with pytest.raises(cs.Error, match="list of \\(i, j\\) camera indexes"):
        cs.RigStereo(rig, "fast", "cpu", pairs=[(0, "1")])
    with pytest.raises(cs.Error, match="cam3 is in none of the pairs"):
        cs.RigStereo(rig, "fast", "cpu", pairs=[(0, 1), (1, 2)])
    with pytest.raises(cs.Error, match="cross-check"):
        cs.RigStereo(rig, "fast", "cpu", cross_check=2.0)
    with pytest.raises(cs.Error, match="width"):
        r.panorama(width=255)
    with pytest.raises(cs.Error, match="centre"):
        r.panorama(centre=[0.0, 1.0])


def test_sequence_continues_every_direction(ring4, solved):
    """RigStereo.next: each pair direction is its own Stereo sequence (realtime: warm frames
    need the band sweep), the first frame the cold solve itself."""
    rig, _, images, _ = solved
    options = dict(levels=3, min_width=16)
    stereo = cs.RigStereo(rig, "realtime", "cpu", **options)
    first = stereo.next(images)
    cold = cs.RigStereo(rig, "realtime", "cpu", **options).compute(images)
    for k in range(4):
        assert same_bits(first.cameras[k].depth, cold.cameras[k].depth), k
    assert not any(s["warm"] for s in first.solves)
    # A still rig: the body pose changes nothing, every direction starts warm.
    second = stereo.next(images, pose=np.eye(4))
    assert all(s["warm"] and not s["redone"] for s in second.solves), second.solves
    for k in range(4):
        assert second.cameras[k].valid.mean() > 0.5, k
    # compute() in between leaves the sequence; reset_sequence() starts it again cold.
    stereo.compute(images)
    assert all(s["warm"] for s in stereo.next(images, pose=np.eye(4)).solves)
    stereo.reset_sequence()
    assert not any(s["warm"] for s in stereo.next(images).solves)
    with pytest.raises(cs.Error, match="pose"):
        stereo.next(images, pose="nope")


def test_field_of_view_as_the_cli(cli, tmp_path):
    """back2's 220-degree lenses: the preset's 180 degrees widen to the lenses', as `run` does,
    unless the field of view is given."""
    run_cli(cli, "synth", "--rig", "back2", "-o", tmp_path, "--size", 64, "--samples", 1,
            "--panorama-width", 64, "--quiet")
    rig = cs.load_rig(tmp_path / "camchain.yaml")
    assert cs.preset_params("fast")["max_fov_deg"] == 180
    assert cs.RigStereo(rig, "fast", "cpu").params["max_fov_deg"] > 200
    assert cs.RigStereo(rig, "fast", "cpu", max_fov=210).params["max_fov_deg"] == 210
    # Within 120 degrees two lenses back to back see nothing of each other.
    with pytest.raises(cs.Error, match="cam0 sees nothing of cam1's view within the field of view"):
        cs.RigStereo(rig, "fast", "cpu", max_fov=120)


def test_rig_sequence_frames_feed_next(ring4, tmp_path):
    """RigSequence: an ASL folder with one cam<k> per camera, each frame's images and the
    rig's pose (T_world_body from camera 0's poses) ready for RigStereo.next."""
    import shutil

    rig = cs.load_rig(ring4 / "camchain.yaml")
    times = [5_000_000_000, 5_033_333_333]
    for k in range(len(rig)):
        data = tmp_path / "mav0" / f"cam{k}" / "data"
        data.mkdir(parents=True)
        rows = ["#timestamp [ns],filename"]
        for t in times:
            shutil.copy(ring4 / f"cam{k}.png", data / f"{t}.png")
            rows.append(f"{t},{t}.png")
        (data.parent / "data.csv").write_text("\n".join(rows) + "\n")
    (tmp_path / "poses_cam0.csv").write_text("".join(f"{t},1,2,3,0,0,0,1\n" for t in times))
    seq = cs.RigSequence(tmp_path, rig)
    assert len(seq) == 2 and seq.warnings == [] and "2 frames of 4 cameras" in seq.summary
    f = seq[-1]
    assert f.timestamp_ns == times[1] and len(f.paths) == 4
    images = f.images
    assert len(images) == 4 and images[2].shape == (SIZE, SIZE) and images[2].dtype == np.float32
    assert same_bits(images[2], cs.read_image(ring4 / "cam2.png"))
    # The rig's pose puts camera 0's centre on the body where the file puts camera 0.
    body, cam0 = f.pose, rig.poses[0]
    assert np.allclose(body[:3, :3] @ cam0[:3, 3] + body[:3, 3], [1, 2, 3])
    stereo = cs.RigStereo(rig, "realtime", "cpu", levels=3, min_width=16)
    solves = [stereo.next(frame.images, pose=frame.pose).solves for frame in seq]
    assert not any(s["warm"] for s in solves[0]) and all(s["warm"] for s in solves[1])
    with pytest.raises(cs.Error, match="cam3/data.csv"):
        shutil.rmtree(tmp_path / "mav0" / "cam3")
        cs.RigSequence(tmp_path, rig)


def test_one_way_solves_each_pair_once_as_the_cli(cli, ring4, solved):
    rig, both, images, _ = solved
    stereo = cs.RigStereo(rig, preset="fast", backend="cpu", one_way=True)
    r = stereo.compute(images)
    assert len(r.solves) == len(stereo.pairs) == len(both.pairs)
    solved_pairs = {frozenset((s["reference"], s["other"])) for s in r.solves}
    assert solved_pairs == {frozenset((p["i"], p["j"])) for p in stereo.pairs}
    # A camera's own window, and beyond it its partner's estimate carried into it: about as
    # much depth as both ways give.
    for k, (camera, two_way) in enumerate(zip(r.cameras, solved[3].cameras)):
        share, full = (~np.isnan(camera.depth)).mean(), (~np.isnan(two_way.depth)).mean()
        assert share > 0.85 * full, (k, share, full)
    out = ring4 / "out_one_way"
    run_cli(cli, "run", "--calib", ring4 / "camchain.yaml", *[ring4 / f"cam{k}.png" for k in range(4)], "-o", out,
            *SOLVE, "--panorama-width", PANORAMA, "--one-way")
    assert same_bits(r.panorama(width=PANORAMA).range, cs.read_image(out / "panorama_range.exr"))
