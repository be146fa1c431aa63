"""training/rarity.py: pose descriptors that ignore heading, and clip rarity that singles out the
clip whose poses no other clip has."""
import numpy as np
import pytest

from training import procedural, rarity
from training import skeleton as sk


def _yawed(motion, degrees):
    """The same motion turned about the vertical: the pelvis's global rotation and the path."""
    a = np.radians(degrees)
    yaw = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    rot = motion.local_rot.copy()
    rot[:, 0] = yaw @ rot[:, 0]
    return sk.Motion(motion.name, motion.subject, motion.fps, rot, motion.root_pos @ yaw.T, motion.offsets)


def test_descriptors_ignore_heading_and_see_the_pose():
    walk = procedural.make_motion("walk", 4.0, seed=0)
    d = rarity.pose_descriptors(walk, stride=5)
    assert d.shape == (len(walk.local_rot[::5]), 18) and np.isfinite(d).all()
    np.testing.assert_allclose(rarity.pose_descriptors(_yawed(walk, 70), stride=5), d, atol=1e-5)
    # a squat brings the feet up towards the pelvis: their height below it (columns 13, 16) shrinks
    squat = rarity.pose_descriptors(procedural.make_motion("squat", 4.0, seed=0), stride=5)
    assert squat[:, [13, 16]].max() > d[:, [13, 16]].max() + 0.1
    # the floor's height is not part of the pose
    lifted = sk.Motion(walk.name, walk.subject, walk.fps, walk.local_rot, walk.root_pos + [0, 1.5, 0], walk.offsets)
    np.testing.assert_array_equal(rarity.pose_descriptors(lifted, stride=5), d)


def test_descriptors_ignore_body_size():
    walk = procedural.make_motion("walk", 2.0, seed=0)
    tall = sk.Motion(walk.name, walk.subject, walk.fps, walk.local_rot, walk.root_pos * 1.2, walk.offsets * 1.2)
    np.testing.assert_allclose(rarity.pose_descriptors(tall), rarity.pose_descriptors(walk), atol=1e-6)


def test_the_clip_with_unshared_poses_is_the_rarest_and_the_mean_is_one():
    motions = [procedural.make_motion("walk", 5.0, seed=i) for i in range(6)] + \
              [procedural.make_motion("squat", 3.0, seed=7)]
    r = rarity.clip_rarity(motions, max_k=8, stride=5)
    assert r.shape == (7,) and np.isfinite(r).all() and (r > 0).all()
    assert int(np.argmax(r)) == 6 and r[6] > 2 * r[:6].max()
    lengths = np.array([m.num_frames for m in motions], np.float64)
    assert (r * lengths).sum() / lengths.sum() == pytest.approx(1.0)
    np.testing.assert_array_equal(rarity.clip_rarity(motions, max_k=8, stride=5), r)   # deterministic


def test_kmeans_separates_two_blobs():
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(0, 0.1, (50, 2)), rng.normal(5, 0.1, (30, 2))])
    labels = rarity.kmeans(x, 2, np.random.default_rng(1))
    assert len(set(labels[:50])) == 1 and len(set(labels[50:])) == 1 and labels[0] != labels[-1]
