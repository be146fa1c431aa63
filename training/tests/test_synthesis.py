"""Virtual IMU synthesis (training/synthesis.py)."""
import numpy as np
import pytest

from training import procedural, skeleton as sk, synthesis as sy


def _static_motion(T=120, root=(0.0, 0.93, 0.0)):
    local = np.broadcast_to(np.eye(3, dtype=np.float32), (T, 24, 3, 3)).copy()
    rp = np.tile(np.asarray(root, np.float32), (T, 1))
    return sk.Motion("static", 0, 60.0, local, rp, sk.DEFAULT_OFFSETS.astype(np.float32))


def test_static_pose_has_zero_acceleration_and_planted_feet():
    s = sy.synthesize(_static_motion())
    assert s.imu_orientation.shape == (120, 6, 3, 3) and s.imu_acceleration.shape == (120, 6, 3)
    assert np.allclose(s.imu_orientation, np.eye(3), atol=1e-6)
    assert np.abs(s.imu_acceleration).max() < 1e-4
    assert np.abs(s.root_velocity).max() < 1e-5
    assert s.foot_contact.min() == 1.0
    assert s.positions.shape == (120, 24, 3) and s.local_rot.shape == (120, 24, 3, 3)


def test_constant_acceleration_is_recovered_exactly_everywhere():
    T, a = 90, np.array([1.5, -0.5, 2.0])
    m = _static_motion(T)
    t = np.arange(T) / 60.0
    m.root_pos = (m.root_pos + 0.5 * a * t[:, None] ** 2).astype(np.float32)
    s = sy.synthesize(m)
    # second difference of a quadratic is exact (incl. the shrunken k at the ends), float32 data
    assert np.allclose(s.imu_acceleration, a, atol=0.05)
    assert np.allclose(s.root_velocity[1:-1], a * t[1:-1, None], atol=1e-3)
    assert s.foot_contact[T // 2:].max() == 0.0     # feet moving fast: no contact


def test_rotating_pelvis_gives_centripetal_acceleration_of_the_sensor_offset():
    T, w = 240, 2.0                                   # rad/s about Y
    m = _static_motion(T)
    ang = w * np.arange(T) / 60.0
    ry = np.stack([sy._ry(x) for x in ang]).astype(np.float32)
    for j in range(24):
        if j == 0:
            m.local_rot[:, 0] = ry
    s = sy.synthesize(m)
    off = sy.sensor_offsets(m.offsets)[0]
    r = np.hypot(off[0], off[2])
    acc = s.imu_acceleration[10:-10, 0]
    mag = np.linalg.norm(acc[:, [0, 2]], axis=-1)
    # centripetal w^2 r (the +-4 frame difference underestimates by ~sinc^2: 0.5 %)
    assert np.allclose(mag, w * w * r, rtol=0.02)
    # points from the sensor towards the rotation axis
    pos = s.sensor_position[10:-10, 0]
    inward = -(pos[:, [0, 2]] - s.root_pos[10:-10][:, [0, 2]])
    assert np.all((acc[:, [0, 2]] * inward).sum(-1) > 0)


def test_sensor_placement_is_on_the_stated_sides():
    off = sy.sensor_offsets(sk.DEFAULT_OFFSETS)
    assert off[0, 2] < 0                               # pelvis on the lower back
    assert off[3, 2] > 0 and off[4, 2] > 0             # shins: front
    assert np.isclose(off[3, 1], 0.4 * sk.DEFAULT_OFFSETS[7, 1])
    assert off[1, 0] < 0 < off[2, 0]                   # wrists: up the forearm
    assert off[5, 1] > 0.1                             # head: above the ears


def test_augmentation_is_seeded_and_bounded():
    m = procedural.make_motion("walk", seconds=3.0, seed=3)
    unmirrored = sy.Augmentation(mirror=0.0, speed=(1.0, 1.0))
    a = sy.synthesize(m, np.random.default_rng(7), unmirrored)
    b = sy.synthesize(m, np.random.default_rng(7), unmirrored)
    c = sy.synthesize(m, np.random.default_rng(8), unmirrored)
    assert np.array_equal(a.imu_acceleration, b.imu_acceleration)
    assert not np.array_equal(a.imu_acceleration, c.imu_acceleration)
    scale = a.offsets[4, 1] / m.offsets[4, 1]
    assert 0.9 <= scale <= 1.1
    clean = sy.synthesize(m)
    nohead = sy.synthesize(m, np.random.default_rng(7), sy.Augmentation(heading=False, mirror=0.0, speed=(1.0, 1.0)))
    # orientation errors: a few degrees (mounting + drift + noise), never more than ~15 deg
    # (drop-outs hold an older sample, so compare the median)
    ang = np.degrees(sk.angle_between_rots(nohead.imu_orientation, clean.imu_orientation))
    assert 0.3 < np.median(ang) < 8.0
    # local rotations below the root are untouched by augmentation
    assert np.allclose(a.local_rot[:, 1:], clean.local_rot[:, 1:], atol=1e-6)


def test_heading_augmentation_is_a_pure_yaw():
    m = procedural.make_motion("turn", seconds=3.0, seed=1)
    aug = sy.Augmentation(scale=(1.0, 1.0), mounting_deg=0, heading_drift_deg=0, orientation_noise_deg=0,
                          acc_noise=0, acc_bias=0, drop_rate=0, mirror=0.0,
                          speed=(1.0, 1.0))
    a = sy.synthesize(m, np.random.default_rng(2), aug)
    c = sy.synthesize(m)
    # same accelerations up to one rotation about Y: norms and vertical components match
    assert np.allclose(np.linalg.norm(a.imu_acceleration, axis=-1), np.linalg.norm(c.imu_acceleration, axis=-1), atol=1e-3)
    assert np.allclose(a.imu_acceleration[..., 1], c.imu_acceleration[..., 1], atol=1e-3)
    assert np.allclose(a.foot_contact, c.foot_contact)
    assert not np.allclose(a.imu_acceleration[..., 0], c.imu_acceleration[..., 0], atol=1e-2)


def test_walk_contacts_alternate():
    s = sy.synthesize(procedural.make_motion("walk", seconds=6.0, seed=0))
    frac = s.foot_contact.mean(0)
    assert np.all((frac > 0.2) & (frac < 0.9))
    feet = s.positions[:, sk.FOOT_JOINTS]
    v = np.linalg.norm(np.gradient(feet, axis=0) * 60, axis=-1)
    assert v[s.foot_contact > 0].mean() < 0.2 < v[s.foot_contact == 0].mean()
    assert np.abs(s.root_velocity[:, [0, 2]]).max() > 0.5


def test_raw_specific_force_at_rest_and_with_mounting():
    m = _static_motion(30)
    mount = sk.random_rotations(6, np.random.default_rng(0))
    raw = sy.raw_sensor_signals(m, mounting=mount)
    f = raw["specific_force_g"]
    assert np.allclose(np.linalg.norm(f, axis=-1), 1.0, atol=1e-6)
    # the reading is gravity's reaction (up, model +Y) expressed in each sensor frame
    up = np.einsum("sba,b->sa", mount, np.array([0.0, 1.0, 0.0]))
    assert np.allclose(f[5], up, atol=1e-6)
    assert np.abs(raw["angular_rate"]).max() < 1e-6


def test_raw_angular_rate_of_a_yaw_spin():
    m = _static_motion(60)
    ang = 1.5 * np.arange(60) / 60.0
    m.local_rot[:, 0] = np.stack([sy._ry(x) for x in ang])
    raw = sy.raw_sensor_signals(m)
    assert np.allclose(raw["angular_rate"][:, 0], [0.0, 1.5, 0.0], atol=1e-4)


MIRROR_ONLY = dict(scale=(1.0, 1.0), heading=False, mounting_deg=0, heading_drift_deg=0,
                   orientation_noise_deg=0, acc_noise=0, acc_bias=0, drop_rate=0, speed=(1.0, 1.0))


def test_mirrored_motion_is_the_reflection_with_sides_swapped():
    m = procedural.make_motion("mixed", seconds=3.0, seed=4)
    local, root, off = sk.mirror_motion(m.local_rot, m.root_pos, m.offsets)
    reflect = np.diag([-1.0, 1.0, 1.0])
    _, p = sk.forward_kinematics(m.local_rot, m.root_pos, m.offsets)
    _, pm = sk.forward_kinematics(local, root, off)
    # the mirrored left wrist is where the original right wrist was, reflected in x = 0
    assert np.allclose(pm, p[:, sk.MIRROR_JOINTS] @ reflect, atol=1e-5)
    assert not np.allclose(pm, p, atol=1e-2)          # the motion is not symmetric itself
    # still proper rotations, and mirroring twice gives the motion back
    assert np.allclose(np.linalg.det(local), 1.0, atol=1e-5)
    back = sk.mirror_motion(local, root, off)
    for x, y in zip(back, (m.local_rot, m.root_pos, m.offsets)):
        assert np.allclose(x, y, atol=1e-6)


def test_mirror_augmentation_swaps_the_sensors_of_both_sides():
    m = procedural.make_motion("walk", seconds=3.0, seed=2)
    plain = sy.synthesize(m)
    mirrored = sy.synthesize(m, np.random.default_rng(0), sy.Augmentation(**MIRROR_ONLY, mirror=1.0))
    never = sy.synthesize(m, np.random.default_rng(0), sy.Augmentation(**MIRROR_ONLY, mirror=0.0))
    reflect = np.diag([-1.0, 1.0, 1.0])
    swap = [0, 2, 1, 4, 3, 5]                         # sensor order: pelvis, wrists, shins, head
    assert np.allclose(mirrored.imu_acceleration, plain.imu_acceleration[:, swap] @ reflect, atol=1e-4)
    assert np.allclose(mirrored.imu_orientation, reflect @ plain.imu_orientation[:, swap] @ reflect, atol=1e-5)
    assert np.array_equal(mirrored.foot_contact, plain.foot_contact[:, ::-1])
    assert np.allclose(never.imu_acceleration, plain.imu_acceleration, atol=1e-5)


SPEED_ONLY = dict(MIRROR_ONLY, mirror=0.0)


def test_speed_augmentation_replays_the_motion_at_another_tempo():
    m = procedural.make_motion("walk", seconds=4.0, seed=2)
    clean = sy.synthesize(m)
    fast = sy.synthesize(m, np.random.default_rng(0), sy.Augmentation(**SPEED_ONLY | {"speed": (2.0, 2.0)}))
    slow = sy.synthesize(m, np.random.default_rng(0), sy.Augmentation(**SPEED_ONLY | {"speed": (0.5, 0.5)}))
    T = m.num_frames
    assert fast.num_frames == (T - 1) // 2 + 1 and slow.num_frames == 2 * (T - 1) + 1
    # twice the tempo: frame n is the original frame 2n, and the root moves twice as fast
    assert np.allclose(fast.local_rot, clean.local_rot[::2], atol=1e-5)
    assert np.allclose(fast.root_pos, clean.root_pos[::2], atol=1e-5)
    inner = slice(2, -2)
    assert np.allclose(fast.root_velocity[inner], 2.0 * clean.root_velocity[::2][inner], atol=0.05)
    # half the tempo: the original frames come back on the even frames, slerp in between
    assert np.allclose(slow.local_rot[::2], clean.local_rot, atol=1e-5)
    mid = sk.angle_between_rots(slow.local_rot[1::2], clean.local_rot[:-1])
    step = sk.angle_between_rots(clean.local_rot[1:], clean.local_rot[:-1])
    assert np.allclose(mid, step / 2, atol=1e-4)
    # accelerations follow the tempo (about 4x for 2x speed); contacts stay a walk's
    ratio = np.abs(fast.imu_acceleration).mean() / np.abs(clean.imu_acceleration).mean()
    assert 2.5 < ratio < 5.0
    assert 0.2 < fast.foot_contact.mean() < 0.9


def test_evaluation_inputs_keep_the_clip_timing():
    from training.evaluate import eval_augmentation
    m = procedural.make_motion("squat", seconds=3.0, seed=4)
    s = sy.synthesize(m, np.random.default_rng(1), eval_augmentation())
    assert s.num_frames == m.num_frames
    assert np.allclose(s.local_rot, m.local_rot, atol=1e-6)


def _two_clips():
    walk = procedural.make_motion("walk", seconds=4.0, seed=1, name="walk")
    arms = procedural.make_motion("arm_swing", seconds=3.0, seed=2, name="arms")
    return walk, arms


def _crop_start(clip, varied) -> int:
    """Where the varied clip's window starts in the clip, found from the root track (kept as is)."""
    T = varied.num_frames
    return int(np.argmin([np.abs(clip.root_pos[a:a + T] - varied.root_pos).max()
                          for a in range(clip.num_frames - T + 1)]))


def _window(clip, start, T):
    return sk.Motion("w", 0, clip.fps, clip.local_rot[start:start + T], clip.root_pos[start:start + T],
                     clip.offsets)


def _turned_deg(clip, varied):
    """(T,24) angle in degrees by which each joint's local rotation was turned."""
    rel = np.swapaxes(clip.local_rot, -1, -2) @ varied.local_rot
    return np.rad2deg(np.linalg.norm(sk.rot_to_axis_angle(rel), axis=-1))


def test_arm_swap_takes_the_donors_arms_and_keeps_the_rest():
    walk, arms = _two_clips()
    aug = sy.Augmentation(arm_swap=1.0)
    v = sy.vary_motion(walk, np.random.default_rng(3), aug, [arms])
    T = v.num_frames
    assert T == arms.num_frames < walk.num_frames          # cropped to the shorter donor
    # the crop is a window of the original: find its start from the root track
    start = _crop_start(walk, v)
    assert np.array_equal(v.root_pos, walk.root_pos[start:start + T])
    body = [j for j in range(24) if j not in sy.ARM_JOINTS]
    assert np.array_equal(v.local_rot[:, body], walk.local_rot[start:start + T, body])
    assert np.array_equal(v.local_rot[:, sy.ARM_JOINTS], arms.local_rot[:, sy.ARM_JOINTS])
    # the sensors follow the new arms: the wrists move as the donor's arms on the walker's body
    s, w = sy.synthesize(v), sy.synthesize(_window(walk, start, T))
    assert np.abs(s.imu_orientation[:, 1:3] - w.imu_orientation[:, 1:3]).max() > 0.1
    assert np.allclose(s.imu_orientation[:, [0, 3, 4, 5]], w.imu_orientation[:, [0, 3, 4, 5]], atol=1e-6)
    assert np.array_equal(s.foot_contact, w.foot_contact)


def test_trunk_swap_takes_the_donors_upper_body_on_the_clips_legs():
    walk, arms = _two_clips()
    v = sy.vary_motion(walk, np.random.default_rng(3), sy.Augmentation(trunk_swap=1.0), [arms])
    T, start = v.num_frames, _crop_start(walk, v)
    upper = sy.UPPER_BODY_JOINTS
    assert set(sy.ARM_JOINTS) < set(upper) and {3, 6, 9, 12, 15} <= set(upper)
    lower = [j for j in range(24) if j not in upper]
    assert lower == [0, 1, 2, 4, 5, 7, 8, 10, 11]
    assert np.array_equal(v.local_rot[:, lower], walk.local_rot[start:start + T, lower])
    assert np.array_equal(v.local_rot[:, upper], arms.local_rot[:, upper])
    # the head sensor now follows the donor's trunk; the pelvis and shin sensors and contacts do not
    s, w = sy.synthesize(v), sy.synthesize(_window(walk, start, T))
    assert np.allclose(s.imu_orientation[:, [0, 3, 4]], w.imu_orientation[:, [0, 3, 4]], atol=1e-6)
    assert np.array_equal(s.foot_contact, w.foot_contact)


def test_arm_jitter_turns_only_the_shoulders_slowly_by_about_sigma():
    walk, _ = _two_clips()
    aug = sy.Augmentation(arm_jitter_deg=8.0)
    v = sy.vary_motion(walk, np.random.default_rng(4), aug)
    ang = _turned_deg(walk, v)
    others = [j for j in range(24) if j not in sy.SHOULDER_JOINTS]
    assert ang[:, others].max() < 1e-3
    assert 3.0 < ang[:, sy.SHOULDER_JOINTS].mean() < 25.0
    assert np.abs(np.diff(ang[:, sy.SHOULDER_JOINTS], axis=0)).max() < 1.0    # slow: < 1 deg/frame


def test_spine_jitter_bends_only_the_spine_and_moves_the_upper_sensors():
    walk, _ = _two_clips()
    v = sy.vary_motion(walk, np.random.default_rng(6), sy.Augmentation(spine_jitter_deg=6.0))
    ang = _turned_deg(walk, v)
    others = [j for j in range(24) if j not in sy.SPINE_JOINTS]
    assert ang[:, others].max() < 1e-3
    assert 2.0 < ang[:, sy.SPINE_JOINTS].mean() < 20.0
    assert np.abs(np.diff(ang[:, sy.SPINE_JOINTS], axis=0)).max() < 1.0
    # the head and wrist sensors ride on the bent trunk; pelvis, shins and contacts do not move
    s, w = sy.synthesize(v), sy.synthesize(walk)
    assert np.abs(s.imu_orientation[:, [1, 2, 5]] - w.imu_orientation[:, [1, 2, 5]]).max() > 0.05
    assert np.allclose(s.imu_orientation[:, [0, 3, 4]], w.imu_orientation[:, [0, 3, 4]], atol=1e-6)
    assert np.array_equal(s.foot_contact, w.foot_contact)


def test_motion_variety_is_off_by_default_and_for_evaluation():
    walk, arms = _two_clips()
    rng = np.random.default_rng(5)
    assert sy.vary_motion(walk, rng, sy.Augmentation(), [arms]) is walk
    assert sy.vary_motion(walk, rng, None, [arms]) is walk
