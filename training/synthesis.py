"""Virtual IMUs on a Motion: the inputs the calibrated engine feeds the model, and the targets
(owner: model).

Sensors ride on segments of the engine's table (sensors.py; default: the six of the default set,
in the table's order) at fixed offsets from the segment's joint, in the frame of the bone they
turn with (sensors.sensor_bones; bone frames are parallel to the model frame in the T-pose: X
left, Y up, Z forward):

| sensor | bone it turns with | offset (default proportions, scaled with the body) |
|---|---|---|
| pelvis | 0 pelvis | (0, +0.05, -0.11) m from the pelvis joint: on the lower back (sacrum / L5) |
| left / right wrist | 20 / 21 hand (`wrist="forearm"`: the forearm 18 / 19 with its twist) | (-/+0.03, +0.035, 0) m from the wrist joint (20 / 21): the back of the wrist (the top in a palms-down T-pose), 3 cm up the forearm |
| left / right shin | 4 / 5 knee | 40 % of the knee -> ankle bone, plus 5 cm forward: the front of the shin |
| head | 15 head (skull base) | (0, +0.13, 0) m: above the ears (headband) |
| chest | 9 spine3 | (0, +0.02, +0.10) m: on the sternum (a chest strap) |

* Orientation = global rotation of the sensor's bone (what the engine's T-pose calibration
  reports). The wrist sensors turn with the hand (a sensor on the back of the hand: the shipped
  model's placement) or, with `wrist="forearm"`, as a wrist strap does: with the forearm turned by
  the wrist joint's twist about the arm, following pronation but not the hand bending
  (sensors.sensor_bone_orientations). A mounting rotation only matters for the raw sensor
  signals (`raw_sensor_signals`).
* Acceleration = central second difference of the sensor's world position over +-k frames,
  (p[t+k] - 2 p[t] + p[t-k]) / (k dt)^2 with k = ACC_K = 4 at 60 Hz (+-67 ms, TIP's choice).
  The CMU clips are 24 fps resampled to 60 Hz by slerp, so positions are only piecewise smooth
  at the 60 Hz frame level: k = 1 would turn every source key into an acceleration spike, while
  +-4 frames spans more than three source frames and averages them out. The kernel is
  centred (no lag), like the instantaneous accelerometer reading. At the clip ends k shrinks.
  Gravity removed, model frame, m/s^2: exactly the engine's `bone_acceleration`.
* Targets: local joint rotations (joint 0 global), root (pelvis) velocity in the model frame
  (central difference, m/s), foot contact, joint positions (model frame, metres).
* Foot contact (per foot joint 10 / 11, the ball of the foot): speed below CONTACT_SPEED
  (0.25 m/s, central difference) AND height within CONTACT_HEIGHT (0.06 m) of the lowest foot
  (either foot) within +-CONTACT_WINDOW frames (0.5 s), which follows stairs and slopes.

Augmentation (training only, all draws from the given numpy Generator), see `Augmentation`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import skeleton as sk
from .sensors import DEFAULT_SENSORS, sensor_bone_orientations, sensor_joints, sensor_list

GRAVITY = 9.80665
ACC_K = 4
CONTACT_SPEED = 0.25
CONTACT_HEIGHT = 0.06
CONTACT_WINDOW = 30

PELVIS_SENSOR_OFFSET = (0.0, 0.05, -0.11)
WRIST_SENSOR_OFFSET = (0.03, 0.035, 0.0)     # x mirrored: towards the elbow
HEAD_SENSOR_OFFSET = (0.0, 0.13, 0.0)
CHEST_SENSOR_OFFSET = (0.0, 0.02, 0.10)
SHIN_FRACTION = 0.4
SHIN_FORWARD = 0.05


@dataclass
class Augmentation:
    """Training-time augmentation. Angles in degrees, accelerations in m/s^2."""
    scale: tuple = (0.9, 1.1)        # body scale U(a, b): offsets and root trajectory
    heading: bool = True             # random yaw of the whole clip, U(-180, 180)
    mounting_deg: float = 2.5        # per-axis sigma of a fixed per-sensor calibration error
                                     # (right-multiplied, bone frame; |error| ~ 4 deg on average)
    heading_drift_deg: float = 2.0   # fixed per-sensor yaw error of the sensor world, U(+-x)
    orientation_noise_deg: float = 0.3   # per-axis sigma per frame (|noise| ~ 0.5 deg)
    acc_noise: float = 0.1           # per-axis sigma per frame
    acc_bias: float = 0.1            # per-axis U(+-x) per sensor per sequence
    drop_rate: float = 0.005         # probability per sensor per frame that a drop-out starts
    drop_max_frames: int = 6         # drop-out length U{1..n} frames: the last sample is held
    mirror: float = 0.5              # probability that the clip is performed mirror-image
    speed: tuple = (0.8, 1.2)        # playback speed U(a, b): the same motion done faster or slower
    # Motion variety (applied by the trainer's batcher through `vary_motion`, before synthesis):
    arm_swap: float = 0.0            # probability that both arms move as in another clip
    arm_jitter_deg: float = 0.0      # per-axis sigma of a slowly varying offset of each shoulder
    spine_jitter_deg: float = 0.0    # the same for each of the three spine joints
    trunk_swap: float = 0.0          # probability that the whole upper body moves as in another clip


@dataclass
class Sample:
    name: str
    fps: float
    imu_orientation: np.ndarray      # (T,N,3,3) float32, bone -> model, N = len(sensors)
    imu_acceleration: np.ndarray     # (T,N,3) float32, m/s^2, model frame, gravity removed
    local_rot: np.ndarray            # (T,24,3,3) float32, joint 0 global
    root_velocity: np.ndarray        # (T,3) float32, m/s, model frame
    foot_contact: np.ndarray         # (T,2) float32 in {0, 1}
    positions: np.ndarray            # (T,24,3) float32, model frame
    offsets: np.ndarray              # (24,3) float32 (after body scaling)
    root_pos: np.ndarray             # (T,3) float32
    sensor_position: np.ndarray      # (T,N,3) float32
    sensors: tuple = DEFAULT_SENSORS # segment names, the order of the IMU arrays

    @property
    def num_frames(self) -> int:
        return int(self.local_rot.shape[0])


# ------------------------------------------------------------------------------ helpers
def _ry(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _sensor_offset(name: str, o: np.ndarray, s: float) -> np.ndarray:
    """Where the sensor of segment `name` sits, in its bone frame, from its joint (module
    docstring's table); o: the skeleton's offsets, s: its scale against the default body."""
    wx, wy, wz = WRIST_SENSOR_OFFSET
    if name == "pelvis":
        return np.asarray(PELVIS_SENSOR_OFFSET) * s
    if name == "left_wrist":
        return np.array([-wx, wy, wz]) * s        # left arm points +X: the elbow is at -X
    if name == "right_wrist":
        return np.array([wx, wy, wz]) * s
    if name in ("left_shin", "right_shin"):
        ankle = sk.JOINT_NAMES.index(name.replace("shin", "ankle"))
        return SHIN_FRACTION * o[ankle] + np.array([0.0, 0.0, SHIN_FORWARD * s])
    if name == "head":
        return np.asarray(HEAD_SENSOR_OFFSET) * s
    if name == "chest":
        return np.asarray(CHEST_SENSOR_OFFSET) * s
    raise ValueError(f"segment {name!r} has no sensor placement in synthesis.py (_sensor_offset)")


def sensor_offsets(offsets, sensors=DEFAULT_SENSORS) -> np.ndarray:
    """(N,3) positions of the sensors (segment names) in their bone frames for a skeleton with
    these offsets."""
    o = np.asarray(offsets, dtype=np.float64)
    s = sk.leg_height(o) / sk.leg_height(sk.DEFAULT_OFFSETS)
    return np.stack([_sensor_offset(n, o, s) for n in sensor_list(sensors)])


def second_difference(pos: np.ndarray, fps: float, k: int = ACC_K) -> np.ndarray:
    """Acceleration (T,...) of positions (T,...) by a centred second difference over +-k frames;
    k shrinks at the ends (to 1; the first and last frame copy their neighbour)."""
    pos = np.asarray(pos, dtype=np.float64)
    T = pos.shape[0]
    acc = np.zeros_like(pos)
    if T < 3:
        return acc
    dt = 1.0 / fps
    t = np.arange(T)
    kk = np.minimum(np.minimum(t, T - 1 - t), k)
    for kv in range(1, k + 1):
        idx = np.nonzero(kk == kv)[0]
        if idx.size:
            acc[idx] = (pos[idx + kv] - 2.0 * pos[idx] + pos[idx - kv]) / (kv * dt) ** 2
    acc[0] = acc[1]
    acc[-1] = acc[-2]
    return acc


def central_velocity(pos: np.ndarray, fps: float) -> np.ndarray:
    pos = np.asarray(pos, dtype=np.float64)
    if pos.shape[0] < 2:
        return np.zeros_like(pos)
    return np.gradient(pos, axis=0) * fps


def foot_contact_labels(positions: np.ndarray, fps: float) -> np.ndarray:
    """(T,24,3) joint positions -> (T,2) contact labels for skeleton.FOOT_JOINTS."""
    feet = np.asarray(positions, dtype=np.float64)[:, sk.FOOT_JOINTS]           # (T,2,3)
    speed = np.linalg.norm(central_velocity(feet, fps), axis=-1)                  # (T,2)
    low = feet[:, :, 1].min(axis=1)                                               # (T,)
    w = int(round(CONTACT_WINDOW * fps / sk.MODEL_FPS))
    padded = np.pad(low, (w, w), mode="edge")
    nb_min = np.lib.stride_tricks.sliding_window_view(padded, 2 * w + 1).min(axis=-1)
    near = feet[:, :, 1] - nb_min[:, None] < CONTACT_HEIGHT
    return ((speed < CONTACT_SPEED) & near).astype(np.float32)


def _small_rotations(rng, n, sigma_deg) -> np.ndarray:
    return sk.axis_angle_to_rot(rng.normal(scale=np.deg2rad(sigma_deg), size=(n, 3)))


def with_orientation_errors(bones, rng, augment) -> tuple:
    """bones (T,n,3,3) global orientations as n sensors with `augment`'s orientation errors report
    them: a fixed mounting error on the bone side, a fixed yaw of each sensor's world, noise per
    frame. Returns (orientations, the per-sensor world yaws (n,3,3), which turn the accelerations
    too)."""
    T, n = bones.shape[:2]
    mount = _small_rotations(rng, n, augment.mounting_deg)
    drift = np.stack([_ry(a) for a in np.deg2rad(
        rng.uniform(-augment.heading_drift_deg, augment.heading_drift_deg, n))])
    ori = drift[None] @ bones @ mount[None]   # a three-operand einsum took 5x as long
    noise = _small_rotations(rng, T * n, augment.orientation_noise_deg).reshape(T, n, 3, 3)
    return ori @ noise, drift


def _hold_drops(rng, x: np.ndarray, rate: float, max_len: int) -> np.ndarray:
    """x (T,N,...): per sensor, drop-outs hold the last sample."""
    T = x.shape[0]
    for s in range(x.shape[1]):
        starts = np.nonzero(rng.random(T) < rate)[0]
        for t0 in starts:
            if t0 == 0:
                continue
            n = int(rng.integers(1, max_len + 1))
            x[t0:t0 + n, s] = x[t0 - 1, s]
    return x


# ------------------------------------------------------------------------------ motion variety
ARM_JOINTS = [13, 14, 16, 17, 18, 19, 20, 21, 22, 23]   # collars, shoulders, elbows, wrists, hands
SHOULDER_JOINTS = [16, 17]
SPINE_JOINTS = [3, 6, 9]                                  # spine1, spine2, spine3
UPPER_BODY_JOINTS = sorted(SPINE_JOINTS + [12, 15] + ARM_JOINTS)   # spine, neck, head, arms


def _smooth_offsets(rng, T: int, fps: float, sigma_deg: float, n: int) -> np.ndarray:
    """(T,n,3,3): per joint a rotation that wanders slowly (two sinusoids per axis, 0.05-0.5 Hz,
    random phase), per-axis standard deviation sigma_deg."""
    t = np.arange(T) / fps
    freq = rng.uniform(0.05, 0.5, size=(2, n, 3))
    phase = rng.uniform(0, 2 * np.pi, size=(2, n, 3))
    wave = np.sin(2 * np.pi * freq[:, None] * t[None, :, None, None] + phase[:, None]).sum(0)
    return sk.axis_angle_to_rot(wave * np.deg2rad(sigma_deg))           # sum of 2 sines: std 1


def _donor(motion, donors, rng):
    """A random other clip at the same frame rate, or None (the draw landed on the clip itself)."""
    d = donors[int(rng.integers(len(donors)))]
    return d if d is not motion and float(d.fps) == float(motion.fps) else None


def vary_motion(motion: sk.Motion, rng, augment, donors=()) -> sk.Motion:
    """New arm and trunk movements on an existing clip (training only). The 6 h of CMU motion
    tie each arm pose to the body motion it was captured with, and the network learns those
    pairings: its error on the training subjects is far below that on new ones, mostly in the
    unobserved upper arms. With probability `arm_swap` both arms (collars to hands) take their
    local rotations from a random window of a donor clip; `arm_jitter_deg` adds a slow random
    rotation to each shoulder, `spine_jitter_deg` to each spine joint (the trunk bends and
    twists a little otherwise than it did, so its bend must be read from the head and wrist
    sensors rather than guessed from the legs' motion). With probability `trunk_swap` (drawn
    before the arm swap, which it then replaces) the whole upper body, spine to head and hands,
    moves as in the donor's window: a bent-over or twisted trunk on legs that walk, stand or
    climb. Legs, root and therefore contacts and root velocity are untouched; the sensors are
    synthesised afterwards from the new pose, so signals and targets stay consistent."""
    if not augment:
        return motion
    donor, swapped = None, ARM_JOINTS
    # trunk_swap 0 draws nothing here, so arm-only runs keep their random streams
    if donors and augment.trunk_swap > 0 and rng.random() < augment.trunk_swap:
        donor, swapped = _donor(motion, donors, rng), UPPER_BODY_JOINTS
    elif donors and augment.arm_swap > 0 and rng.random() < augment.arm_swap:
        donor = _donor(motion, donors, rng)
    jitters = [(sigma, joints) for sigma, joints in ((augment.arm_jitter_deg, SHOULDER_JOINTS),
                                                     (augment.spine_jitter_deg, SPINE_JOINTS)) if sigma > 0]
    if donor is None and not jitters:
        return motion
    T = motion.num_frames if donor is None else min(motion.num_frames, donor.num_frames)
    a = int(rng.integers(0, motion.num_frames - T + 1))
    local = np.array(motion.local_rot[a:a + T])                   # a copy: the clip is shared
    if donor is not None:
        b = int(rng.integers(0, donor.num_frames - T + 1))
        local[:, swapped] = np.asarray(donor.local_rot)[b:b + T, swapped]
    for sigma, joints in jitters:
        off = _smooth_offsets(rng, T, float(motion.fps), sigma, len(joints)).astype(local.dtype)
        local[:, joints] = local[:, joints] @ off
    return sk.Motion(name=motion.name, subject=motion.subject, fps=motion.fps,
                     local_rot=local, root_pos=np.asarray(motion.root_pos)[a:a + T],
                     offsets=motion.offsets)


# ------------------------------------------------------------------------------ synthesis
def synthesize(motion: sk.Motion, rng=None, augment=None, k: int = ACC_K,
               wrist: str = "hand", sensors=DEFAULT_SENSORS) -> Sample:
    """Motion -> Sample. augment: None/False (exact signals), True (default Augmentation) or an
    Augmentation; rng: numpy Generator (default seeded 0) for the augmentation draws; wrist:
    where the wrist sensors are, "hand" (the shipped model's placement) or "forearm" (straps);
    sensors: the segment names to synthesise, in this order."""
    sensors = sensor_list(sensors)
    if augment is True:
        augment = Augmentation()
    if augment and rng is None:
        rng = np.random.default_rng(0)
    fps = float(motion.fps)
    local = np.asarray(motion.local_rot, dtype=np.float64).copy()
    root = np.asarray(motion.root_pos, dtype=np.float64).copy()
    offsets = np.asarray(motion.offsets, dtype=np.float64).copy()
    if augment:
        if tuple(augment.speed) != (1.0, 1.0):
            # People do the same movement at different tempos; CMU has one take per subject and
            # action. Slerp resampling keeps the rotations on the rotation group, and root speed,
            # sensor accelerations (synthesised below) and contacts all follow the new tempo.
            from .retarget import resample
            f = rng.uniform(*augment.speed)
            local, root = resample(local, root, 1.0 / (fps * f), fps)
        if augment.mirror > 0 and rng.random() < augment.mirror:
            # Left-right mirrored motion is as plausible as the original and doubles the variety
            # of the 6 h of training data (it also removes the subjects' handedness bias).
            local, root, offsets = sk.mirror_motion(local, root, offsets)
        s = rng.uniform(*augment.scale)
        offsets *= s
        root *= s
        if augment.heading:
            r = _ry(rng.uniform(-np.pi, np.pi))
            local[:, 0] = r @ local[:, 0]
            root = root @ r.T
    g, p = sk.forward_kinematics(local, root, offsets)
    bone = sensor_bone_orientations(g, local, wrist, sensors)                            # (T,N,3,3)
    spos = p[:, sensor_joints(sensors)] + np.einsum("tsab,sb->tsa", bone, sensor_offsets(offsets, sensors))
    acc = second_difference(spos, fps, k)
    ori = bone.copy()
    if augment:
        n = len(sensors)
        ori, drift = with_orientation_errors(ori, rng, augment)
        T = ori.shape[0]
        acc = np.einsum("sab,tsb->tsa", drift, acc)
        acc = acc + rng.uniform(-augment.acc_bias, augment.acc_bias, size=(1, n, 3))
        acc = acc + rng.normal(scale=augment.acc_noise, size=acc.shape)
        if augment.drop_rate > 0:
            both = np.concatenate([ori.reshape(T, n, 9), acc], axis=-1)
            both = _hold_drops(rng, both, augment.drop_rate, augment.drop_max_frames)
            ori = both[..., :9].reshape(T, n, 3, 3)
            acc = both[..., 9:]
    f32 = np.float32
    return Sample(
        name=motion.name, fps=fps,
        imu_orientation=ori.astype(f32), imu_acceleration=acc.astype(f32),
        local_rot=local.astype(f32), root_velocity=central_velocity(root, fps).astype(f32),
        foot_contact=foot_contact_labels(p, fps), positions=p.astype(f32),
        offsets=offsets.astype(f32), root_pos=root.astype(f32), sensor_position=spos.astype(f32),
        sensors=sensors)


# ------------------------------------------------------------------------------ raw sensors
def specific_force_sensor_frame(sensor_orientation, acceleration) -> np.ndarray:
    """What an accelerometer reads, in g, in its own frame: R_model_sensor^T (a + g_up) / g.

    sensor_orientation (...,3,3) sensor -> model; acceleration (...,3) model frame m/s^2
    (gravity removed). At rest the reading is +1 g along the sensor axis that points up."""
    r = np.asarray(sensor_orientation, dtype=np.float64)
    a = np.asarray(acceleration, dtype=np.float64) + np.array([0.0, GRAVITY, 0.0])
    return np.einsum("...ba,...b->...a", r, a) / GRAVITY


def angular_rate_sensor_frame(sensor_orientation, fps: float) -> np.ndarray:
    """Angular velocity (T,...,3) rad/s in the sensor frame from orientations (T,...,3,3)
    (sensor -> model), central difference: log(R[t-1]^T R[t+1]) / (2 dt)."""
    r = np.asarray(sensor_orientation, dtype=np.float64)
    T = r.shape[0]
    if T < 2:
        return np.zeros(r.shape[:-1])
    prev = np.concatenate([r[:1], r[:-2], r[-2:-1]], axis=0)
    nxt = np.concatenate([r[1:2], r[2:], r[-1:]], axis=0)
    span = np.full(T, 2.0)
    span[0] = span[-1] = 1.0
    rel = np.swapaxes(prev, -1, -2) @ nxt
    w = sk.rot_to_axis_angle(rel) * fps
    return w / span.reshape((T,) + (1,) * (w.ndim - 1))


def raw_sensor_signals(motion: sk.Motion, mounting=None, k: int = ACC_K, sensors=DEFAULT_SENSORS) -> dict:
    """Ideal raw signals of the sensors (segment names; no noise) for a Motion.

    mounting: (N,3,3) sensor -> bone rotations (identity if None). Returns float64 arrays:
    sensor_orientation (T,N,3,3) sensor -> model, bone_orientation (T,N,3,3),
    position (T,N,3) model frame, acceleration (T,N,3) model frame m/s^2 gravity removed,
    specific_force_g (T,N,3) sensor frame in g, angular_rate (T,N,3) sensor frame rad/s."""
    sensors = sensor_list(sensors)
    fps = float(motion.fps)
    g, p = sk.forward_kinematics(np.asarray(motion.local_rot, np.float64),
                                 np.asarray(motion.root_pos, np.float64), motion.offsets)
    bone = sensor_bone_orientations(g, motion.local_rot, "hand", sensors)
    spos = p[:, sensor_joints(sensors)] + np.einsum("tsab,sb->tsa", bone, sensor_offsets(motion.offsets, sensors))
    acc = second_difference(spos, fps, k)
    n = len(sensors)
    m = np.broadcast_to(np.eye(3), (n, 3, 3)) if mounting is None else np.asarray(mounting, np.float64)
    if m.shape != (n, 3, 3):
        raise ValueError(f"mounting must be ({n},3,3) for {n} sensors, got {m.shape}")
    sens = bone @ m
    return {"sensor_orientation": sens, "bone_orientation": bone, "position": spos,
            "acceleration": acc, "specific_force_g": specific_force_sensor_frame(sens, acc),
            "angular_rate": angular_rate_sensor_frame(sens, fps)}
