import numpy as np
import pytest

from training import sensors as se
from training import skeleton as sk


def test_contract_names_and_parents():
    assert len(sk.JOINT_NAMES) == 24 and len(sk.PARENTS) == 24
    assert sk.PARENTS[0] == -1
    assert all(0 <= p < j for j, p in enumerate(sk.PARENTS) if j > 0)
    # spot checks against the contract table
    byname = dict(zip(sk.JOINT_NAMES, sk.PARENTS))
    assert sk.JOINT_NAMES[byname["left_wrist"]] == "left_elbow"
    assert sk.JOINT_NAMES[byname["head"]] == "neck"
    assert sk.JOINT_NAMES[byname["left_collar"]] == "spine3"
    assert sk.JOINT_NAMES[byname["right_foot"]] == "right_ankle"
    assert [sk.JOINT_NAMES[j] for j in se.sensor_joints()] == ["pelvis", "left_wrist", "right_wrist",
                                                             "left_knee", "right_knee", "head"]
    assert [sk.JOINT_NAMES[j] for j in sk.FOOT_JOINTS] == ["left_foot", "right_foot"]


def test_default_offsets_tpose_geometry():
    o = sk.DEFAULT_OFFSETS
    assert o.shape == (24, 3)
    assert 0.91 <= o[0, 1] <= 0.95                                   # pelvis above the sole
    g, p = sk.forward_kinematics(np.tile(np.eye(3), (24, 1, 1)), o[0], o)
    names = sk.JOINT_NAMES
    P = dict(zip(names, p))
    # left is +X, mirror symmetric
    assert P["left_hip"][0] > 0 and P["left_wrist"][0] > 0.6
    for j, n in enumerate(names):
        if n.startswith("left_"):
            m = P["right_" + n[5:]]
            assert np.allclose(m, P[n] * [-1, 1, 1])
    # arms straight along +-X at shoulder height
    for side in ("left", "right"):
        arm = np.array([P[f"{side}_{k}"] for k in ("shoulder", "elbow", "wrist", "hand")])
        assert np.allclose(arm[:, 1], arm[0, 1]) and np.allclose(arm[:, 2], 0)
    # feet: sole at y = 0, toes forward (+Z)
    assert P["left_ankle"][1] == pytest.approx(sk.ANKLE_HEIGHT)
    assert P["left_foot"][2] > 0.1
    # plausible adult: head joint ~1.5-1.6 m, arm span ~1.7 m
    assert 1.5 < P["head"][1] < 1.6
    assert 1.6 < P["left_hand"][0] - P["right_hand"][0] < 1.8
    assert sk.leg_height() == pytest.approx(0.87)


def test_forward_kinematics_matches_loop(rng):
    T = 5
    loc = sk.random_rotations(T * 24, rng).reshape(T, 24, 3, 3)
    root = rng.normal(size=(T, 3))
    g, p = sk.forward_kinematics(loc, root, sk.DEFAULT_OFFSETS)
    for t in range(T):
        gg = [None] * 24
        pp = [None] * 24
        for j in range(24):
            q = sk.PARENTS[j]
            if q < 0:
                gg[j], pp[j] = loc[t, j], root[t]
            else:
                gg[j] = gg[q] @ loc[t, j]
                pp[j] = pp[q] + gg[q] @ sk.DEFAULT_OFFSETS[j]
        assert np.allclose(g[t], np.array(gg)) and np.allclose(p[t], np.array(pp))
    assert np.allclose(sk.global_to_local(g), loc)


@pytest.mark.parametrize("order", ["XYZ", "ZXY", "ZYX", "YXZ", "XZY", "YZX"])
def test_euler_roundtrip_and_convention(order, rng):
    R = sk.random_rotations(500, rng)
    assert np.allclose(sk.euler_to_rot(sk.rot_to_euler(R, order), order), R, atol=1e-9)
    lock = sk.euler_to_rot(np.array([[30.0, 90.0, 0.0], [10.0, -90.0, 20.0]]), order)
    assert np.allclose(sk.euler_to_rot(sk.rot_to_euler(lock, order), order), lock, atol=1e-9)
    a = np.array([10.0, 20.0, 30.0])
    expect = sk.rot_axis(order[0], np.radians(10)) @ sk.rot_axis(order[1], np.radians(20)) @ \
        sk.rot_axis(order[2], np.radians(30))
    assert np.allclose(sk.euler_to_rot(a, order), expect)


def test_quaternions(rng):
    R = sk.random_rotations(1000, rng)
    q = sk.quat_from_rot(R)
    assert np.allclose(np.linalg.norm(q, axis=-1), 1) and np.all(q[:, 0] >= 0)
    assert np.allclose(sk.rot_from_quat(q), R, atol=1e-12)
    assert np.allclose(sk.rot_from_quat(-q), R)
    half = sk.rot_axis("z", np.pi)                         # 180 deg: w = 0 branch
    assert np.allclose(sk.rot_from_quat(sk.quat_from_rot(half)), half)
    assert np.allclose(sk.rot_from_quat(sk.quat_mul(sk.quat_from_rot(R[:5]), sk.quat_from_rot(R[5:10]))),
                       R[:5] @ R[5:10])


def test_quaternions_from_every_branch_in_any_shape(rng):
    # near 180 deg about x, y, z (the m00, m11, m22 branches) and small turns (the trace branch),
    # mixed in one stack of any leading shape: each element takes its own branch
    turns = [sk.rot_axis(a, np.pi - 0.1) for a in "xyz"] + [sk.rot_axis("x", 0.1)]
    stack = np.stack(turns * 3 + list(sk.random_rotations(12, rng))).reshape(2, 3, 4, 3, 3)
    q = sk.quat_from_rot(stack)
    assert q.shape == (2, 3, 4, 4) and np.all(q[..., 0] >= 0)
    assert np.allclose(sk.rot_from_quat(q), stack, atol=1e-12)
    assert np.allclose(np.abs(q[0, 0, :3, 1:]), np.eye(3) * np.cos(0.05), atol=1e-12)   # the axis, w small
    assert sk.quat_from_rot(np.eye(3)).shape == (4,) and sk.quat_from_rot(np.zeros((0, 3, 3))).shape == (0, 4)


def test_slerp():
    a = sk.rot_axis("y", 0.2)
    b = sk.rot_axis("y", 1.0)
    assert np.allclose(sk.slerp_rot(a, b, 0.0), a) and np.allclose(sk.slerp_rot(a, b, 1.0), b)
    assert np.allclose(sk.slerp_rot(a, b, 0.25), sk.rot_axis("y", 0.4))
    # shortest path across the quaternion sign flip
    c, d = sk.rot_axis("x", 3.0), sk.rot_axis("x", -3.0)
    assert sk.rotation_angle(np.swapaxes(c, -1, -2) @ sk.slerp_rot(c, d, 0.5)) == pytest.approx(np.pi - 3.0, abs=1e-9)


def test_rot6d_and_helpers(rng):
    R = sk.random_rotations(200, rng)
    r6 = sk.matrix_to_rot6d(R)
    assert r6.shape == (200, 6) and np.allclose(r6[:, :3], R[:, :, 0])
    assert np.allclose(sk.rot6d_to_matrix(r6), R)
    noisy = sk.rot6d_to_matrix(r6 + 0.05 * rng.normal(size=r6.shape))
    assert np.allclose(noisy @ np.swapaxes(noisy, -1, -2), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(noisy), 1)
    a, b = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    Q = sk.rotation_between(a, b)
    assert np.allclose(np.einsum("nij,nj->ni", Q, a / np.linalg.norm(a, axis=1, keepdims=True)),
                       b / np.linalg.norm(b, axis=1, keepdims=True))
    anti = sk.rotation_between(np.array([1.0, 0, 0]), np.array([-1.0, 0, 0]))
    assert np.allclose(anti @ [1, 0, 0], [-1, 0, 0])
    aa = rng.normal(size=(20, 3))
    assert np.allclose(sk.rot_to_axis_angle(sk.axis_angle_to_rot(aa * 0.5)), aa * 0.5)
    assert np.degrees(sk.rotation_angle(sk.rot_axis("z", np.radians(1e-4)))) == pytest.approx(1e-4, rel=1e-6)


def test_wrist_sensors_follow_the_forearm_and_its_twist_not_the_hand_bend(rng):
    """A wrist strap turns with the forearm and with pronation, not with the hand's flexion."""
    T = 50
    local = np.broadcast_to(np.eye(3), (T, 24, 3, 3)).copy()
    local[:, 16] = sk.random_rotations(T, rng, max_angle=1.5)          # upper arm anywhere
    local[:, 18] = sk.rot_axis("y", rng.uniform(0, 2.2, T))           # elbow flexion
    twist = rng.uniform(-1.2, 1.2, T)
    # a pure swing (axis in the Y-Z plane: flexion and sideways bend together, no twist)
    bend_axis = np.stack([np.zeros(T), rng.uniform(-0.5, 0.5, T), rng.uniform(-1.0, 1.0, T)], -1)
    bend = sk.axis_angle_to_rot(bend_axis)
    local[:, 20] = bend @ sk.rot_axis("x", twist)                     # swing times twist
    g, _ = sk.forward_kinematics(local, np.zeros((T, 3)))
    ori = se.sensor_bone_orientations(g, local, "forearm")
    assert ori.shape == (T, 6, 3, 3)
    expected = g[:, 18] @ sk.rot_axis("x", twist)
    np.testing.assert_allclose(ori[:, 1], expected, atol=1e-9)
    # the sensor points along the forearm, whatever the hand does
    np.testing.assert_allclose(ori[:, 1, :, 0], g[:, 18, :, 0], atol=1e-9)
    assert np.degrees(sk.angle_between_rots(ori[:, 1], g[:, 20])).mean() > 5.0
    # a pure twist of the wrist turns the sensor exactly as the hand
    local[:, 20] = sk.rot_axis("x", twist)
    g, _ = sk.forward_kinematics(local, np.zeros((T, 3)))
    np.testing.assert_allclose(se.sensor_bone_orientations(g, local, "forearm")[:, 1], g[:, 20], atol=1e-9)
    # the other sensors report their own bones; the right wrist is at rest, so it is its forearm
    np.testing.assert_allclose(ori[:, [0, 3, 4, 5]], g[:, [0, 4, 5, 15]])
    np.testing.assert_allclose(ori[:, 2], g[:, 19], atol=1e-12)
    # on the back of the hands (the default, the shipped model's placement) they report the hands
    np.testing.assert_allclose(se.sensor_bone_orientations(g, local), g[:, se.sensor_joints()])
    with pytest.raises(ValueError, match="wrist sensor place"):
        se.sensor_bones("elbow")


def test_twist_about_x_splits_swing_and_twist(rng):
    a = rng.uniform(-3.0, 3.0, 200)
    swing_axis = np.stack([np.zeros(200), rng.normal(size=200), rng.normal(size=200)], -1)
    swing_axis /= np.linalg.norm(swing_axis, axis=-1, keepdims=True)
    swing = sk.axis_angle_to_rot(swing_axis * rng.uniform(0, 1.4, 200)[:, None])
    tw = sk.twist_about_x(swing @ sk.rot_axis("x", a))
    np.testing.assert_allclose(tw, sk.rot_axis("x", a), atol=1e-9)
    np.testing.assert_allclose(sk.twist_about_x(swing), np.broadcast_to(np.eye(3), (200, 3, 3)), atol=1e-9)


def test_segment_table_is_the_headers_enum_and_sets_the_default_sensors():
    # The engine's table (segments.def) and its public header's enum must agree row for row;
    # training reads the table, so a drifted header would feed a model other sensors than it names.
    import re
    from pathlib import Path
    header = (Path(__file__).resolve().parents[2] / "Packages" / "com.mocap.imu" / "Native~" / "include"
              / "mocap_imu.h").read_text()
    enum = {name: int(v) for name, v in re.findall(r"MOCAP_SEGMENT_([A-Z0-9_]+)\s*=\s*(\d+)", header)}
    assert enum == {s.enum: s.id for s in se.SEGMENTS}
    assert [s.name for s in se.SEGMENTS] == [e.lower() for e, _ in sorted(enum.items(), key=lambda kv: kv[1])]
    # the default set is contract 1's six, in the contract's order, on the contract's joints
    assert se.DEFAULT_SENSORS == ("pelvis", "left_wrist", "right_wrist", "left_shin", "right_shin", "head")
    assert [sk.JOINT_NAMES[j] for j in se.sensor_joints()] == ["pelvis", "left_wrist", "right_wrist",
                                                               "left_knee", "right_knee", "head"]
