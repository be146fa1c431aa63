"""Procedural motions on our skeleton, and fixture BVH folders that look like the CMU Daz data.

make_motion(kind, seconds, seed): kind in walk, arm_swing, squat, turn, mixed. Motions are smooth
(sums of sinusoids and smoothsteps), plausible (leg lengths respected by two-bone IK, feet planted
on the floor during stance, arms hanging and swinging), deterministic for a seed. Joints the CMU
Daz data cannot drive (spine3, collars, toes, hands) keep identity local rotations, so fixtures
survive the Daz round trip exactly.

write_fixture_bvh_dir(dir, n_clips, seed) writes DIR/bvh/NN/NN_MM.bvh on a Daz-like skeleton
(same joint names, order, channels; own approximate offsets) and DIR/manifest.csv with the real
manifest's columns, for end-to-end tests of bvh.py + retarget.py + dataset.py without ../shared.
"""
from __future__ import annotations

import csv
import os

import numpy as np

from . import skeleton as sk
from .bvh import BvhClip, write_bvh

KINDS = ("walk", "arm_swing", "squat", "turn", "mixed")
FPS = sk.MODEL_FPS


def _ry(a):
    return sk.rot_axis("y", a)


def _smoothstep(x):
    """C2 "smootherstep" from 0 to 1."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * x * (x * (6 * x - 15) + 10)


def _frame_from_y_z(neg_bone, fwd):
    """Global frames (T,3,3) whose -Y axis is neg_bone (bone direction) and whose Z is as close to
    fwd as possible."""
    y = -neg_bone / np.linalg.norm(neg_bone, axis=-1, keepdims=True)
    z = fwd - np.sum(fwd * y, axis=-1, keepdims=True) * y
    z /= np.linalg.norm(z, axis=-1, keepdims=True)
    x = np.cross(y, z)
    return np.stack([x, y, z], axis=-1)


def _leg_ik(hip, ankle, fwd, l1, l2):
    """Two-bone IK, knee bending towards fwd. hip, ankle, fwd (T,3) -> thigh, shin globals."""
    d = ankle - hip
    L = np.linalg.norm(d, axis=-1, keepdims=True)
    # soft reach limit: the leg never snaps straight (the knee would jump), the ankle falls short
    lmax, a = (l1 + l2) * 0.995, 0.93
    knee_in = a * lmax
    L = np.where(L > knee_in, knee_in + (lmax - knee_in) * np.tanh((L - knee_in) / (lmax - knee_in)), L)
    L = np.maximum(L, abs(l1 - l2) + 1e-3)
    dh = d / np.linalg.norm(d, axis=-1, keepdims=True)
    n = fwd - np.sum(fwd * dh, axis=-1, keepdims=True) * dh
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    cos_a = (l1 * l1 + L * L - l2 * l2) / (2 * l1 * L)
    sin_a = np.sqrt(np.clip(1 - cos_a ** 2, 0, 1))
    knee = hip + l1 * (cos_a * dh + sin_a * n)
    ank = hip + L * dh
    thigh = _frame_from_y_z(knee - hip, fwd)
    shin = _frame_from_y_z(ank - knee, fwd)
    return thigh, shin


class _Gen:
    def __init__(self, T, seed, offsets):
        self.T = T
        self.t = np.arange(T) / FPS
        self.rng = np.random.default_rng(seed)
        self.o = offsets
        self.g = np.broadcast_to(np.eye(3), (T, sk.NUM_JOINTS, 3, 3)).copy()   # globals
        self.local = np.broadcast_to(np.eye(3), (T, sk.NUM_JOINTS, 3, 3)).copy()

    def set_local(self, j, r):
        self.local[:, j] = r


def _feet_stepping(t, path_xz, heading, period, lift, foot_x, phase0=0.0):
    """Planted/swinging ankle ground positions and yaws for both feet.
    path_xz(t) -> (T,2) pelvis ground point, heading(t) -> (T,) yaw."""
    out = []
    for side, (sx, ph) in enumerate(((foot_x, 0.0), (-foot_x, 0.5))):
        u = t / period + phase0 - ph          # cycle coordinate, swing in [k, k+0.4)
        k = np.floor(u)
        f = u - k
        def plant(kk):
            tm = (kk + 0.7 - phase0 + ph) * period    # mid-stance time of stance kk
            p = path_xz(tm)
            h = heading(tm)
            return np.stack([p[..., 0] + np.cos(h) * sx, p[..., 1] - np.sin(h) * sx], -1), h
        prev, hp = plant(k - 1)
        nxt, hn = plant(k)
        s = np.where(f < 0.4, _smoothstep(f / 0.4), 1.0)
        pos = prev + (nxt - prev) * s[:, None]
        yaw = hp + (hn - hp) * s
        moved = np.linalg.norm(nxt - prev, axis=-1) + np.abs(hn - hp)
        up = np.where(f < 0.4, np.sin(np.pi * f / 0.4) ** 2, 0.0) * lift * np.clip(moved / 0.05, 0, 1)
        out.append((pos, yaw, up))
    return out


def make_motion(kind: str, seconds: float = 4.0, seed: int = 0, offsets=None, name: str = "",
                subject: int = 0) -> sk.Motion:
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}")
    o = np.asarray(sk.DEFAULT_OFFSETS if offsets is None else offsets, dtype=np.float64)
    T = max(2, int(round(seconds * FPS)))
    G = _Gen(T, seed, o)
    rng, t = G.rng, G.t
    s = o[4, 1] / sk.DEFAULT_OFFSETS[4, 1]
    l1, l2 = -o[4, 1], -o[7, 1]
    ankle_h = sk.ANKLE_HEIGHT * s
    foot_x = o[1, 0]
    pelvis_h = o[0, 1]

    # ---- pelvis path, heading, stepping parameters per kind
    period = rng.uniform(1.0, 1.2)
    phase0 = rng.uniform(0, 1)
    yaw0 = rng.uniform(-np.pi, np.pi)
    start = rng.uniform(-1, 1, size=2)
    stepping = True
    speed = 0.0
    if kind == "walk":
        speed = rng.uniform(0.8, 1.05) * s
        turn_rate = rng.uniform(-0.15, 0.15)
        heading = lambda tt: yaw0 + turn_rate * np.asarray(tt)
    elif kind == "turn":
        total = rng.choice([-1, 1]) * rng.uniform(0.5, 1.0) * np.pi
        heading = lambda tt: yaw0 + total * _smoothstep(np.asarray(tt) / max(seconds, 1e-3))
        period = rng.uniform(0.9, 1.1)
    elif kind == "mixed":
        speed = rng.uniform(0.5, 0.9) * s
        a1, w1 = rng.uniform(0.3, 0.6), rng.uniform(0.2, 0.4)
        heading = lambda tt: yaw0 + a1 * np.sin(w1 * np.asarray(tt))
    else:                                           # arm_swing, squat: standing
        stepping = False
        heading = lambda tt: yaw0 + 0.0 * np.asarray(tt)

    if speed > 0:
        # integrate the ground path along the heading (fine grid, also for any query time)
        grid = np.arange(-3 * FPS, T + 3 * FPS) / FPS
        hg = heading(grid)
        ramp = _smoothstep((grid + 0.5) / 1.0) if kind == "mixed" else np.ones_like(grid)
        vel = np.stack([np.sin(hg), np.cos(hg)], -1) * (speed * ramp)[:, None]
        pos = np.cumsum(vel, axis=0) / FPS
        pos -= pos[3 * FPS]
        pos += start

        def path_xz(tt):
            tt = np.asarray(tt, dtype=np.float64)
            return np.stack([np.interp(tt, grid, pos[:, 0]), np.interp(tt, grid, pos[:, 1])], -1)
    else:
        def path_xz(tt):
            tt = np.asarray(tt, dtype=np.float64)
            return np.broadcast_to(start, tt.shape + (2,)).copy()

    yaw = heading(t)
    ground = path_xz(t)

    # ---- pelvis height / orientation
    crouch = 0.05 * s
    height = np.full(T, pelvis_h - crouch)
    pitch = np.zeros(T)
    roll = np.zeros(T)
    back = np.zeros(T)
    if stepping:
        w = 2 * np.pi / period
        cyc = w * t + 2 * np.pi * phase0
        height += 0.02 * s * np.cos(2 * cyc - 2 * np.pi * 0.7) * (1.0 if speed > 0 else 0.3)
        roll += 0.04 * np.sin(cyc)
        pitch += 0.05 + 0.02 * np.cos(2 * cyc)
    if kind == "squat":
        n_sq = max(1, int(seconds / rng.uniform(2.0, 3.0)))
        depth = rng.uniform(0.25, 0.4) * s
        sq = 0.5 - 0.5 * np.cos(2 * np.pi * n_sq * t / seconds)
        height -= depth * sq
        back = -0.12 * s * sq
        pitch += 0.6 * sq
    if kind == "arm_swing":
        height += 0.01 * s * np.sin(2 * np.pi * t / 3.0)
        roll += 0.03 * np.sin(2 * np.pi * t / 2.3)
    G_pelvis = _ry(yaw) @ sk.rot_axis("x", pitch) @ sk.rot_axis("z", roll)
    fwd = np.stack([np.sin(yaw), np.zeros(T), np.cos(yaw)], -1)
    sway = 0.0
    if stepping:
        sway = 0.02 * s * np.sin(2 * np.pi * t / period + 2 * np.pi * phase0)
    lat = np.stack([np.cos(yaw), np.zeros(T), -np.sin(yaw)], -1)
    root = np.stack([ground[:, 0], height, ground[:, 1]], -1) + fwd * back[:, None] + lat * np.asarray(sway)[..., None] if stepping else \
        np.stack([ground[:, 0], height, ground[:, 1]], -1) + fwd * back[:, None]
    G.set_local(0, G_pelvis)

    # ---- legs
    if stepping:
        feet = _feet_stepping(t, path_xz, heading, period, 0.07 * s, foot_x, phase0)
    else:
        feet = []
        for sx in (foot_x, -foot_x):
            p = start + np.array([np.cos(yaw0) * sx * 1.3, -np.sin(yaw0) * sx * 1.3])
            feet.append((np.broadcast_to(p, (T, 2)), np.full(T, yaw0), np.zeros(T)))
    for side, (hip_j, knee_j, ank_j) in enumerate(((1, 4, 7), (2, 5, 8))):
        pos, fyaw, up = feet[side]
        hip = root + np.einsum("tab,b->ta", G_pelvis, o[hip_j])
        ankle = np.stack([pos[:, 0], ankle_h + up, pos[:, 1]], -1)
        ffwd = np.stack([np.sin(fyaw), np.zeros(T), np.cos(fyaw)], -1)
        kfwd = ffwd + 0.3 * fwd
        thigh, shin = _leg_ik(hip, ankle, kfwd, l1, l2)
        foot = _ry(fyaw) @ sk.rot_axis("x", 0.25 * up / max(0.07 * s, 1e-6))
        G.set_local(hip_j, np.swapaxes(G_pelvis, -1, -2) @ thigh)
        G.set_local(knee_j, np.swapaxes(thigh, -1, -2) @ shin)
        G.set_local(ank_j, np.swapaxes(shin, -1, -2) @ foot)

    # ---- spine, neck, head: counter-rotate the pelvis, small idle motion
    ph = rng.uniform(0, 2 * np.pi, size=6)
    counter = sk.rot_axis("x", -0.6 * pitch) @ sk.rot_axis("z", -0.7 * roll)
    G.set_local(3, counter @ sk.rot_axis("y", 0.05 * np.sin(0.7 * t + ph[0])))
    G.set_local(6, sk.rot_axis("x", 0.04 * np.sin(0.5 * t + ph[1])) @ sk.rot_axis("y", 0.08 * np.sin(0.9 * t + ph[2])))
    G.set_local(12, sk.rot_axis("x", 0.05 + 0.05 * np.sin(0.6 * t + ph[3])))
    G.set_local(15, sk.rot_axis("y", 0.3 * np.sin(0.4 * t + ph[4])) @ sk.rot_axis("x", -0.3 * pitch * 0.5
                                                                                   + 0.08 * np.sin(0.8 * t + ph[5])))

    # ---- arms: hang down (shoulder about Z), swing in the sagittal plane, elbow flexion (about Y)
    for side, (sh, el, wr, sgn) in enumerate(((16, 18, 20, 1.0), (17, 19, 21, -1.0))):
        down = -sgn * np.deg2rad(rng.uniform(70, 80))
        abd = np.zeros(T)
        flex = np.zeros(T)      # forward swing, radians (positive = forward)
        elbow = np.full(T, np.deg2rad(rng.uniform(10, 25)))
        if stepping:
            amp = np.deg2rad(15 + 10 * speed)
            cyc = 2 * np.pi * t / period + 2 * np.pi * phase0
            flex = -sgn * amp * np.sin(cyc)       # opposite to the leg on the same side
            elbow = elbow + 0.25 * (flex + amp)
        if kind == "arm_swing":
            mode = rng.integers(0, 3)
            w = 2 * np.pi / rng.uniform(1.5, 3.0)
            if mode == 0:        # forward raises
                flex = np.deg2rad(60) * (1 - np.cos(w * t + side * np.pi * rng.integers(0, 2)))
            elif mode == 1:      # lateral raises towards the T-pose and above
                abd = np.deg2rad(55) * (1 - np.cos(w * t))
            else:                # swinging, arms alternate
                flex = np.deg2rad(45) * np.sin(w * t + side * np.pi)
            elbow = elbow + np.deg2rad(30) * (0.5 - 0.5 * np.cos(0.5 * w * t))
        if kind == "squat":
            sq = (height.max() - height) / max(height.max() - height.min(), 1e-6)
            flex = flex + np.deg2rad(80) * sq
        sh_rot = sk.rot_axis("x", -flex) @ sk.rot_axis("z", down + sgn * abd)
        G.set_local(sh, sh_rot)
        G.set_local(el, sk.rot_axis("y", -sgn * elbow))
        G.set_local(wr, sk.rot_axis("z", 0.1 * np.sin(1.1 * t + side)) @ sk.rot_axis("x", 0.1 * np.sin(0.8 * t)))

    # ---- floor: lowest sole point at y = 0
    local = G.local
    gr, p = sk.forward_kinematics(local, root, o)
    from .retarget import sole_points
    root = root.copy()
    root[:, 1] -= sole_points(gr, p, o)[..., 1].min()
    return sk.Motion(name=name or f"{kind}_{seed}", subject=int(subject), fps=float(FPS),
                     local_rot=local.astype(np.float32), root_pos=root.astype(np.float32),
                     offsets=o.astype(np.float32))


# ----------------------------------------------------------------------------- Daz fixture
# A Daz-like skeleton: the CMU Daz-friendly joint names, order and channels, with approximate
# offsets (cm) of our own (a T-pose: arms out along +-X a few degrees forward, elbows slightly
# bent forward, legs straight; hip ~83 cm above the toe tips).
_DAZ = [
    # name, parent, offset, end site
    ("hip", None, (0, 0, 0), None),
    ("abdomen", "hip", (0, 20.5, -0.8), None),
    ("chest", "abdomen", (0, 11.5, -0.5), None),
    ("neck", "chest", (0, 22.0, -2.0), None),
    ("head", "neck", (-0.2, 7.0, 1.2), (0.2, 8.0, 8.0)),
    ("rCollar", "chest", (-2.7, 19.0, -4.8), None),
    ("rShldr", "rCollar", (-8.8, -2.0, 1.5), None),
    ("rForeArm", "rShldr", (-28.0, -1.7, 0.5), None),
    ("rHand", "rForeArm", (-22.5, 0.8, 7.0), (-6.9, 0.4, 2.7)),
    ("lCollar", "chest", (2.7, 19.0, -4.8), None),
    ("lShldr", "lCollar", (8.8, -2.0, 1.5), None),
    ("lForeArm", "lShldr", (28.0, -1.7, 0.5), None),
    ("lHand", "lForeArm", (22.5, 0.8, 7.0), (6.9, 0.4, 2.7)),
    ("rButtock", "hip", (-8.8, 4.4, 1.2), None),
    ("rThigh", "rButtock", (0, -1.7, -2.2), None),
    ("rShin", "rThigh", (0, -36.8, 0.7), None),
    ("rFoot", "rShin", (0.7, -45.1, -5.1), (-1.1, -3.7, 12.1)),
    ("lButtock", "hip", (8.8, 4.4, 1.2), None),
    ("lThigh", "lButtock", (0, -1.7, -2.2), None),
    ("lShin", "lThigh", (0, -36.8, 0.7), None),
    ("lFoot", "lShin", (-0.7, -45.1, -5.1), (1.1, -3.7, 12.1)),
]


def daz_template() -> BvhClip:
    names = [d[0] for d in _DAZ]
    parents = [-1 if d[1] is None else names.index(d[1]) for d in _DAZ]
    offsets = np.array([d[2] for d in _DAZ], dtype=np.float64)
    ends = {i: np.array(d[3], dtype=np.float64) for i, d in enumerate(_DAZ) if d[3] is not None}
    chans = [["Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"]] + \
            [["Zrotation", "Xrotation", "Yrotation"]] * (len(_DAZ) - 1)
    return BvhClip(names, parents, offsets, chans, 1 / 24, np.tile(np.eye(3), (1, len(names), 1, 1)),
                   np.zeros((1, 3)), ends, None)


def resample_motion(motion: sk.Motion, fps: float) -> sk.Motion:
    """The same motion sampled at another rate (slerp / lerp)."""
    from .retarget import resample
    rot, root = resample(motion.local_rot.astype(np.float64), motion.root_pos.astype(np.float64),
                         1.0 / motion.fps, fps)
    return sk.Motion(motion.name, motion.subject, float(fps), rot.astype(np.float32), root.astype(np.float32),
                     motion.offsets.copy())


def motion_to_daz(motion: sk.Motion, frame_step: int = 1) -> BvhClip:
    from .retarget import to_source_clip
    return to_source_clip(motion, daz_template(), frame_step=frame_step)


MANIFEST_COLUMNS = ["clip", "subject", "frames", "seconds", "description", "source_fps", "frame_time",
                    "status", "duplicate_of", "elbow_reversed", "timing_note", "fbx_repo", "fbx_blob"]

# (subject, kind, seconds, bvh fps label) -- subjects chosen so that every split gets clips
_FIXTURE_PLAN = [
    (2, "walk", 4.0, 24), (3, "arm_swing", 3.0, 24), (1, "squat", 4.0, 24), (6, "turn", 3.0, 12),
    (4, "mixed", 4.0, 24), (5, "walk", 3.0, 24), (11, "arm_swing", 3.0, 12), (16, "squat", 3.0, 24),
    (7, "turn", 3.0, 24), (8, "mixed", 4.0, 24),
]


def write_fixture_bvh_dir(directory, n_clips: int = 6, seed: int = 0, seconds_scale: float = 1.0,
                          extra_rows: bool = True):
    """Write n_clips procedural clips as Daz-style BVH (DIR/bvh/NN/NN_MM.bvh, no T-pose frame, ZXY
    channels, 24 fps or "12 fps" frame time) and DIR/manifest.csv in the real manifest's format.
    Clip 2 (if present) is written with its left elbow reversed and marked elbow_reversed=L.
    With extra_rows, a duplicate and a missing row (no files) are added. Returns the list of
    (clip name, Motion at 60 Hz) written (the ground truth, before reversal)."""
    os.makedirs(directory, exist_ok=True)
    rows, written = [], []
    per_subject: dict = {}
    for i in range(n_clips):
        subj, kind, secs, fps = _FIXTURE_PLAN[i % len(_FIXTURE_PLAN)]
        per_subject[subj] = per_subject.get(subj, 0) + 1
        name = f"{subj:02d}_{per_subject[subj]:02d}"
        m = make_motion(kind, secs * seconds_scale, seed=seed * 1000 + i, name=name, subject=subj)
        clip = motion_to_daz(resample_motion(m, fps))
        elbow = "L" if i == 2 else ""
        if elbow:
            e = clip.index("lForeArm")
            clip.rotations[:, e] = np.swapaxes(clip.rotations[:, e], -1, -2)
        sub = os.path.join(directory, "bvh", f"{subj:02d}")
        os.makedirs(sub, exist_ok=True)
        write_bvh(os.path.join(sub, name + ".bvh"), clip, order="ZXY", decimals=4)
        ft = "0.0416667" if fps == 24 else "0.0833333"
        rows.append(dict(clip=name, subject=subj, frames=clip.num_frames,
                         seconds=f"{clip.num_frames / fps:.4f}", description=f"procedural {kind}",
                         source_fps=120 if fps == 24 else 60, frame_time=ft, status="ok", duplicate_of="",
                         elbow_reversed=elbow, timing_note="" if fps == 24 else "procedural 60 fps",
                         fbx_repo="procedural", fbx_blob=f"{seed:08x}{i:032x}"))
        written.append((name, m))
    if extra_rows and rows:
        first = rows[0]
        rows.append(dict(first, clip=f"{first['subject']:02d}_90", status="duplicate", duplicate_of=first["clip"],
                         elbow_reversed="", fbx_blob="0" * 40))
        rows.append(dict(first, clip=f"{first['subject']:02d}_91", frames=0, seconds="0", status="missing: fbx over 4 MiB",
                         elbow_reversed="", fbx_blob="1" * 40))
    with open(os.path.join(directory, "manifest.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=MANIFEST_COLUMNS)
        w.writeheader()
        w.writerows(rows)
    return written
