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
