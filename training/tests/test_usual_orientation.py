"""training usual-orientation: the hands' and head's usual orientation with the pelvis' heading
taken out, and the engine's copy of it.

Clips whose body turns while each hand and the head keep one orientation relative to the turned
body (with a wobble about it) must give back that orientation whatever the turning; the pelvis'
heading must be read as the engine reads it, tilted or not; and solver.c must hold rotations in
the form the command prints."""
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from training import skeleton as sk, usual_orientation as uo
from training.errors import UsageError

SOLVER_C = Path(__file__).resolve().parents[2] / "Packages/com.mocap.imu/Native~/src/pose/solver.c"


def _ry(angle):
    return Rotation.from_euler("y", angle).as_matrix()


def _turning_clip(seed, left, right, head=np.eye(3), frames=600):
    """A body turning about the vertical (its pelvis also pitching), each wrist at left / right
    and the head at head relative to the turned body, wobbling about it by up to 10 deg either
    way."""
    rng = np.random.default_rng(seed)
    heading = np.cumsum(rng.normal(0.0, 0.05, frames)) + rng.uniform(-np.pi, np.pi)
    turned = _ry(heading)                                         # (T, 3, 3)
    glob = np.repeat(turned[:, None], sk.NUM_JOINTS, axis=1).copy()
    glob[:, 0] = turned @ Rotation.from_euler("x", rng.uniform(-0.5, 0.5, frames)).as_matrix()
    for joint, usual in ((20, left), (21, right), (15, head)):
        wobble = Rotation.from_rotvec(np.radians(10.0) * np.stack(
            [np.sin(np.arange(frames) * 0.1 + joint), np.cos(np.arange(frames) * 0.13), np.zeros(frames)], -1))
        glob[:, joint] = turned @ usual @ wobble.as_matrix()
    local = sk.global_to_local(glob).astype(np.float32)
    return sk.Motion(f"turning_{seed}", 1, 60.0, local, np.zeros((frames, 3), np.float32),
                     np.asarray(sk.DEFAULT_OFFSETS, np.float32))


def test_the_usual_orientation_is_found_whatever_the_body_turns():
    left = Rotation.from_euler("zyx", [-70, 20, 10], degrees=True).as_matrix()
    right = Rotation.from_euler("zyx", [75, -30, 5], degrees=True).as_matrix()
    head = Rotation.from_euler("x", 12, degrees=True).as_matrix()
    usual = uo.usual_orientations([_turning_clip(s, left, right, head) for s in range(3)], frame_step=3)
    for name, want in (("left_wrist", left), ("right_wrist", right), ("head", head)):
        rotation, spread = usual[name]
        # the wobble is symmetric about the usual orientation, so the mean is it
        assert np.degrees(Rotation.from_matrix(rotation.T @ want).magnitude()) < 0.5, name
        assert np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-9)
        assert spread.max() <= 1.0 + 1e-9 and spread.min() > 0.9   # a hand that barely moves


def test_a_hand_that_points_everywhere_has_a_small_spread():
    rng = np.random.default_rng(4)
    clip = _turning_clip(5, np.eye(3), np.eye(3), frames=3000)
    glob, _ = sk.forward_kinematics(clip.local_rot.astype(np.float64), clip.root_pos, clip.offsets)
    glob[:, 20] = Rotation.random(len(glob), random_state=rng).as_matrix()
    clip.local_rot[:] = sk.global_to_local(glob)
    _, spread = uo.usual_orientations([clip], frame_step=1)["left_wrist"]
    assert spread.max() < 0.1


def test_the_heading_is_read_as_the_engine_reads_it():
    # forward axis on the floor: the plain heading; pitched near vertical: the up axis decides
    for h in (-2.5, -0.3, 0.0, 1.2, 3.0):
        for pitch in (0.0, 0.6, 1.5, 1.8, -1.8):   # past 90 deg: bent over, read by the up axis
            pelvis = _ry(h) @ Rotation.from_euler("x", pitch).as_matrix()
            got = uo.heading_rotations(pelvis[None])[0]
            assert np.allclose(got, _ry(h), atol=1e-9), (h, pitch)


def test_no_clips_is_an_error():
    with pytest.raises(UsageError, match="no clips"):
        uo.usual_orientations([])


def test_the_engine_holds_the_rotations():
    text = SOLVER_C.read_text()
    for name in ("USUAL_LEFT_WRIST", "USUAL_RIGHT_WRIST", "USUAL_HEAD"):
        block = re.search(name + r"\[9\] = (\{.*?\});", text, re.S)
        assert block, f"solver.c has no {name}"
        values = [float(v) for v in re.findall(r"-?\d+\.\d+", block.group(1))]
        assert len(values) == 9, name
        m = np.asarray(values).reshape(3, 3)
        assert np.allclose(m @ m.T, np.eye(3), atol=2e-4), name
        assert np.linalg.det(m) == pytest.approx(1.0, abs=3e-4), name
        # the command prints in solver.c's format, so its output can replace these as they stand
        # (whether they are still today's means needs the CMU clips: run the command)
        assert uo.c_initialiser(m) == re.sub(r"\s+", " ", block.group(1)), name
