"""pose-range: a range of motion measured on motions whose extremes are known tells their own
poses from bent-out-of-range and snapping ones, and survives a round trip through its file."""
import numpy as np
import pytest

from training import pose_range as pr
from training import procedural
from training import skeleton as sk


@pytest.fixture(scope="module")
def walking_range():
    motions = [procedural.make_motion(kind, 8.0, seed=i) for i, kind in enumerate(("walk", "arm_swing", "squat"))]
    return motions, pr.build_pose_range(motions, frame_step=1, source="procedural walks")


def test_chord_and_angle_are_inverse():
    for deg in (0.0, 1.0, 30.0, 90.0, 179.0):
        assert pr.chord_to_deg(pr.deg_to_chord(deg)) == pytest.approx(deg, abs=1e-9)


def test_the_motions_own_poses_are_in_range_and_not_too_fast(walking_range):
    motions, r = walking_range
    for m in motions:
        d = r.distance_deg(m.local_rot)
        # the cover keeps one rotation per cell: every frame is within a cell of one of them
        assert np.nanmax(d) < 2 * pr.COVER_DEG
        bad = r.implausible(m.local_rot, m.fps)
        assert not bad["range"].any() and not bad["speed"].any()
    assert pr.implausible_share(r, motions)[1:] == (0, 0)


def test_a_knee_bent_sideways_is_out_of_range_and_a_snap_too_fast(walking_range):
    motions, r = walking_range
    m = motions[0]
    rot = m.local_rot.astype(np.float64).copy()
    rot[100:110, 4] = rot[100:110, 4] @ sk.rot_axis("z", np.radians(70.0))[None]   # left knee
    bad = r.implausible(rot, m.fps)
    out = np.nonzero(bad["range"].any(axis=1))[0]
    assert out.tolist() == list(range(100, 110))
    assert np.nonzero(bad["range"][100])[0].tolist() == [4]
    # entering and leaving the bend are 70 deg in 1/60 s: too fast; the bend held is not
    assert np.nonzero(bad["speed"].any(axis=1))[0].tolist() == [100, 110]
    # a slow turn to the same bend breaks the range but never the speed
    slow = m.local_rot.astype(np.float64).copy()
    ramp = np.radians(np.linspace(0.0, 70.0, 60))
    slow[100:160, 4] = np.einsum("tab,tbc->tac", slow[100:160, 4],
                                 np.stack([sk.rot_axis("z", a) for a in ramp]))
    bad = r.implausible(slow, m.fps)
    assert bad["range"][:, 4].any() and not bad["speed"][:160, 4].any()   # (160: it drops back)


def test_a_nan_pose_is_not_a_distance(walking_range):
    motions, r = walking_range
    rot = motions[0].local_rot.astype(np.float64).copy()
    rot[5, 18] = np.nan
    d = r.distance_deg(rot)
    assert np.isnan(d[5, 18]) and np.isfinite(np.delete(d.reshape(-1), 5 * 24 + 18)).all()


def test_the_range_survives_its_file(tmp_path, walking_range):
    motions, r = walking_range
    again = pr.PoseRange.load(r.save(tmp_path / "range.npz"))
    assert again.source == "procedural walks"
    np.testing.assert_allclose(again.speed_limit, r.speed_limit)
    probe = motions[1].local_rot.astype(np.float64) @ sk.rot_axis("x", 0.3)[None, None]
    np.testing.assert_allclose(again.distance_deg(probe), r.distance_deg(probe), atol=1e-3)


def test_no_motion_is_a_usage_error():
    from training.errors import UsageError
    with pytest.raises(UsageError):
        pr.build_pose_range([])


def test_the_engine_cover_is_a_thinned_quantised_range(walking_range):
    motions, r = walking_range
    cover = pr.engine_cover(r)
    assert len(cover) == sk.NUM_JOINTS and len(cover[0]) == 0        # the root is not guarded
    for j in range(1, sk.NUM_JOINTS):
        c = cover[j]
        assert c.dtype == np.int8 and 0 < len(c) <= len(r.covers[j])
        # every rotation of the full cover is near one of the engine's
        p = c.astype(np.float64) / np.linalg.norm(c.astype(np.float64), axis=1, keepdims=True)
        near = np.abs(r.covers[j] @ p.T).max(axis=1)
        assert np.degrees(2 * np.arccos(np.clip(near, -1, 1))).max() < pr.ENGINE_COVER_DEG


def test_the_guard_turns_a_broken_joint_back_to_the_tolerance_and_leaves_the_rest(walking_range):
    motions, r = walking_range
    cover = pr.engine_cover(r)
    m = motions[0]
    q = sk.quat_from_rot(m.local_rot[:200].astype(np.float64))
    same, moved = pr.guard_quats(q, cover, 25.0)
    assert not moved.any()
    assert np.allclose(np.abs(np.sum(same * q, -1)), 1.0, atol=1e-12)
    rot = m.local_rot[:200].astype(np.float64).copy()
    rot[50:60, 4] = rot[50:60, 4] @ sk.rot_axis("z", np.radians(90.0))[None]   # a knee sideways
    bent = sk.quat_from_rot(rot)
    out, moved = pr.guard_quats(bent, cover, 25.0)
    assert np.nonzero(moved.any(axis=1))[0].tolist() == list(range(50, 60))
    assert np.nonzero(moved[50])[0].tolist() == [4]
    # the guarded knee is at the tolerance from the engine's cover, on the way back from the bend
    p = cover[4].astype(np.float64)
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    dist = np.degrees(2 * np.arccos(np.clip(np.abs(out[50:60, 4] @ p.T).max(axis=1), -1, 1)))
    assert np.allclose(dist, 25.0, atol=0.05)
    before = np.degrees(2 * np.arccos(np.clip(np.abs(bent[50:60, 4] @ p.T).max(axis=1), -1, 1)))
    gone = np.degrees(2 * np.arccos(np.clip(np.abs(np.sum(out[50:60, 4] * bent[50:60, 4], -1)), -1, 1)))
    assert np.allclose(gone + 25.0, before, atol=0.05)
    # the guard's answer is in range for the full cover too: no longer broken
    assert not r.implausible(sk.rot_from_quat(out), m.fps)["range"].any()
    again, moved = pr.guard_quats(out, cover, 25.0)
    assert not moved.any()


def test_the_engine_table_written_is_what_the_engine_reads(walking_range, tmp_path):
    import re
    _, r = walking_range
    path = tmp_path / "table.c"
    n = pr.write_engine_table(path, r)
    assert all((a == b).all() for a, b in zip(pr.read_engine_table(path), pr.engine_cover(r)))
    text = path.read_text()
    spans = [(int(a), int(b)) for a, b in re.findall(r"\{(\d+), (\d+)\},\s+/\*", text)]
    points = re.findall(r"\{(-?\d+),(-?\d+),(-?\d+),(-?\d+)\},", text)
    cover = pr.engine_cover(r)
    assert len(spans) == sk.NUM_JOINTS and spans[0] == (0, 0)
    assert [b for _, b in spans] == [len(c) for c in cover] and len(points) == n
    assert f"pose_range_points[{n}][4]" in text
    first = 0
    for (a, b), c in zip(spans, cover):
        assert a == first
        got = np.array(points[a:a + b], np.int64).reshape(-1, 4)
        assert (got == c.astype(np.int64)).all()
        first += b


def test_the_engines_table_is_complete():
    """The committed table: a span per joint, back to back, the root's empty, the rest not."""
    import re
    cover = pr.read_engine_table()
    assert len(cover[0]) == 0 and all(len(c) > 0 for c in cover[1:])
    text = pr.ENGINE_TABLE.read_text()
    spans = [(int(a), int(b)) for a, b in re.findall(r"\{(\d+), (\d+)\},\s+/\*", text)]
    n = int(re.search(r"pose_range_points\[(\d+)\]\[4\]", text).group(1))
    assert len(spans) == sk.NUM_JOINTS and spans[0][1] == 0
    assert all(b > 0 for _, b in spans[1:])
    assert [a for a, _ in spans] == list(np.cumsum([0] + [b for _, b in spans[:-1]]))
    assert sum(b for _, b in spans) == n == len(re.findall(r"\{-?\d+,-?\d+,-?\d+,-?\d+\},", text))
