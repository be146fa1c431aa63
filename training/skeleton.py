"""Our SMPL-24-topology skeleton (model contract, docs/model-contract.md) and numpy rotation helpers.

Conventions: right-handed, Y up, the character faces +Z, X is the character's left; metres.
Rotation matrices map bone-frame vectors into the parent (or world) frame. Quaternions are (w, x, y, z).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MODEL_FPS = 60

JOINT_NAMES = [
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
    "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck",
    "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hand", "right_hand",
]
PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
NUM_JOINTS = 24

FOOT_JOINTS = [10, 11]
ANKLE_JOINTS = [7, 8]

# ---------------------------------------------------------------------------------------------
# Default proportions: an adult of stature H = 1.75 m in a T-pose, arms straight out along +-X,
# legs straight down, every bone frame parallel to the model frame.
# Sources (ratios of stature H): Drillis & Contini (1966), "Body segment parameters", as tabulated
# in D. A. Winter, "Biomechanics and Motor Control of Human Movement" (4th ed., 2009), fig. 4.1:
#   hip (greater trochanter) height 0.530 H, knee height 0.285 H, ankle height 0.039 H,
#   shoulder height 0.818 H, chin 0.870 H, biacromial (shoulder) width 0.259 H,
#   upper arm 0.186 H, forearm 0.146 H, hand 0.108 H, foot length 0.152 H, foot breadth 0.055 H.
# Joint centres are placed slightly inside those landmarks: hip joint centres 0.87 m high and
# 0.17 m apart (functional hip-centre separation of adults, roughly 0.1 H); the pelvis joint 6 cm
# above them (so the pelvis is 0.93 m above the sole); glenohumeral centres 0.36 m apart at
# shoulder height; the "hand" joint at the knuckles (~0.45 of hand length from the wrist); the
# "foot" joint at the ball of the foot (~0.53 foot lengths in front of the ankle, 2 cm above the
# sole). The spine split (spine1/2/3, neck at C7, head at the skull base) follows the usual
# SMPL-style placement at roughly equal thirds between pelvis and neck.
# ---------------------------------------------------------------------------------------------
_H = 1.75
_PELVIS_Y = 0.93
_HIP_Y = 0.87
_KNEE_Y = 0.285 * _H            # 0.49875
_ANKLE_Y = 0.039 * _H           # 0.06825
_SHOULDER_Y = 0.818 * _H        # 1.4315
_UPPER_ARM = 0.186 * _H         # 0.3255
_FOREARM = 0.146 * _H           # 0.2555
_HAND = 0.45 * 0.108 * _H       # 0.08505 (wrist -> knuckles)
_FOOT_FWD = 0.53 * 0.152 * _H   # 0.14098 (ankle -> ball of foot)
_BALL_Y = 0.02

STANDING_HEIGHT = _H           # the DEFAULT_OFFSETS body's height, sole to crown (metres)

DEFAULT_OFFSETS = np.array([
    [0.0, _PELVIS_Y, 0.0],                      # 0 pelvis (height above the sole)
    [0.085, _HIP_Y - _PELVIS_Y, 0.0],           # 1 left_hip
    [-0.085, _HIP_Y - _PELVIS_Y, 0.0],          # 2 right_hip
    [0.0, 0.11, 0.0],                           # 3 spine1
    [0.0, _KNEE_Y - _HIP_Y, 0.0],               # 4 left_knee
    [0.0, _KNEE_Y - _HIP_Y, 0.0],               # 5 right_knee
    [0.0, 0.13, 0.0],                           # 6 spine2
    [0.0, _ANKLE_Y - _KNEE_Y, 0.0],             # 7 left_ankle
    [0.0, _ANKLE_Y - _KNEE_Y, 0.0],             # 8 right_ankle
    [0.0, 0.12, 0.0],                           # 9 spine3 (y = 1.29)
    [0.0, _BALL_Y - _ANKLE_Y, _FOOT_FWD],       # 10 left_foot
    [0.0, _BALL_Y - _ANKLE_Y, _FOOT_FWD],       # 11 right_foot
    [0.0, 0.16, 0.0],                           # 12 neck (y = 1.45, C7)
    [0.07, 0.11, 0.0],                          # 13 left_collar (y = 1.40)
    [-0.07, 0.11, 0.0],                         # 14 right_collar
    [0.0, 0.10, 0.0],                           # 15 head (y = 1.55, skull base)
    [0.11, _SHOULDER_Y - 1.40, 0.0],            # 16 left_shoulder (x = 0.18)
    [-0.11, _SHOULDER_Y - 1.40, 0.0],           # 17 right_shoulder
    [_UPPER_ARM, 0.0, 0.0],                     # 18 left_elbow
    [-_UPPER_ARM, 0.0, 0.0],                    # 19 right_elbow
    [_FOREARM, 0.0, 0.0],                       # 20 left_wrist
    [-_FOREARM, 0.0, 0.0],                      # 21 right_wrist
    [_HAND, 0.0, 0.0],                          # 22 left_hand
    [-_HAND, 0.0, 0.0],                         # 23 right_hand
], dtype=np.float64)

# Height of the sole points below the ankle / ball joints at rest (for floor estimation).
ANKLE_HEIGHT = _ANKLE_Y
BALL_HEIGHT = _BALL_Y
HEEL_BACK = 0.05  # heel point behind the ankle, metres


@dataclass
class Motion:
    """One clip on OUR skeleton at MODEL_FPS."""
    name: str
    subject: int
    fps: float
    local_rot: np.ndarray   # (T,24,3,3) float32, joint 0 global
    root_pos: np.ndarray    # (T,3) float32 metres, floor at y=0 (approximately)
    offsets: np.ndarray     # (24,3) float32

    @property
    def num_frames(self) -> int:
        return int(self.local_rot.shape[0])

    def non_finite_field(self) -> str:
        """The first of local_rot, root_pos, offsets that holds NaN or inf ("" when none does)."""
        for name in ("local_rot", "root_pos", "offsets"):
            if not np.isfinite(getattr(self, name)).all():
                return name
        return ""

    @property
    def seconds(self) -> float:
        return self.num_frames / float(self.fps)


def leg_height(offsets: np.ndarray = DEFAULT_OFFSETS) -> float:
    """Rest height of the hip joints above the sole (the length used to scale skeletons)."""
    o = np.asarray(offsets)
    return float(o[0, 1] + o[1, 1]) * 1.0


# Each joint's counterpart on the other side of the body (itself on the midline).
MIRROR_JOINTS = [0, 2, 1, 3, 5, 4, 6, 8, 7, 9, 11, 10, 12, 14, 13, 15, 17, 16, 19, 18, 21, 20, 23, 22]
_REFLECT_X = np.diag([-1.0, 1.0, 1.0])
_REFLECT_ROTATION_SIGNS = np.outer(np.diag(_REFLECT_X), np.diag(_REFLECT_X))


def mirror_motion(local_rot, root_pos, offsets):
    """The same movement performed mirror-image (reflected in the sagittal plane x = 0, left and
    right swapped). With M = diag(-1, 1, 1) every global rotation G of joint j becomes M G M on the
    counterpart joint, and so does every local rotation, since M M = I; positions become M p.
    Returns (local_rot, root_pos, offsets) as new arrays; applying it twice gives the input back."""
    m = _REFLECT_X
    local = np.asarray(local_rot)[..., MIRROR_JOINTS, :, :]
    # M R M with a diagonal M of signs is R with those signs flipped, without two products
    local = (local * _REFLECT_ROTATION_SIGNS).astype(np.asarray(local_rot).dtype)
    root = (np.asarray(root_pos) @ m).astype(np.asarray(root_pos).dtype)
    off = (np.asarray(offsets)[..., MIRROR_JOINTS, :] @ m).astype(np.asarray(offsets).dtype)
    return local, root, off


# ------------------------------------------------------------------------- forward kinematics
def forward_kinematics(local_rot, root_pos, offsets=DEFAULT_OFFSETS, parents=PARENTS):
    """local_rot (...,J,3,3) with joint 0 global, root_pos (...,3), offsets (J,3) or (...,J,3).
    Returns global_rot (...,J,3,3), positions (...,J,3); joint 0's position is root_pos."""
    local_rot = np.asarray(local_rot)
    root_pos = np.asarray(root_pos)
    offsets = np.asarray(offsets, dtype=local_rot.dtype if local_rot.dtype.kind == "f" else np.float64)
    J = local_rot.shape[-3]
    g = np.empty_like(local_rot)
    p = np.empty(local_rot.shape[:-1], dtype=np.result_type(local_rot.dtype, root_pos.dtype))
    g[..., 0, :, :] = local_rot[..., 0, :, :]
    p[..., 0, :] = root_pos
    for j in range(1, J):
        q = parents[j]
        g[..., j, :, :] = g[..., q, :, :] @ local_rot[..., j, :, :]
        off = offsets[..., j, :]
        p[..., j, :] = p[..., q, :] + np.einsum("...ab,...b->...a", g[..., q, :, :], off)
    return g, p


def global_to_local(global_rot, parents=PARENTS):
    """Inverse of the rotation part of forward_kinematics."""
    global_rot = np.asarray(global_rot)
    loc = np.empty_like(global_rot)
    loc[..., 0, :, :] = global_rot[..., 0, :, :]
    for j in range(1, global_rot.shape[-3]):
        loc[..., j, :, :] = np.swapaxes(global_rot[..., parents[j], :, :], -1, -2) @ global_rot[..., j, :, :]
    return loc


# ------------------------------------------------------------------------- rotation helpers
def rot_axis(axis: str, angle):
    """Rotation about 'x', 'y' or 'z' by angle (radians, array ok) -> (...,3,3)."""
    a = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    if axis in ("x", "X"):
        m = [o, z, z, z, c, -s, z, s, c]
    elif axis in ("y", "Y"):
        m = [c, z, s, z, o, z, -s, z, c]
    elif axis in ("z", "Z"):
        m = [c, -s, z, s, c, z, z, z, o]
    else:
        raise ValueError(axis)
    return np.stack(m, axis=-1).reshape(a.shape + (3, 3))


def euler_to_rot(angles, order: str = "ZXY", degrees: bool = True):
    """Intrinsic rotations applied in the listed order: order 'ZXY' gives Rz(a0) Rx(a1) Ry(a2).
    angles (...,3) -> (...,3,3)."""
    ang = np.asarray(angles, dtype=np.float64)
    if degrees:
        ang = np.deg2rad(ang)
    r = rot_axis(order[0], ang[..., 0])
    for k in (1, 2):
        r = r @ rot_axis(order[k], ang[..., k])
    return r


def rot_to_euler(rot, order: str = "ZXY", degrees: bool = True):
    """Inverse of euler_to_rot for a Tait-Bryan order (three distinct axes). (...,3,3) -> (...,3).
    The middle angle is in [-90, 90] degrees; at gimbal lock the last angle is set to 0."""
    R = np.asarray(rot, dtype=np.float64)
    idx = {"X": 0, "Y": 1, "Z": 2}
    i, j, k = (idx[c.upper()] for c in order)
    if len({i, j, k}) != 3:
        raise ValueError("only Tait-Bryan orders are supported: " + order)
    s = 1.0 if (i, j, k) in ((0, 1, 2), (1, 2, 0), (2, 0, 1)) else -1.0
    sb = np.clip(s * R[..., i, k], -1.0, 1.0)
    b = np.arcsin(sb)
    a = np.arctan2(-s * R[..., j, k], R[..., k, k])
    c = np.arctan2(-s * R[..., i, j], R[..., i, i])
    lock = np.abs(sb) > 1.0 - 1e-9
    if np.any(lock):
        # R = R_i(a) R_j(+-90) R_k(c): with c = 0 the angle a follows from the (k, j) / (j, j) terms.
        a_l = np.arctan2(s * R[..., k, j], R[..., j, j])
        a = np.where(lock, a_l, a)
        c = np.where(lock, 0.0, c)
    out = np.stack([a, b, c], axis=-1)
    return np.rad2deg(out) if degrees else out


def rot_from_quat(q):
    """(w,x,y,z) quaternions (...,4), any norm > 0 -> rotation matrices (...,3,3)."""
    q = np.asarray(q, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    m = [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
         2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
         2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]
    return np.stack(m, axis=-1).reshape(q.shape[:-1] + (3, 3))


def twist_about_x(rot):
    """The twist part of rotations (...,3,3) about their bone's X axis (swing-twist split): the
    rotation about X that is left when the swing, which moves the X axis, is taken out."""
    q = quat_from_rot(rot)
    w, x = q[..., 0], q[..., 1]
    angle = 2.0 * np.arctan2(x, w)
    return rot_axis("x", angle)


def quat_from_rot(rot):
    """Rotation matrices (...,3,3) -> unit quaternions (w,x,y,z) (...,4) with w >= 0.
    Uses the largest-diagonal branch per element (numerically stable): each element's quaternion
    comes from the one row of 4 q_b q that its largest of (trace, m00, m11, m22) picks, computed
    for the elements of that branch only (training synthesis converts every clip it plays)."""
    R = np.asarray(rot, dtype=np.float64)
    shape = R.shape[:-2]
    R = R.reshape(-1, 3, 3)
    m00, m11, m22 = R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]
    branch = np.argmax(np.stack([m00 + m11 + m22, m00, m11, m22], -1), axis=-1)
    q = np.empty((R.shape[0], 4))
    for b in range(4):
        i = np.flatnonzero(branch == b)
        if i.size == 0:
            continue
        r = R[i]
        a00, a11, a22 = r[:, 0, 0], r[:, 1, 1], r[:, 2, 2]
        if b == 0:
            row = (1 + (a00 + a11 + a22), r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1])
        elif b == 1:
            row = (r[:, 2, 1] - r[:, 1, 2], 1 + a00 - a11 - a22, r[:, 0, 1] + r[:, 1, 0], r[:, 0, 2] + r[:, 2, 0])
        elif b == 2:
            row = (r[:, 0, 2] - r[:, 2, 0], r[:, 0, 1] + r[:, 1, 0], 1 - a00 + a11 - a22, r[:, 1, 2] + r[:, 2, 1])
        else:
            row = (r[:, 1, 0] - r[:, 0, 1], r[:, 0, 2] + r[:, 2, 0], r[:, 1, 2] + r[:, 2, 1], 1 - a00 - a11 + a22)
        q[i] = np.stack(row, -1)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    q = q * np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(shape + (4,))


def quat_mul(a, b):
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], -1)


def slerp_quat(q0, q1, t):
    """Shortest-path slerp between unit quaternions (...,4) at fraction t (broadcastable to (...))."""
    q0 = np.asarray(q0, dtype=np.float64)
    q1 = np.asarray(q1, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)[..., None]
    d = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(d < 0, -q1, q1)
    d = np.abs(d)
    theta = np.arccos(np.clip(d, -1.0, 1.0))
    sin_t = np.sin(theta)
    small = sin_t < 1e-6
    safe = np.where(small, 1.0, sin_t)
    w0 = np.where(small, 1.0 - t, np.sin((1.0 - t) * theta) / safe)
    w1 = np.where(small, t, np.sin(t * theta) / safe)
    q = w0 * q0 + w1 * q1
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def slerp_rot(r0, r1, t):
    """Spherical interpolation between rotation matrices (...,3,3) at fraction t."""
    return rot_from_quat(slerp_quat(quat_from_rot(r0), quat_from_rot(r1), t))


def axis_angle_to_rot(axis_angle):
    """Rotation vectors (...,3) (axis * angle in radians) -> (...,3,3) (Rodrigues)."""
    v = np.asarray(axis_angle, dtype=np.float64)
    th = np.linalg.norm(v, axis=-1)
    half = 0.5 * th
    k = np.where(th > 1e-12, np.sin(half) / np.where(th > 1e-12, th, 1.0), 0.5)
    q = np.concatenate([np.cos(half)[..., None], v * k[..., None]], axis=-1)
    return rot_from_quat(q)


def rot_to_axis_angle(rot):
    q = quat_from_rot(rot)
    s = np.linalg.norm(q[..., 1:], axis=-1)
    ang = 2.0 * np.arctan2(s, q[..., 0])
    k = np.where(s > 1e-12, ang / np.where(s > 1e-12, s, 1.0), 2.0)
    return q[..., 1:] * k[..., None]


def rotation_between(a, b):
    """Minimal rotation R with R @ a/|a| = b/|b| for vectors (...,3) -> (...,3,3)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    c = np.sum(a * b, axis=-1)
    ax = np.cross(a, b)
    # anti-parallel: rotate 180 deg about any axis perpendicular to a
    anti = c < -1.0 + 1e-9
    if np.any(anti):
        perp = np.cross(a, np.array([1.0, 0.0, 0.0]))
        alt = np.cross(a, np.array([0.0, 1.0, 0.0]))
        perp = np.where(np.linalg.norm(perp, axis=-1, keepdims=True) < 1e-6, alt, perp)
        perp = perp / np.linalg.norm(perp, axis=-1, keepdims=True)
    q = np.concatenate([(1.0 + c)[..., None], ax], axis=-1)
    if np.any(anti):
        q = np.where(anti[..., None], np.concatenate([np.zeros_like(c)[..., None], perp], -1), q)
    return rot_from_quat(q)


def rotation_angle(r):
    """Angle (radians) of rotation matrices (...,3,3)."""
    r = np.asarray(r, dtype=np.float64)
    tr = r[..., 0, 0] + r[..., 1, 1] + r[..., 2, 2]
    ax = np.stack([r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]], -1)
    # atan2(sin, cos) is accurate for small angles, unlike arccos of the trace
    return np.arctan2(0.5 * np.linalg.norm(ax, axis=-1), 0.5 * (tr - 1.0))


def angle_between_rots(a, b):
    """Geodesic angle (radians) between rotation matrices."""
    return rotation_angle(np.swapaxes(np.asarray(a), -1, -2) @ np.asarray(b))


def matrix_to_rot6d(rot):
    """(...,3,3) -> (...,6): the first two COLUMNS, column 0 then column 1 (x0,y0,z0,x1,y1,z1)."""
    r = np.asarray(rot)
    return np.concatenate([r[..., :, 0], r[..., :, 1]], axis=-1)


def rot6d_to_matrix(r6):
    """(...,6) -> (...,3,3) by Gram-Schmidt (inverse of matrix_to_rot6d for valid rotations)."""
    r6 = np.asarray(r6, dtype=np.float64)
    a, b = r6[..., 0:3], r6[..., 3:6]
    x = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b - np.sum(x * b, axis=-1, keepdims=True) * x
    y = b / np.linalg.norm(b, axis=-1, keepdims=True)
    z = np.cross(x, y)
    return np.stack([x, y, z], axis=-1)


def orthonormalize(rot):
    """Project (...,3,3) onto the nearest rotation (via SVD)."""
    u, _, vt = np.linalg.svd(np.asarray(rot, dtype=np.float64))
    d = np.sign(np.linalg.det(u @ vt))
    u[..., :, -1] *= d[..., None]
    return u @ vt


def random_rotations(n, rng, max_angle=np.pi):
    """n random rotations (n,3,3); with max_angle < pi, angles uniform in [0, max_angle]."""
    ax = rng.normal(size=(n, 3))
    ax /= np.linalg.norm(ax, axis=-1, keepdims=True)
    if max_angle >= np.pi:
        q = rng.normal(size=(n, 4))
        return rot_from_quat(q)
    ang = rng.uniform(0, max_angle, size=(n, 1))
    return axis_angle_to_rot(ax * ang)
