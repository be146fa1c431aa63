"""training/chest_follow.py: the engine's chest rule in numpy turns what it says and nothing else."""
import numpy as np
import pytest

from training import chest_follow as cf
from training import skeleton as sk
from training.errors import UsageError


def _random_pose(rng, frames=20):
    aa = rng.normal(size=(frames, 24, 3)) * 0.4
    aa[:, 0] = rng.normal(size=(frames, 3)) * 2.0
    return sk.axis_angle_to_rot(aa)


def _angle(a, b):
    tr = np.einsum("...ji,...ji->...", a, b)
    return np.degrees(np.arccos(np.clip((tr - 1.0) / 2.0, -1.0, 1.0)))


def _chest_off(rng, local, degrees):
    g = cf._globals(local)[:, 9]
    axis = rng.normal(size=(len(local), 3))
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    return sk.axis_angle_to_rot(axis * np.radians(degrees)[:, None]) @ g


def test_the_engine_rule_turns_the_spine_by_shares_and_keeps_head_and_arms():
    rng = np.random.default_rng(1)
    local = _random_pose(rng)
    off = rng.uniform(3.0, 40.0, size=len(local))
    chest = _chest_off(rng, local, off)
    out = cf.follow_chest(local, chest, 0.5)
    g0, g1 = cf._globals(local), cf._globals(out)
    np.testing.assert_allclose(_angle(g0[:, 9], g1[:, 9]), 0.5 * off, atol=1e-4)
    np.testing.assert_allclose(_angle(g1[:, 9], chest), 0.5 * off, atol=1e-4)
    np.testing.assert_allclose(_angle(g0[:, 3], g1[:, 3]), off / 3.0, atol=1e-4)
    np.testing.assert_allclose(_angle(g0[:, 6], g1[:, 6]), off / 2.0, atol=1e-4)
    assert _angle(local[:, 9], out[:, 9]).max() < 1e-4   # spine3 keeps its bend from spine2
    for j in (cf.HEAD,) + cf.UPPER_ARMS:
        assert _angle(g0[:, j], g1[:, j]).max() < 1e-4, j
    for j in (cf.NECK,) + cf.COLLARS + (0, 1, 2, 4, 5, 7, 8, 10, 11, 18, 19, 20, 21, 22, 23):
        assert _angle(local[:, j], out[:, j]).max() < 1e-4, j


def test_spine3_alone_and_the_ends_of_the_share():
    rng = np.random.default_rng(2)
    local = _random_pose(rng)
    chest = _chest_off(rng, local, rng.uniform(5.0, 30.0, size=len(local)))
    g0 = cf._globals(local)
    alone = cf._globals(cf.follow_chest(local, chest, 1.0, keep=None))
    assert _angle(alone[:, 9], chest).max() < 1e-4
    others = [j for j in range(24) if j != 9]
    assert _angle(alone[:, others], g0[:, others]).max() < 1e-4
    np.testing.assert_allclose(cf.follow_chest(local, chest, 0.0), local, atol=1e-12)
    reached = cf._globals(cf.follow_chest(local, chest, 1.0))
    assert _angle(reached[:, 9], chest).max() < 1e-4


def test_a_share_outside_zero_to_one_is_refused():
    local = _random_pose(np.random.default_rng(3), 2)
    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(UsageError):
            cf.follow_chest(local, cf._globals(local)[:, 9], bad)
    assert cf._shares("0.25,0.5") == [0.25, 0.5]
    for bad in ("0", "1.5", "x", ""):
        with pytest.raises(Exception):
            cf._shares(bad)


def test_a_spread_sets_how_far_each_spine_joint_turns():
    rng = np.random.default_rng(4)
    local = _random_pose(rng)
    off = rng.uniform(3.0, 40.0, size=len(local))
    chest = _chest_off(rng, local, off)
    out = cf.follow_chest(local, chest, 0.5, spread=cf.SPREADS["half each of spine1 and spine2"])
    g0, g1 = cf._globals(local), cf._globals(out)
    np.testing.assert_allclose(_angle(g0[:, 3], g1[:, 3]), 0.5 * off * 0.5, atol=1e-4)
    np.testing.assert_allclose(_angle(g0[:, 6], g1[:, 6]), 0.5 * off, atol=1e-4)
    np.testing.assert_allclose(_angle(g1[:, 9], chest), 0.5 * off, atol=1e-4)
    # spine3 keeps its bend from spine2, as in the motion the network learnt from
    assert _angle(local[:, 9], out[:, 9]).max() < 1e-4
    assert _angle(local[:, 3], out[:, 3]).min() > 0.1
    for bad in ((0.7, 0.5), (-0.1, 0.5), (0.5, 1.2)):
        with pytest.raises(UsageError):
            cf.follow_chest(local, chest, 0.5, spread=bad)


def test_the_numpy_rule_spreads_the_turn_as_the_engine_does():
    import re
    from training.dataset import REPO
    header = (REPO / "Packages/com.mocap.imu/Native~/src/pose/chest_follow.h").read_text()
    parts = {}
    for name in ("SPINE1", "SPINE2"):
        m = re.search(rf"#define CHEST_FOLLOW_{name}_PART\s+\(?([0-9.]+)(?:\s*/\s*([0-9.]+))?\)?", header)
        assert m, name
        parts[name] = float(m.group(1)) / (float(m.group(2)) if m.group(2) else 1.0)
    assert (parts["SPINE1"], parts["SPINE2"]) == pytest.approx(cf.ENGINE_SPREAD, abs=1e-12)
