"""Map source BVH skeletons (CMU Daz-friendly, original cgspeed CMU, our own SMPL-24 BVH) onto our
SMPL-24 skeleton by GLOBAL rotations, and back.

Method (per clip)
1. Source forward kinematics gives every source joint's global rotation G_s(t). In a BVH every
   joint frame is parallel to the world at rest, and all supported sources are Y up, facing +Z,
   character's left = +X (checked: Daz lShldr / cgspeed LeftUpLeg OFFSETs have x > 0, toes +z).
2. Each of our joints takes one source joint with one of these modes:
   - "align": G(t) = G_s(t) Q with Q the minimal rotation taking OUR rest bone direction (to our
     child) onto the SOURCE rest bone direction (source joint -> chosen child or End Site). The
     bone then points in the same world direction as the source bone in every frame, e.g. the CMU
     rest pose (arms ~8 deg forward, elbows bent ~17 deg) reproduces that pose on our skeleton,
     and a source pose whose bones lie along our T-pose directions maps to identity.
   - "global": G(t) = G_s(t) (pelvis, head: frames without a single bone direction).
   - "local": our local rotation = the source joint's local rotation (leaf joints such as toes).
   - "parent": identity local rotation (copy of the parent's global): joints the source lacks or
     never moves. Daz: spine3, toes (left/right_foot), hands, and the collars (which carry zero
     rotation in every clip of the library).
3. Units -> metres; our DEFAULT_OFFSETS are scaled uniformly by (source hip-joint height above its
   lowest foot point at rest) / (ours, 0.87 m); the root is placed so that the midpoint of our hip
   joints coincides with the midpoint of the source's hip joints.
4. Floor: the lowest sole point (heel and ball of both feet, FK on our skeleton) over the clip is
   moved to y = 0.
5. Resampled from the file's Frame Time to 60 Hz: slerp of local rotations, lerp of the root.
Elbow-reversed clips are repaired on request by inverting (transposing) the source elbow's local
rotation before step 1 (README of the CMU data: this restores the original forearm direction).

A clip this cannot use (no frames, unknown skeleton, a missing hip or foot joint, a zero-length
bone, units that cannot be inferred, a root kilometres away) is a RetargetError (a BvhError) naming
the clip's file (BvhClip.source), never NaN motion.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import skeleton as sk
from .bvh import MAX_FRAME_TIME, BvhClip, BvhError

END = "@end"  # direction target: the joint's End Site

# our joint index -> (mode, source joint, direction target)
DAZ_MAP = {
    0: ("global", "hip", None),
    1: ("align", "lThigh", "lShin"), 2: ("align", "rThigh", "rShin"),
    3: ("align", "abdomen", "chest"),
    4: ("align", "lShin", "lFoot"), 5: ("align", "rShin", "rFoot"),
    6: ("align", "chest", "neck"),
    7: ("align", "lFoot", END), 8: ("align", "rFoot", END),
    9: ("parent", None, None), 10: ("parent", None, None), 11: ("parent", None, None),
    12: ("align", "neck", "head"),
    13: ("parent", None, None), 14: ("parent", None, None),
    15: ("global", "head", None),
    16: ("align", "lShldr", "lForeArm"), 17: ("align", "rShldr", "rForeArm"),
    18: ("align", "lForeArm", "lHand"), 19: ("align", "rForeArm", "rHand"),
    20: ("align", "lHand", END), 21: ("align", "rHand", END),
    22: ("parent", None, None), 23: ("parent", None, None),
}
DAZ_ELBOWS = {"L": "lForeArm", "R": "rForeArm"}
DAZ_HIPS = ("lThigh", "rThigh")
DAZ_FEET = ("lFoot", "rFoot")

CGSPEED_MAP = {
    0: ("global", "Hips", None),
    1: ("align", "LeftUpLeg", "LeftLeg"), 2: ("align", "RightUpLeg", "RightLeg"),
    3: ("align", "LowerBack", "Spine"),
    4: ("align", "LeftLeg", "LeftFoot"), 5: ("align", "RightLeg", "RightFoot"),
    6: ("align", "Spine", "Spine1"),
    7: ("align", "LeftFoot", "LeftToeBase"), 8: ("align", "RightFoot", "RightToeBase"),
    9: ("align", "Spine1", "Neck"),
    10: ("local", "LeftToeBase", None), 11: ("local", "RightToeBase", None),
    12: ("align", "Neck", "Neck1"),
    13: ("align", "LeftShoulder", "LeftArm"), 14: ("align", "RightShoulder", "RightArm"),
    15: ("global", "Head", None),
    16: ("align", "LeftArm", "LeftForeArm"), 17: ("align", "RightArm", "RightForeArm"),
    18: ("align", "LeftForeArm", "LeftHand"), 19: ("align", "RightForeArm", "RightHand"),
    20: ("align", "LeftHand", "LeftFingerBase"), 21: ("align", "RightHand", "RightFingerBase"),
    22: ("parent", None, None), 23: ("parent", None, None),
}
CGSPEED_ELBOWS = {"L": "LeftForeArm", "R": "RightForeArm"}
CGSPEED_HIPS = ("LeftUpLeg", "RightUpLeg")
CGSPEED_FEET = ("LeftFoot", "RightFoot")

SMPL_MAP = {j: ("global", name, None) for j, name in enumerate(sk.JOINT_NAMES)}
SMPL_ELBOWS = {"L": "left_elbow", "R": "right_elbow"}
SMPL_HIPS = ("left_hip", "right_hip")
SMPL_FEET = ("left_ankle", "right_ankle")

CMU_ASF_UNIT_M = 0.0254 / 0.45   # original cgspeed CMU BVH: ASF length unit 1/0.45 inch
# No capture volume is kilometres wide: a root that far from the origin is a damaged value (one
# frame's Xposition 1e300 became inf in float32 and NaN in the network).
MAX_ROOT_DISTANCE_M = 1000.0


class RetargetError(BvhError):
    """A BVH clip that cannot be mapped onto our skeleton (a message, not a bug)."""


def _refused(clip: BvhClip, problem: str) -> RetargetError:
    return RetargetError(f"{clip.source}: {problem}" if clip.source else problem)


@dataclass
class SourceSkeleton:
    kind: str
    mapping: dict
    elbows: dict
    hips: tuple
    feet: tuple


SOURCES = {
    "daz": SourceSkeleton("daz", DAZ_MAP, DAZ_ELBOWS, DAZ_HIPS, DAZ_FEET),
    "cgspeed": SourceSkeleton("cgspeed", CGSPEED_MAP, CGSPEED_ELBOWS, CGSPEED_HIPS, CGSPEED_FEET),
    "smpl": SourceSkeleton("smpl", SMPL_MAP, SMPL_ELBOWS, SMPL_HIPS, SMPL_FEET),
}


def detect_source(joints) -> SourceSkeleton:
    names = set(joints)
    if {"hip", "lThigh", "rShldr", "abdomen"} <= names:
        return SOURCES["daz"]
    if {"Hips", "LeftUpLeg", "RightArm", "LowerBack"} <= names:
        return SOURCES["cgspeed"]
    if set(sk.JOINT_NAMES) <= names:
        return SOURCES["smpl"]
    raise RetargetError("unknown source skeleton (expected CMU Daz-friendly, cgspeed CMU or SMPL-24 names): "
                     + ", ".join(list(joints)[:8]) + " ...")


def _subtree_end_points(clip: BvhClip, rest: np.ndarray, root_j: int):
    """Rest positions of all joints and End Sites in the subtree of root_j."""
    pts = []
    for j in range(len(clip.joints)):
        k = j
        while k >= 0 and k != root_j:
            k = clip.parents[k]
        if k == root_j:
            pts.append(rest[j])
            if j in clip.end_sites:
                pts.append(rest[j] + clip.end_sites[j])
    return np.array(pts)


def _rest_dir(clip: BvhClip, rest: np.ndarray, j: int, target):
    if target == END:
        if j not in clip.end_sites:
            raise _refused(clip, f"{clip.joints[j]} has no End Site (its bone direction is needed)")
        return clip.end_sites[j]
    return rest[clip.index(target)] - rest[j]


def source_leg_height(clip: BvhClip, src: SourceSkeleton) -> float:
    """Rest height (file units) of the source's hip joints above its lowest foot point."""
    rest = clip.rest_positions()
    hips = [clip.index(n) for n in src.hips]
    low = min(_subtree_end_points(clip, rest, clip.index(f))[:, 1].min() for f in src.feet)
    return float(np.mean(rest[hips, 1]) - low)


def unit_scale(leg_height_units: float) -> float:
    """Metres per file unit, from the leg height: cm, CMU ASF units or metres."""
    h = leg_height_units
    if 40.0 <= h <= 150.0:
        return 0.01
    if 8.0 <= h <= 30.0:
        return CMU_ASF_UNIT_M
    if 0.4 <= h <= 1.5:
        return 1.0
    raise RetargetError(f"cannot infer units from a leg height of {h:.3f} file units (hip joints above "
                        "the lowest foot point at rest: 40-150 cm, 8-30 CMU ASF units or 0.4-1.5 m)")


@dataclass
class _Plan:
    src: SourceSkeleton
    modes: list          # per our joint: (mode, source index or -1, Q (3,3))
    unit: float
    scale: float
    hip_idx: tuple


def _plan(clip: BvhClip, units=None) -> _Plan:
    try:
        src = detect_source(clip.joints)
    except RetargetError as e:
        raise _refused(clip, str(e)) from None
    # the root, hip and foot joints place and scale our skeleton: no fallback for them
    missing = [n for n in (src.mapping[0][1],) + src.hips + src.feet if n not in clip.joints]
    if missing:
        raise _refused(clip, f"the {src.kind} skeleton lacks {', '.join(missing)} (root, hip and foot "
                             "joints are needed for retargeting)")
    leg = source_leg_height(clip, src)
    try:
        unit = unit_scale(leg) if units is None else float(units)
    except RetargetError as e:
        raise _refused(clip, str(e)) from None
    if not leg > 0:
        raise _refused(clip, f"the hip joints are not above the feet at rest (leg height {leg:.3f})")
    rest = clip.rest_positions()
    modes = []
    for j in range(sk.NUM_JOINTS):
        mode, name, target = src.mapping[j]
        if mode != "parent" and name not in clip.joints:
            mode, name, target = "parent", None, None      # optional source joint missing
        if mode == "align" and target != END and target not in clip.joints:
            mode = "global"
        si = clip.index(name) if name is not None else -1
        Q = np.eye(3)
        if mode == "align":
            ours = _our_child_dir(j)
            bone = _rest_dir(clip, rest, si, target)
            # a zero-length bone has no direction: the alignment would be NaN in every frame
            if not np.linalg.norm(bone) > 1e-6 * leg:
                raise _refused(clip, f"the bone {name} -> {'End Site' if target == END else target} has "
                                     "zero length (OFFSET 0 0 0); its direction cannot be retargeted")
            Q = sk.rotation_between(ours, bone)
        modes.append((mode, si, Q))
    scale = leg * unit / sk.leg_height(sk.DEFAULT_OFFSETS)
    return _Plan(src, modes, unit, scale, tuple(clip.index(n) for n in src.hips))


def _our_child_dir(j: int) -> np.ndarray:
    kids = [c for c, p in enumerate(sk.PARENTS) if p == j]
    if j == 9:
        kids = [12]                     # spine3 -> neck
    if not kids:
        raise ValueError(f"{sk.JOINT_NAMES[j]} has no child bone to align")
    return sk.DEFAULT_OFFSETS[kids[0]]


def sole_points(global_rot, positions, offsets):
    """(T,4,3): left heel, left ball, right heel, right ball on our skeleton."""
    s = offsets[4, 1] / sk.DEFAULT_OFFSETS[4, 1]
    heel = np.array([0.0, -sk.ANKLE_HEIGHT, -sk.HEEL_BACK]) * s
    ball = np.array([0.0, -sk.BALL_HEIGHT, 0.0]) * s
    out = []
    for a, f in zip(sk.ANKLE_JOINTS, sk.FOOT_JOINTS):
        out.append(positions[:, a] + global_rot[:, a] @ heel)
        out.append(positions[:, f] + global_rot[:, f] @ ball)
    return np.stack(out, axis=1)


def retarget_frames(clip: BvhClip, elbow_reversed: str = "", units=None, floor: bool = True):
    """Source-rate retarget: (local_rot (F,24,3,3) float64, root_pos (F,3) metres, offsets (24,3))."""
    _check_source(clip)
    plan = _plan(clip, units)
    rots = clip.rotations
    if elbow_reversed:
        rots = rots.copy()
        for side in elbow_reversed.upper():
            if side in plan.src.elbows and plan.src.elbows[side] in clip.joints:
                e = clip.index(plan.src.elbows[side])
                rots[:, e] = np.swapaxes(rots[:, e], -1, -2)
            elif side.strip():
                raise _refused(clip, f"bad elbow_reversed value {elbow_reversed!r} (L, R or LR)")
    src_clip = BvhClip(clip.joints, clip.parents, clip.offsets, clip.channels, clip.frame_time, rots,
                       clip.root_pos, clip.end_sites, clip.translations, clip.source)
    g_src, p_src = src_clip.global_transforms()
    F = clip.num_frames
    g = np.empty((F, sk.NUM_JOINTS, 3, 3))
    for j in range(sk.NUM_JOINTS):           # parents come first in our joint order
        mode, si, Q = plan.modes[j]
        if mode == "global":
            g[:, j] = g_src[:, si]
        elif mode == "align":
            g[:, j] = g_src[:, si] @ Q
        elif mode == "local":
            g[:, j] = g[:, sk.PARENTS[j]] @ rots[:, si]
        else:
            g[:, j] = g[:, sk.PARENTS[j]]
    local = sk.global_to_local(g)
    offsets = sk.DEFAULT_OFFSETS * plan.scale
    hip_mid_src = 0.5 * (p_src[:, plan.hip_idx[0]] + p_src[:, plan.hip_idx[1]]) * plan.unit
    reach = np.abs(hip_mid_src).max(axis=-1)           # not the norm: 1e300 squared overflows
    far = np.flatnonzero(~(reach <= MAX_ROOT_DISTANCE_M))
    if far.size:
        raise _refused(clip, f"frame {far[0] + 1}: the hips are {reach[far[0]]:.3g} m from the origin "
                             f"(more than {MAX_ROOT_DISTANCE_M:g} m: a damaged value)")
    hip_mid_ours = 0.5 * (offsets[1] + offsets[2])
    root = hip_mid_src - g[:, 0] @ hip_mid_ours
    if floor and F:
        gr, pos = sk.forward_kinematics(local, root, offsets)
        root[:, 1] -= sole_points(gr, pos, offsets)[..., 1].min()
    return local, root, offsets


def _check_source(clip: BvhClip) -> None:
    """What retargeting needs of any clip, whoever built it (bvh.parse_bvh checks its own)."""
    if clip.num_frames == 0:
        raise _refused(clip, "the clip has no frames (Frames: 0)")
    if not 0 < clip.frame_time <= MAX_FRAME_TIME:
        raise _refused(clip, f"Frame Time {clip.frame_time} s is not a plausible frame time "
                             f"(0 to {MAX_FRAME_TIME:g} s)")
    for what, v in (("rotations", clip.rotations), ("root positions", clip.root_pos),
                    ("OFFSETs", clip.offsets), ("End Site OFFSETs", list(clip.end_sites.values())),
                    ("joint positions", clip.translations)):
        if v is not None and not np.isfinite(np.asarray(v, dtype=np.float64)).all():
            raise _refused(clip, f"the clip's {what} are not all finite")


def resample(local_rot, root_pos, src_dt: float, fps: float = sk.MODEL_FPS):
    """Resample (F,J,3,3) rotations (slerp) and (F,3) positions (lerp) from frame time src_dt to
    fps. The output covers the same duration: frames at n/fps for n/fps <= (F-1) src_dt."""
    if not 0 < src_dt <= MAX_FRAME_TIME:
        # the output has src_dt * fps frames per input frame: a huge src_dt exhausts the memory
        raise ValueError(f"resample: frame time {src_dt} s is outside (0, {MAX_FRAME_TIME:g}] s")
    F = local_rot.shape[0]
    if F < 2:
        return local_rot.copy(), root_pos.copy()
    dur = (F - 1) * src_dt
    n = int(np.floor(dur * fps + 1e-6)) + 1
    t = np.arange(n) / fps / src_dt
    i0 = np.minimum(np.floor(t).astype(np.int64), F - 2)
    w = (t - i0)
    q = sk.quat_from_rot(local_rot)
    qo = sk.slerp_quat(q[i0], q[i0 + 1], w[:, None])
    rot = sk.rot_from_quat(qo)
    root = root_pos[i0] * (1 - w)[:, None] + root_pos[i0 + 1] * w[:, None]
    return rot, root


def at_rate(local_rot, root_pos, src_dt: float, fps: float = sk.MODEL_FPS):
    """(local_rot, root_pos) at `fps`: resampled unless the source frame time already is 1/fps
    (then returned as they are, so clips at the model rate are never interpolated)."""
    if abs(src_dt * fps - 1.0) > 1e-6:
        return resample(local_rot, root_pos, src_dt, fps)
    return local_rot, root_pos


def to_smpl_motion(clip: BvhClip, name: str = "", subject: int = 0, elbow_reversed: str = "",
                   units=None, fps: float = sk.MODEL_FPS, floor: bool = True) -> sk.Motion:
    """Source BVH clip -> Motion on our skeleton at `fps` (see the module docstring)."""
    local, root, offsets = retarget_frames(clip, elbow_reversed, units, floor)
    local, root = at_rate(local, root, clip.frame_time, fps)
    m = sk.Motion(name=name, subject=int(subject), fps=float(fps), local_rot=local.astype(np.float32),
                  root_pos=root.astype(np.float32), offsets=offsets.astype(np.float32))
    # the checks above should leave nothing non-finite; training and evaluation must never see it
    what = {"local_rot": "joint rotations", "root_pos": "root positions", "offsets": "offsets"}
    bad = m.non_finite_field()
    if bad:
        raise _refused(clip, f"the retargeted {what[bad]} are not finite")
    return m


# --------------------------------------------------------------------------- the other way
def _depth_first_order(parents):
    children = [[] for _ in parents]
    for j, p in enumerate(parents):
        if p >= 0:
            children[p].append(j)
    out, stack = [], [0]
    while stack:
        j = stack.pop()
        out.append(j)
        stack.extend(reversed(children[j]))
    return out


SMPL_END_SITES = {10: (0.0, -sk.BALL_HEIGHT, 0.05), 11: (0.0, -sk.BALL_HEIGHT, 0.05), 15: (0.0, 0.2, 0.0),
                  22: (0.1, 0.0, 0.0), 23: (-0.1, 0.0, 0.0)}


def from_smpl_motion(motion: sk.Motion, unit: float = 0.01) -> BvhClip:
    """Motion -> BvhClip of our SMPL-24 skeleton (joint names of the contract, depth-first order,
    file units of `unit` metres, default centimetres). Reading it back with to_smpl_motion gives
    the same rotations (exactly: every joint maps "global")."""
    order = _depth_first_order(sk.PARENTS)
    new_index = {old: new for new, old in enumerate(order)}
    parents = [-1 if sk.PARENTS[o] < 0 else new_index[sk.PARENTS[o]] for o in order]
    s = motion.offsets[4, 1] / sk.DEFAULT_OFFSETS[4, 1]
    offsets = np.asarray(motion.offsets, dtype=np.float64)[order] / unit
    offsets[0] = 0.0
    ends = {new_index[j]: np.array(v) * s / unit for j, v in SMPL_END_SITES.items()}
    rot = np.asarray(motion.local_rot, dtype=np.float64)[:, order]
    chans = [["Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"]] + \
            [["Zrotation", "Xrotation", "Yrotation"]] * 23
    return BvhClip([sk.JOINT_NAMES[o] for o in order], parents, offsets, chans, 1.0 / motion.fps, rot,
                   np.asarray(motion.root_pos, dtype=np.float64) / unit, ends, None)


def to_source_clip(motion: sk.Motion, template: BvhClip, frame_step: int = 1, units=None) -> BvhClip:
    """Inverse retarget: our Motion -> a clip on the `template` source skeleton (Daz or cgspeed),
    every `frame_step`-th frame. Source joints without a mapping get identity local rotations.
    Exact inverse of retarget_frames (up to the floor shift) when our unmapped joints ("parent"
    mode) have identity local rotations in `motion`."""
    src = detect_source(template.joints)
    F0 = motion.num_frames
    idx = np.arange(0, F0, frame_step)
    local = np.asarray(motion.local_rot, dtype=np.float64)[idx]
    g, pos = sk.forward_kinematics(local, np.asarray(motion.root_pos, np.float64)[idx],
                                   np.asarray(motion.offsets, np.float64))
    rest = template.rest_positions()
    J = len(template.joints)
    F = len(idx)
    gs = np.full((F, J, 3, 3), np.nan)
    plan = _plan(template, units)
    for j in range(sk.NUM_JOINTS):
        mode, si, Q = plan.modes[j]
        if mode in ("global", "align") and si >= 0:
            gs[:, si] = g[:, j] @ Q.T
    rots = np.empty((F, J, 3, 3))
    for j in range(J):
        p = template.parents[j]
        if np.isnan(gs[0, j, 0, 0]):
            gs[:, j] = gs[:, p] if p >= 0 else np.eye(3)
        rots[:, j] = gs[:, j] if p < 0 else np.swapaxes(gs[:, p], -1, -2) @ gs[:, j]
    for j in range(sk.NUM_JOINTS):
        mode, si, Q = plan.modes[j]
        if mode == "local":
            rots[:, si] = local[:, j]
    # root: source hip-joint midpoint = our hip-joint midpoint
    hip_mid_ours = 0.5 * (pos[:, 1] + pos[:, 2]) / plan.unit
    h = plan.hip_idx
    tmp = BvhClip(template.joints, template.parents, template.offsets, template.channels, 1.0,
                  rots, np.zeros((F, 3)), template.end_sites, None)
    _, p_rel = tmp.global_transforms()
    root = hip_mid_ours - 0.5 * (p_rel[:, h[0]] + p_rel[:, h[1]])
    return BvhClip(list(template.joints), list(template.parents), template.offsets.copy(),
                   [list(c) for c in template.channels], frame_step / motion.fps, rots, root,
                   dict(template.end_sites), None)
