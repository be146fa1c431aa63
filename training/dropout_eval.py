"""missing-sensor: one sensor silent for a few seconds, scored through the engine's whole path.

    python3 -m training missing-sensor [--split val | --split test | --bvh DIR | --procedural]
        [--clips 15] [--clip-seconds 25] [--seconds 5] [--model M.onnx] [--sensors A,B,...]
        [--segments A,B,...] [--seed 0] [--out FILE] [--keep DIR]

For each clip (the first --clip-seconds of evenly spaced clips at least MIN_CLIP_S long) and each
condition, "none" then each segment of the capture's sensors in turn (--sensors: the capture's
sensor set, default the model's sensors; a contract-2 model's optional sensors can be left out of
it): synth_capture writes the capture (calibration prelude, realistic noise, random mountings and
headings) with that segment's sensor sending nothing for --seconds in the middle of the clip (`mocapctl synth --silence`), then
`mocapctl replay --model M --truth --pose-csv --metrics-json` runs it through decode -> filter ->
calibrate -> model -> output filter -> drift correction, and its poses are compared with the truth
frame by frame. Every condition of a clip uses the same seed, so its capture is byte for byte the
"none" capture outside the gap and the poses before the gap are the same.

Per condition (frames of all clips; windows in motion time):
  gap        the silent window; after: the RECOVERY_WINDOW_S after it; elsewhere: the rest
  angle      mean joint angle error, deg (24 joints, local rotations, joint 0 global; as mocapctl)
  pos        mean root-aligned joint position error, cm (the truth's own skeleton for both)
  bone       global orientation error of the silent sensor's bone in the gap, deg, and the
             same bone's in the "none" run (what the sensor's absence costs where it was)
  freeze     the longest stretch, s, in the gap and the window after it, in which the pose (body:
             mean root-aligned joint speed; bone: the silent bone's angular speed) moves at less
             than FREEZE_RATIO of the truth's speed while the truth moves (speeds averaged over
             SMOOTH_S); for the bone also in the "none" run
  broken     frames whose pose is not one a person takes, judged on the pose alone (pose_range.py:
             the training people's motion capture): a joint rotated out of its range or turning
             faster than people's do, a NaN, or a root step over EXPLODE_ROOT_STEP_M in one frame,
             in the gap and the window after it; also those that are not broken in the "none" run,
             by cause, and the joints that broke
  far off    frames with a NaN, a joint angle error over EXPLODE_ANGLE_DEG or a root step over
             EXPLODE_ROOT_STEP_M in one frame (the truth's pose is needed to tell: an arm posed
             hanging while the person's was raised is far off but not broken), the same windows;
             also those that are not far off in the "none" run (a hard clip's error can pass 90
             deg with every sensor), by cause: the pelvis's global rotation (a wrong heading),
             another joint, the root step, a NaN
  recovery   seconds from the gap's end until the angle and position errors (averaged over
             SMOOTH_S, frames after the gap only) are within RECOVERED_WITHIN of the "none" run's
             (plus a small absolute slack) and stay there for RECOVERY_HOLD_S; "never" when they
             do not before the clip ends
  incomplete the poses flagged MOCAP_POSE_INCOMPLETE in the gap (each should be) and outside it
             beyond those of the "none" run (none should be): the silence is where it was put
Writes OUT (default training/results/missing_sensor.md; training/results/test/missing_sensor.md
for --split test): the table, per-clip recovery times, and the command that made it.
"""
from __future__ import annotations

import argparse
import json
import math
import shlex
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import skeleton as sk
from .cli import POSITIVE_INT, NON_NEGATIVE_INT, number_type, sensor_option
from .errors import CommandError, UsageError
from .pose_range import OUT_OF_RANGE_DEG, SPEED_MARGIN, TOO_FAST_QUANTILE
from .sensors import DEFAULT_SENSORS, node_ids, sensor_bones

REPO = Path(__file__).resolve().parent.parent
MODELS_DIR = REPO / "Packages" / "com.mocap.imu" / "Runtime" / "Models"
DEFAULT_MODEL = MODELS_DIR / "mocap_pose_int8.onnx"
RESULTS_DIR = REPO / "training" / "results"
NONE = "none"

GAP_S = 5.0
LEAD_IN_S = 1.0              # synth_capture's blend from the T-pose into the clip
MIN_CLIP_S = 20.0            # clips shorter than this are not used from a split or folder
CLIP_S = 25.0                # longer ones are cut to this
RECOVERY_WINDOW_S = 2.0
# Gap edges are put on multiples of this: a tick of both the sensors' 100 Hz and the poses'
# 60 Hz, so that the first and last pose of a gap are those of its first and last silent sample.
GRID_S = 0.05
SMOOTH_S = 0.5               # averaging of speeds and errors before thresholds are applied
RECOVERED_WITHIN = 0.20      # recovered: error <= (1 + this) x the "none" run's ...
RECOVERY_SLACK_DEG = 0.5     # ... + this much, so that a near-zero reference is not all noise
RECOVERY_SLACK_CM = 0.3
RECOVERY_HOLD_S = 1.0        # ... for this long
FREEZE_RATIO = 0.2           # frozen: moves at less than this fraction of the truth's speed ...
BODY_MOVING_M_S = 0.10       # ... while the truth's joints move at least this fast (mean)
BONE_MOVING_DEG_S = 20.0     # ... or the truth's bone turns at least this fast
EXPLODE_ANGLE_DEG = 90.0
EXPLODE_ROOT_STEP_M = 0.5
POSE_INCOMPLETE = 1 << 3     # MOCAP_POSE_INCOMPLETE of mocap_imu.h
POSE_CSV_FIRST_QUAT = 12     # sequence, frame_sequence, time_s, flags, root xyz, vel xyz, contacts


# ------------------------------------------------------------------------------ frame metrics
def moving_average(x, n: int) -> np.ndarray:
    """Centred mean over n frames (n odd; the window shrinks at the ends), along axis 0."""
    x = np.asarray(x, np.float64)
    if n <= 1 or len(x) == 0:
        return x.copy()
    h = n // 2
    c = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0)])
    idx = np.arange(len(x))
    lo, hi = np.maximum(idx - h, 0), np.minimum(idx + h + 1, len(x))
    count = (hi - lo).reshape((-1,) + (1,) * (x.ndim - 1))
    return (c[hi] - c[lo]) / count


def smoothing_frames(fps: float) -> int:
    return max(1, int(round(SMOOTH_S * fps)) | 1)


def longest_run(mask) -> int:
    """Length of the longest run of True."""
    best = run = 0
    for v in np.asarray(mask, bool):
        run = run + 1 if v else 0
        best = max(best, run)
    return best


def frozen_frames(pred_speed, true_speed, fps: float, moving: float) -> np.ndarray:
    """Frames where the prediction moves at less than FREEZE_RATIO of the truth's speed while the
    truth moves at least `moving` (both averaged over SMOOTH_S: a swing's turning points are not
    pauses)."""
    n = smoothing_frames(fps)
    p, t = moving_average(pred_speed, n), moving_average(true_speed, n)
    return (t >= moving) & (p < FREEZE_RATIO * t)


def longest_freeze(pred_speed, true_speed, fps: float, moving: float, window=None) -> float:
    """Seconds of the longest stretch of frozen_frames (within the window mask, when given)."""
    frozen = frozen_frames(pred_speed, true_speed, fps, moving)
    if window is not None:
        frozen &= np.asarray(window, bool)
    return longest_run(frozen) / fps


EXPLODE_CAUSES = ("pelvis", "joint", "root", "nan")


def explosion_causes(angle_err, pred_root, finite) -> dict:
    """Per frame, each cause of an explosion: "pelvis" (joint 0's global angle error, angle_err
    (T,J) deg, over EXPLODE_ANGLE_DEG), "joint" (another joint's), "root" (a root step over
    EXPLODE_ROOT_STEP_M from the frame before), "nan" (a non-finite pose or angle)."""
    angle_err = np.asarray(angle_err, np.float64)
    nan = ~np.asarray(finite, bool) | np.any(np.isnan(angle_err), axis=-1)
    root = np.asarray(pred_root, np.float64)
    step = np.zeros(len(root))
    step[1:] = np.linalg.norm(np.diff(root, axis=0), axis=-1)
    return {"pelvis": angle_err[:, 0] > EXPLODE_ANGLE_DEG,
            "joint": np.any(angle_err[:, 1:] > EXPLODE_ANGLE_DEG, axis=-1),
            "root": ~(step <= EXPLODE_ROOT_STEP_M), "nan": nan}


BROKEN_CAUSES = ("range", "speed", "root", "nan")


def broken_causes(pose_range, pred_local, pred_root, finite, fps: float) -> tuple:
    """Per frame, each cause of a broken pose ("range": a joint out of the pose range, "speed": a
    joint turning too fast, "root": a root step over EXPLODE_ROOT_STEP_M, "nan"), and (T, 24) the
    joints out of range or too fast."""
    finite = np.asarray(finite, bool)
    bad = pose_range.implausible(pred_local, fps)
    out_of_range = bad["range"] & finite[:, None]
    too_fast = bad["speed"] & finite[:, None]
    root = np.asarray(pred_root, np.float64)
    step = np.zeros(len(root))
    step[1:] = np.linalg.norm(np.diff(root, axis=0), axis=-1)
    causes = {"range": out_of_range.any(axis=-1), "speed": too_fast.any(axis=-1),
              "root": ~(step <= EXPLODE_ROOT_STEP_M), "nan": ~finite}
    return causes, out_of_range | too_fast


def exploded_frames(angle_err, pred_root, finite) -> np.ndarray:
    """Frames with any of explosion_causes."""
    causes = explosion_causes(angle_err, pred_root, finite)
    return np.logical_or.reduce([causes[c] for c in EXPLODE_CAUSES])


def recovery_time(t, errors, references, slacks, gap_end: float, fps: float) -> float:
    """Seconds after gap_end until every error series (frames after the gap only, averaged over
    SMOOTH_S) is within RECOVERED_WITHIN of its reference + slack and stays so for
    RECOVERY_HOLD_S; inf when that never happens before the end."""
    t = np.asarray(t, np.float64)
    after = t >= gap_end - 0.5 / fps
    if not after.any():
        return math.inf
    n = smoothing_frames(fps)
    ok = np.ones(int(after.sum()), bool)
    for err, ref, slack in zip(errors, references, slacks):
        e = moving_average(np.asarray(err, np.float64)[after], n)
        r = moving_average(np.asarray(ref, np.float64)[after], n)
        ok &= e <= (1.0 + RECOVERED_WITHIN) * r + slack
    hold = max(1, int(round(RECOVERY_HOLD_S * fps)))
    if len(ok) < hold:
        return math.inf
    # ok[k:k+hold] all true <=> the count of true in that window is hold.
    c = np.concatenate([[0], np.cumsum(ok)])
    full = np.nonzero(c[hold:] - c[:-hold] == hold)[0]
    if len(full) == 0:
        return math.inf
    return max(0.0, float(t[after][full[0]] - gap_end))


def angular_speed_deg(rot, fps: float) -> np.ndarray:
    """(T,...,3,3) -> (T,...) deg/s between consecutive frames (frame 0 repeats frame 1)."""
    from .evaluate import rotation_angle_deg
    if len(rot) < 2:
        return np.zeros(rot.shape[:-2])
    s = rotation_angle_deg(rot[1:], rot[:-1]) * fps
    return np.concatenate([s[:1], s])


def joint_speed(positions, fps: float) -> np.ndarray:
    """(T,J,3) root-aligned positions -> (T,) mean joint speed, m/s."""
    if len(positions) < 2:
        return np.zeros(len(positions))
    s = np.linalg.norm(np.diff(positions, axis=0), axis=-1).mean(axis=-1) * fps
    return np.concatenate([s[:1], s])


# ------------------------------------------------------------------------------ one replay
@dataclass
class Run:
    """One replay's poses at truth frames, with the truth (all in motion time, t = 0 at truth
    frame 0 = the start of the lead-in)."""
    t: np.ndarray            # (T,) s
    fps: float
    flags: np.ndarray        # (T,) MOCAP_POSE_* of each pose
    pred_local: np.ndarray   # (T,24,3,3)
    pred_root: np.ndarray    # (T,3) drift-corrected root, m
    true_local: np.ndarray
    offsets: np.ndarray
    finite: np.ndarray       # (T,) the pose had no NaN/inf
    metrics: dict            # mocapctl's --metrics-json


@dataclass
class FrameErrors:
    angle: np.ndarray        # (T,24) deg
    pos_cm: np.ndarray       # (T,) mean over joints
    global_rot: np.ndarray   # (T,24,3,3) predicted
    true_global: np.ndarray
    body_speed: np.ndarray   # (T,) m/s, prediction
    true_body_speed: np.ndarray


def read_pose_csv(path):
    """mocapctl replay --pose-csv: (time_s (P,), flags (P,), root (P,3), quats (P,24,4))."""
    with open(path) as f:
        header = f.readline().rstrip("\n").split(",")
    expected = POSE_CSV_FIRST_QUAT + 24 * 4
    if len(header) != expected or header[2] != "time_s" or header[3] != "flags":
        raise CommandError(f"{path}: not a pose CSV of mocapctl replay ({len(header)} columns, "
                           f"expected {expected})")
    a = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if a.shape[0] == 0:
        raise CommandError(f"{path}: no poses")
    return (a[:, 2], a[:, 3].astype(np.int64), a[:, 4:7],
            a[:, POSE_CSV_FIRST_QUAT:].reshape(-1, 24, 4))


def align_to_truth(time_s, flags, root, quats, truth: dict, metrics: dict) -> Run:
    """Poses at their session times -> the truth frames they fall on (the truth slerped where a
    pose falls between two of its frames, as mocapctl's own metrics do); poses outside the truth
    are dropped."""
    fps = float(truth["fps"])
    t0 = float(truth["t_session_start"])
    n = truth["local_rot"].shape[0]
    x = (np.asarray(time_s, np.float64) - t0) * fps
    keep = (x >= -1e-6) & (x <= n - 1 + 1e-6)
    if not keep.any():
        raise CommandError("no pose falls on the truth's frames")
    x = np.clip(x[keep], 0, n - 1)
    # Pose times are printed to 1 us: a pose on a truth frame is put exactly on it, so that
    # window edges do not depend on the last printed digit.
    on_frame = np.abs(x - np.round(x)) < 1e-3
    x[on_frame] = np.round(x[on_frame])
    i0 = np.floor(x + 1e-6).astype(int).clip(0, n - 1)
    i1 = np.minimum(i0 + 1, n - 1)
    w = np.clip(x - i0, 0.0, 1.0)
    tq = sk.quat_from_rot(truth["local_rot"])
    true_q = sk.slerp_quat(tq[i0], tq[i1], np.broadcast_to(w[:, None], (len(w), 24)))
    q = np.asarray(quats, np.float64)[keep]
    finite = np.isfinite(q).all(axis=(1, 2)) & np.isfinite(root[keep]).all(axis=1)
    safe_q = np.where(np.isfinite(q), q, 0.0)
    safe_q[~(np.linalg.norm(safe_q, axis=-1) > 0)] = (1.0, 0.0, 0.0, 0.0)
    pred = sk.rot_from_quat(safe_q)
    pred[~finite] = np.nan
    return Run(t=x / fps, fps=fps, flags=np.asarray(flags)[keep], pred_local=pred,
               pred_root=np.asarray(root, np.float64)[keep], true_local=sk.rot_from_quat(true_q),
               offsets=np.asarray(truth["offsets"], np.float64), finite=finite, metrics=metrics)


def frame_errors(run: Run) -> FrameErrors:
    from .evaluate import root_aligned_positions, rotation_angle_deg
    angle = rotation_angle_deg(run.pred_local, run.true_local)
    angle[~run.finite] = np.nan
    g, p = root_aligned_positions(np.nan_to_num(run.pred_local), run.offsets)
    tg, tp = root_aligned_positions(run.true_local, run.offsets)
    pos = np.linalg.norm(p - tp, axis=-1).mean(axis=-1) * 100.0
    pos[~run.finite] = np.nan
    return FrameErrors(angle, pos, g, tg, joint_speed(p, run.fps), joint_speed(tp, run.fps))


def session_sensors_argument(sensors) -> str:
    """mocapctl's --sensors for a capture of these segments (node ids as synth_capture gives
    them)."""
    return ",".join(f"{name}={node}" for name, node in zip(sensors, node_ids(sensors)))


def rule_options(pose_limits: float = 0.0, chest_follow: float = 0.0) -> tuple:
    """mocapctl's options for the engine's rules after the network: the pose guard
    (--pose-limits DEG) and chest following (--chest-follow SHARE); 0 leaves a rule off."""
    return ((("--pose-limits", f"{pose_limits:g}") if pose_limits else ())
            + (("--chest-follow", f"{chest_follow:g}") if chest_follow else ()))


def replay_command(mocapctl, capture, truth_csv, model, poses, metrics, sensors=DEFAULT_SENSORS,
                   rules: tuple = ()) -> list:
    """mocapctl replay of a capture of these sensors through the model, against its truth, with
    the poses and the accuracy figures written to files; rules: rule_options' options."""
    cmd = [str(mocapctl), "replay", str(capture), "--model", str(model), "--truth", str(truth_csv),
           "--pose-csv", str(poses), "--metrics-json", str(metrics)]
    if tuple(sensors) != tuple(DEFAULT_SENSORS):
        cmd += ["--sensors", session_sensors_argument(sensors)]
    return cmd + list(rules)


def replay(mocapctl, capture: Path, truth_csv: Path, model, workdir: Path, stem: str,
           sensors=DEFAULT_SENSORS, rules: tuple = ()):
    """mocapctl replay with the model, a session of the capture's sensors: (time_s, flags, root,
    quats, metrics json)."""
    poses, metrics = workdir / f"{stem}.poses.csv", workdir / f"{stem}.metrics.json"
    cmd = replay_command(mocapctl, capture, truth_csv, model, poses, metrics, sensors, rules)
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise CommandError(f"mocapctl replay {capture.name} failed (status {r.returncode}): "
                           + (r.stderr.strip() or r.stdout.strip()[-500:]))
    return (*read_pose_csv(poses), json.loads(metrics.read_text()))


# ------------------------------------------------------------------------------ one condition
@dataclass
class Windows:
    gap_start: float
    gap_end: float

    def masks(self, t) -> dict:
        """Half-open windows of motion time; a frame on an edge belongs to the later window."""
        t = np.asarray(t) + 1e-9
        gap = (t >= self.gap_start) & (t < self.gap_end)
        after = (t >= self.gap_end) & (t < self.gap_end + RECOVERY_WINDOW_S)
        return {"gap": gap, "after": after, "elsewhere": ~(gap | after),
                "before": t < self.gap_start}


@dataclass
class ConditionScore:
    """One clip, one condition."""
    clip: str
    condition: str
    frames: dict                 # window -> frame count
    angle: dict                  # window -> sum of per-frame mean angle errors (deg)
    pos: dict                    # window -> sum (cm)
    bone: float = math.nan       # silent bone's global error in the gap, mean deg
    bone_ref: float = math.nan   # the same bone in the "none" run
    freeze_body: float = 0.0     # s, gap + after
    freeze_bone: float = math.nan
    freeze_bone_ref: float = math.nan
    explode: int = 0             # frames, gap + after
    explode_elsewhere: int = 0
    explode_extra: int = 0       # gap + after, not exploding in the "none" run
    explode_extra_causes: dict = field(default_factory=dict)   # cause -> frames of explode_extra
    explode_extra_joints: dict = field(default_factory=dict)   # joint -> new frames over the angle
    broken: int | None = None    # frames, gap + after (None: not measured, no pose range)
    broken_elsewhere: int | None = None
    broken_extra: int | None = None   # gap + after, not broken in the "none" run
    broken_extra_causes: dict = field(default_factory=dict)    # cause -> frames of broken_extra
    broken_extra_joints: dict = field(default_factory=dict)    # joint -> new broken frames
    recovery: float = math.nan   # s (inf: never)
    incomplete_in_gap: int = 0
    incomplete_extra: int = 0    # flagged outside the gap beyond the "none" run
    same_before_gap: float = math.nan   # largest angle difference to "none" before the gap, deg
    angle_all: float = math.nan  # mean over every frame (mocapctl's angle_error_deg measures the same)
    metrics: dict = field(default_factory=dict)


def score_condition(clip: str, condition: str, run: Run, err: FrameErrors, windows: Windows,
                    ref: tuple | None = None, bone: int | None = None,
                    pose_range=None) -> ConditionScore:
    """The scores of one run; ref = (Run, FrameErrors) of the clip's "none" run (same frames);
    pose_range (pose_range.PoseRange): what a broken pose is (without one, none is counted)."""
    m = windows.masks(run.t)
    per_frame_angle = np.nanmean(err.angle, axis=-1) if len(err.angle) else np.zeros(0)
    windows3 = ("gap", "after", "elsewhere")
    s = ConditionScore(clip, condition, {k: int(m[k].sum()) for k in windows3},
                       {k: float(np.nansum(per_frame_angle[m[k]])) for k in windows3},
                       {k: float(np.nansum(err.pos_cm[m[k]])) for k in windows3}, metrics=run.metrics)
    s.angle_all = float(np.nanmean(per_frame_angle)) if len(per_frame_angle) else math.nan
    around = m["gap"] | m["after"]
    s.freeze_body = longest_freeze(err.body_speed, err.true_body_speed, run.fps, BODY_MOVING_M_S, around)
    causes = explosion_causes(err.angle, run.pred_root, run.finite)
    exploded = np.logical_or.reduce([causes[c] for c in EXPLODE_CAUSES])
    s.explode, s.explode_elsewhere = int(exploded[around].sum()), int(exploded[m["elsewhere"]].sum())
    if pose_range is not None:
        broken_by, broken_joints = broken_causes(pose_range, run.pred_local, run.pred_root,
                                                 run.finite, run.fps)
        broken = np.logical_or.reduce([broken_by[c] for c in BROKEN_CAUSES])
        s.broken, s.broken_elsewhere = int(broken[around].sum()), int(broken[m["elsewhere"]].sum())
    incomplete = (run.flags & POSE_INCOMPLETE) != 0
    s.incomplete_in_gap = int(incomplete[m["gap"]].sum())
    if bone is not None:
        from .evaluate import rotation_angle_deg
        bone_err = rotation_angle_deg(err.global_rot[:, bone], err.true_global[:, bone])
        s.bone = float(np.nanmean(bone_err[m["gap"]])) if m["gap"].any() else math.nan
        s.freeze_bone = longest_freeze(angular_speed_deg(err.global_rot[:, bone], run.fps),
                                       angular_speed_deg(err.true_global[:, bone], run.fps),
                                       run.fps, BONE_MOVING_DEG_S, around)
    if ref is not None:
        ref_run, ref_err = ref
        if len(ref_run.t) != len(run.t) or not np.allclose(ref_run.t, run.t):
            raise CommandError(f"{clip}: the {condition} replay has other frames than the one "
                               f"without a gap ({len(run.t)} against {len(ref_run.t)} poses)")
        extra = exploded & around & ~exploded_frames(ref_err.angle, ref_run.pred_root, ref_run.finite)
        s.explode_extra = int(extra.sum())
        s.explode_extra_causes = {c: int((causes[c] & extra).sum()) for c in EXPLODE_CAUSES}
        over = (err.angle > EXPLODE_ANGLE_DEG) & extra[:, None]
        s.explode_extra_joints = {int(j): int(over[:, j].sum()) for j in np.nonzero(over.any(0))[0]}
        if pose_range is not None:
            ref_by, _ = broken_causes(pose_range, ref_run.pred_local, ref_run.pred_root,
                                      ref_run.finite, ref_run.fps)
            new = broken & around & ~np.logical_or.reduce([ref_by[c] for c in BROKEN_CAUSES])
            s.broken_extra = int(new.sum())
            s.broken_extra_causes = {c: int((broken_by[c] & new).sum()) for c in BROKEN_CAUSES}
            joints = broken_joints & new[:, None]
            s.broken_extra_joints = {int(j): int(joints[:, j].sum())
                                     for j in np.nonzero(joints.any(0))[0]}
        ref_incomplete = (ref_run.flags & POSE_INCOMPLETE) != 0
        s.incomplete_extra = int((incomplete & ~ref_incomplete & ~m["gap"]).sum())
        before = m["before"]
        if before.any():
            s.same_before_gap = float(np.nanmax(np.abs(err.angle[before] - ref_err.angle[before])))
        ref_angle = np.nanmean(ref_err.angle, axis=-1)
        s.recovery = recovery_time(run.t, [per_frame_angle, err.pos_cm], [ref_angle, ref_err.pos_cm],
                                   [RECOVERY_SLACK_DEG, RECOVERY_SLACK_CM], windows.gap_end, run.fps)
        if bone is not None:
            from .evaluate import rotation_angle_deg
            ref_bone = rotation_angle_deg(ref_err.global_rot[:, bone], ref_err.true_global[:, bone])
            s.bone_ref = float(np.nanmean(ref_bone[m["gap"]])) if m["gap"].any() else math.nan
            s.freeze_bone_ref = longest_freeze(
                angular_speed_deg(ref_err.global_rot[:, bone], run.fps),
                angular_speed_deg(ref_err.true_global[:, bone], run.fps), run.fps,
                BONE_MOVING_DEG_S, around)
    return s


# ------------------------------------------------------------------------------ one clip
def on_grid(seconds: float) -> float:
    return round(seconds / GRID_S) * GRID_S


def gap_window(motion: sk.Motion, gap_s: float, lead_in: float = LEAD_IN_S) -> Windows:
    """The gap in the middle of the clip itself (motion time: the lead-in comes first), its
    edges on GRID_S."""
    clip_s = motion.num_frames / motion.fps
    if clip_s < gap_s + 2 * RECOVERY_WINDOW_S:
        raise UsageError(f"{motion.name}: {clip_s:.1f} s is too short for a {gap_s:g} s gap with "
                         f"{RECOVERY_WINDOW_S:g} s on either side")
    start = on_grid(lead_in + (clip_s - gap_s) / 2.0)
    return Windows(start, start + max(GRID_S, on_grid(gap_s)))


def evaluate_clip(motion: sk.Motion, segments, gap_s: float, model, workdir: Path, seed: int,
                  world: str = "enu", mocapctl=None, sensors=DEFAULT_SENSORS,
                  pose_range=None, rules: tuple = ()) -> list:
    """Every condition ("none" first, then each segment silent) of one clip -> [ConditionScore].
    sensors: the capture's (and the session's) sensor set; pose_range: see score_condition;
    rules: the engine's rules after the network (rule_options)."""
    from .ort import mocapctl_path
    from .synth_capture import Silence, load_truth, synth_capture
    mocapctl = mocapctl or mocapctl_path(require_onnx=True)
    windows = gap_window(motion, gap_s)
    sensors = tuple(sensors)
    bones = dict(zip(sensors, sensor_bones("hand", sensors)))
    scores, ref = [], None
    for condition in (NONE, *segments):
        stem = f"{motion.name}-{condition}"
        cap = workdir / f"{stem}.cap"
        silences = () if condition == NONE else (
            Silence(condition, windows.gap_start, windows.gap_end - windows.gap_start),)
        synth_capture(None, cap, motion=motion, seed=seed, world=world, lead_in=LEAD_IN_S,
                      silences=silences, sensors=sensors)
        truth = load_truth(cap.with_suffix(".truth.npz"))
        time_s, flags, root, quats, metrics = replay(mocapctl, cap, cap.with_suffix(".truth.csv"),
                                                     model, workdir, stem, sensors, rules)
        run = align_to_truth(time_s, flags, root, quats, truth, metrics)
        err = frame_errors(run)
        bone = None if condition == NONE else bones[condition]
        scores.append(score_condition(motion.name, condition, run, err, windows,
                                      ref=None if condition == NONE else ref, bone=bone,
                                      pose_range=pose_range))
        if condition == NONE:
            ref = (run, err)
    return scores


# ------------------------------------------------------------------------------ clips
def choose_clips(motions, count: int, clip_s: float = CLIP_S, min_s: float = MIN_CLIP_S) -> list:
    """`count` evenly spaced clips (in clip order) of at least min_s seconds, cut to clip_s."""
    long_enough = [m for m in motions if m.num_frames / m.fps >= min_s - 1e-9]
    if not long_enough:
        raise UsageError(f"no clip is {min_s:g} s or longer")
    if count < len(long_enough):
        picks = np.unique(np.round(np.linspace(0, len(long_enough) - 1, count)).astype(int))
        long_enough = [long_enough[i] for i in picks]
    out = []
    for m in long_enough:
        n = min(m.num_frames, int(round(clip_s * m.fps)))
        out.append(sk.Motion(m.name, m.subject, m.fps, m.local_rot[:n], m.root_pos[:n], m.offsets))
    return out


def procedural_clips(count: int, clip_s: float, seed: int) -> list:
    from .procedural import KINDS, make_motion
    return [make_motion(KINDS[i % len(KINDS)], clip_s, seed=seed + i,
                        name=f"procedural-{KINDS[i % len(KINDS)]}-{i}") for i in range(count)]


# ------------------------------------------------------------------------------ report
def _mean(num: float, den: int) -> float:
    return num / den if den else math.nan


def _fmt(v, digits=2) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if isinstance(v, float) and math.isinf(v):
        return "never"
    return f"{v:.{digits}f}"


def _sum_counts(counts) -> dict:
    total = {}
    for c in counts:
        for k, v in c.items():
            total[k] = total.get(k, 0) + v
    return total


def _sum_measured(values):
    """The sum, or None when a value was not measured."""
    values = list(values)
    return None if any(v is None for v in values) else sum(values)


def _count(v) -> str:
    return "-" if v is None else str(v)


def _top_joints(counts: dict, n: int = 3) -> str:
    top = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))[:n]
    return ", ".join(f"{sk.JOINT_NAMES[j]} {v}" for j, v in top) or "-"


def summarize(scores) -> dict:
    """Condition -> the figures of the table, over all clips."""
    out = {}
    for cond in dict.fromkeys(s.condition for s in scores):
        rows = [s for s in scores if s.condition == cond]
        frames = {w: sum(r.frames[w] for r in rows) for w in ("gap", "after", "elsewhere")}
        rec = [r.recovery for r in rows if not math.isnan(r.recovery)]
        finite_rec = [v for v in rec if math.isfinite(v)]
        out[cond] = {
            "clips": len(rows),
            **{f"angle_{w}": _mean(sum(r.angle[w] for r in rows), frames[w]) for w in frames},
            **{f"pos_{w}": _mean(sum(r.pos[w] for r in rows), frames[w]) for w in frames},
            "bone": float(np.nanmean([r.bone for r in rows])) if cond != NONE else math.nan,
            "bone_ref": float(np.nanmean([r.bone_ref for r in rows])) if cond != NONE else math.nan,
            "freeze_body": max(r.freeze_body for r in rows),
            "freeze_bone": max(r.freeze_bone for r in rows) if cond != NONE else math.nan,
            "freeze_bone_ref": max(r.freeze_bone_ref for r in rows) if cond != NONE else math.nan,
            "explode": sum(r.explode for r in rows),
            "explode_elsewhere": sum(r.explode_elsewhere for r in rows),
            "explode_extra": sum(r.explode_extra for r in rows),
            **{f"explode_extra_{c}": sum(r.explode_extra_causes.get(c, 0) for r in rows)
               for c in EXPLODE_CAUSES},
            "explode_extra_clips": sum(1 for r in rows if r.explode_extra),
            "explode_extra_joints": _sum_counts(r.explode_extra_joints for r in rows),
            "broken": _sum_measured(r.broken for r in rows),
            "broken_elsewhere": _sum_measured(r.broken_elsewhere for r in rows),
            "broken_extra": _sum_measured(r.broken_extra for r in rows),
            **{f"broken_extra_{c}": sum(r.broken_extra_causes.get(c, 0) for r in rows)
               for c in BROKEN_CAUSES},
            "broken_extra_clips": sum(1 for r in rows if r.broken_extra),
            "broken_extra_joints": _sum_counts(r.broken_extra_joints for r in rows),
            "drift_5s": float(np.mean([(r.metrics.get("root_drift_m") or {}).get("5s") or math.nan
                                       for r in rows])),
            "drift_10s": float(np.mean([(r.metrics.get("root_drift_m") or {}).get("10s") or math.nan
                                        for r in rows])),
            "recovery_median": float(np.median(finite_rec)) if finite_rec else (math.inf if rec else math.nan),
            "recovery_max": (max(rec) if rec else math.nan),
            "never_recovered": sum(1 for v in rec if math.isinf(v)),
            "incomplete_in_gap": sum(r.incomplete_in_gap for r in rows),
            "gap_frames": frames["gap"],
            "incomplete_extra": sum(r.incomplete_extra for r in rows),
            "same_before_gap": (float(np.nanmax([r.same_before_gap for r in rows]))
                                if cond != NONE else math.nan),
            "engine_angle": float(np.mean([r.metrics.get("angle_error_deg") or math.nan for r in rows])),
            "module_angle": float(np.mean([r.angle_all for r in rows])),
        }
    return out


def findings(summary) -> list:
    """The table's answers to the questions asked of it, in words (computed, not written by
    hand, so that a rerun keeps them true)."""
    ref = summary[NONE]
    conds = [c for c in summary if c != NONE]
    by_gap = sorted(conds, key=lambda c: summary[c]["angle_gap"], reverse=True)
    worst, others = by_gap[0], by_gap[1:]
    v = summary[worst]
    out = ["## What it shows", "",
           f"- **Error while missing**: without the {worst} sensor the gap's error is "
           f"{_fmt(v['angle_gap'])} deg / {_fmt(v['pos_gap'])} cm against {_fmt(ref['angle_gap'])} / "
           f"{_fmt(ref['pos_gap'])} with every sensor"
           + (f"; without another sensor {_fmt(min(summary[c]['angle_gap'] for c in others))} - "
              f"{_fmt(max(summary[c]['angle_gap'] for c in others))} deg / "
              f"{_fmt(min(summary[c]['pos_gap'] for c in others))} - "
              f"{_fmt(max(summary[c]['pos_gap'] for c in others))} cm" if others else "")
           + ". The bone the missing sensor reports is off by "
           + ", ".join(f"{c} {_fmt(summary[c]['bone'], 0)}" for c in conds)
           + " deg (mean over the gap; "
           + f"{_fmt(min(summary[c]['bone_ref'] for c in conds), 0)} - "
             f"{_fmt(max(summary[c]['bone_ref'] for c in conds), 0)} with every sensor)."]
    body = max(summary[c]["freeze_body"] for c in conds)
    bone_c = max(conds, key=lambda c: summary[c]["freeze_bone"])
    out.append(f"- **Freeze**: the body as a whole " + ("never froze" if body == 0 else
               f"froze for {_fmt(body, 1)} s at most") + f"; the missing sensor's own bone stopped "
               f"while the truth moved for up to {_fmt(summary[bone_c]['freeze_bone'], 1)} s "
               f"({bone_c}), and for at most "
               f"{_fmt(max(summary[c]['freeze_bone_ref'] for c in conds), 1)} s with every sensor.")
    if all(summary[c]["broken_extra"] is not None for c in conds):
        broken = {cause: sum(summary[c][f"broken_extra_{cause}"] for c in conds) for cause in BROKEN_CAUSES}
        total = sum(summary[c]["broken_extra"] for c in conds)
        out.append(f"- **Explode** (a pose no person takes, judged on the pose alone): "
                   + ("no silent sensor broke a pose that was whole with every sensor" if total == 0
                      else f"{total} new broken frames: " + ", ".join(
                          f"{c} {summary[c]['broken_extra']} "
                          f"({_top_joints(summary[c]['broken_extra_joints'], 2)})"
                          for c in conds if summary[c]["broken_extra"]))
                   + f" ({broken['range']} with a joint out of its range, {broken['speed']} turning "
                   f"too fast, {broken['root']} root steps over {EXPLODE_ROOT_STEP_M:g} m, "
                   f"{broken['nan']} NaN); with every sensor {ref['broken']} frames of the same "
                   f"windows are broken.")
    new = {cause: sum(summary[c][f"explode_extra_{cause}"] for c in conds) for cause in EXPLODE_CAUSES}
    out.append(f"- **Far off** (the truth's pose needed to tell): {new['nan']} NaN poses and "
               f"{new['root']} new root steps over "
               f"{EXPLODE_ROOT_STEP_M:g} m; new frames with an error over {EXPLODE_ANGLE_DEG:g} deg: "
               + ", ".join(f"{c} {summary[c]['explode_extra']} "
                           f"({_top_joints(summary[c]['explode_extra_joints'], 2)})" for c in conds)
               + f" (of the pelvis's, {summary.get('pelvis', {}).get('explode_extra_pelvis', 0)} are "
               f"its global rotation: a heading left behind).")
    never = sum(summary[c]["never_recovered"] for c in conds)
    slow_c = max(conds, key=lambda c: summary[c]["recovery_max"])
    out.append(f"- **Recovery**: " + ("every condition of every clip recovered" if never == 0 else
               f"{never} condition runs never recovered") + f"; the median time is "
               + ", ".join(f"{c} {_fmt(summary[c]['recovery_median'])}" for c in conds)
               + f" s, the slowest {_fmt(summary[slow_c]['recovery_max'])} s ({slow_c}). In the "
               f"{RECOVERY_WINDOW_S:g} s after the gap the error is "
               f"{_fmt(min(summary[c]['angle_after'] for c in conds))} - "
               f"{_fmt(max(summary[c]['angle_after'] for c in conds))} deg against "
               f"{_fmt(ref['angle_after'])} with every sensor.")
    return out


def cause_rows(summary, kind: str, causes) -> list:
    """One table row per condition: its frames of `kind` ("broken" or "explode"), the new ones,
    those by cause, the joints most often involved, and those elsewhere."""
    rows = []
    for cond, v in summary.items():
        new = "-" if cond == NONE else v[f"{kind}_extra"]
        why = ["-"] * len(causes) if cond == NONE else [str(v[f"{kind}_extra_{c}"]) for c in causes]
        joints = "-" if cond == NONE else _top_joints(v[f"{kind}_extra_joints"])
        rows.append(f"| {cond} | {v[kind]} | {new} | " + " | ".join(why) +
                    f" | {joints} | {v[f'{kind}_elsewhere']} |")
    return rows


def write_report(path: Path, scores, meta: dict) -> Path:
    summary = summarize(scores)
    lines = [f"# One sensor missing for {meta['gap_s']:g} s, through the engine", "",
             f"{meta['clips']} clips ({meta['source']}, {meta['seconds']:.0f} s of motion in all), "
             f"each replayed {len(summary)} times by `mocapctl replay` through the model "
             f"`{meta['model']}` (contract {meta['contract']}, the engine's default output filter): "
             f"once with every sensor, then with each sensor sending nothing for {meta['gap_s']:g} s "
             f"in the middle of the clip (`mocapctl synth --silence`; the same seed, so the "
             f"capture is the same outside the gap). Made by:", "",
             f"    {meta['command']}", "",
             f"({meta['elapsed_s'] / 60:.1f} min on this machine.) Windows: *gap* the silent "
             f"{meta['gap_s']:g} s, *after* the {RECOVERY_WINDOW_S:g} s after it, *elsewhere* the "
             f"rest of the replay (lead-in and clip). Errors are means over frames: joint angle "
             f"(24 joints, local, deg) and root-aligned joint position (cm). The module docstring "
             f"of `training/dropout_eval.py` defines each column.", "",
             "| missing | angle gap | angle after | angle elsewhere | pos gap | pos after | pos elsewhere "
             "| its bone in the gap, deg (all sensors) | longest freeze s: body / its bone (all sensors) "
             "| broken frames, new (clips) | frames > 90 deg off, new (clips) "
             "| recovery s: median / worst (never) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for cond, v in summary.items():
        if cond == NONE:
            bone = rec = new = broken = "-"
            freeze = f"{_fmt(v['freeze_body'], 1)} / -"
        else:
            new = f"{v['explode_extra']} ({v['explode_extra_clips']})"
            broken = ("-" if v["broken_extra"] is None
                      else f"{v['broken_extra']} ({v['broken_extra_clips']})")
            bone = f"{_fmt(v['bone'], 1)} ({_fmt(v['bone_ref'], 1)})"
            freeze = (f"{_fmt(v['freeze_body'], 1)} / {_fmt(v['freeze_bone'], 1)} "
                      f"({_fmt(v['freeze_bone_ref'], 1)})")
            rec = (f"{_fmt(v['recovery_median'], 2)} / {_fmt(v['recovery_max'], 2)} "
                   f"({v['never_recovered']})")
        lines.append(f"| {cond} | {_fmt(v['angle_gap'])} | {_fmt(v['angle_after'])} | "
                     f"{_fmt(v['angle_elsewhere'])} | {_fmt(v['pos_gap'])} | {_fmt(v['pos_after'])} | "
                     f"{_fmt(v['pos_elsewhere'])} | {bone} | {freeze} | {broken} | {new} | {rec} |")
    if all(v["broken"] is not None for v in summary.values()):
        lines += ["", f"Broken poses in the gap and the {RECOVERY_WINDOW_S:g} s after it (all clips), "
                  f"judged on the pose alone against the training people's range of motion: every "
                  f"one, those that are whole in the run with every sensor (*new*), and the causes "
                  f"of the new ones (a frame can have several); *elsewhere*: the other frames.", "",
                  "| missing | broken | new | a joint out of range | a joint too fast "
                  "| root step > 0.5 m | NaN | joints most often broken in new frames | elsewhere |",
                  "|---|---|---|---|---|---|---|---|---|"]
        lines += cause_rows(summary, "broken", BROKEN_CAUSES)
    lines += ["", f"Frames far off the truth in the gap and the {RECOVERY_WINDOW_S:g} s after it "
              f"(all clips): every one, those that are not far off in the run with every sensor "
              f"(*new*), and the causes of the new ones (a frame can have several); *elsewhere*: "
              f"the other frames. An arm posed hanging while the person's was raised is far off "
              f"and not broken: without its sensor the model cannot know.", "",
              "| missing | far off | new | pelvis global > 90 deg | another joint > 90 deg "
              "| root step > 0.5 m | NaN | joints most often over 90 deg in new frames | elsewhere |",
              "|---|---|---|---|---|---|---|---|---|"]
    lines += cause_rows(summary, "explode", EXPLODE_CAUSES)
    lines += ["", "Checks that the silence is where it was put and changes nothing else: poses "
              "flagged incomplete (a model sensor held or silent) in the gap, and outside it beyond "
              "the run with every sensor; the largest joint angle difference to that run before the "
              "gap (the same bytes, so 0 unless the replay is not deterministic); mocapctl's own "
              "angle error of the whole replay (`--metrics-json`) beside this module's, and its "
              "root drift (drift-corrected pose root, windows over the whole replay).", "",
              "| missing | incomplete in the gap | incomplete elsewhere, extra | before the gap, deg "
              "| angle deg, all frames: mocapctl / this module (clip means) | root drift 5 s / 10 s, m |",
              "|---|---|---|---|---|---|"]
    for cond, v in summary.items():
        lines.append(f"| {cond} | {v['incomplete_in_gap']} of {v['gap_frames']} | "
                     f"{v['incomplete_extra'] if cond != NONE else '-'} | "
                     f"{_fmt(v['same_before_gap'], 3) if cond != NONE else '-'} | "
                     f"{_fmt(v['engine_angle'])} / {_fmt(v['module_angle'])} | "
                     f"{_fmt(v['drift_5s'], 3)} / {_fmt(v['drift_10s'], 3)} |")
    conds = [c for c in summary if c != NONE]
    if conds and NONE in summary:
        lines += [""] + findings(summary)
    clips = list(dict.fromkeys(s.clip for s in scores))
    by = {(s.clip, s.condition): s for s in scores}
    lines += ["", "## Per clip: recovery time, s (angle error in the gap - the same frames with "
              "every sensor, deg)", "",
              "| clip | " + " | ".join(conds) + " |", "|---|" + "---|" * len(conds)]
    for clip in clips:
        cells = []
        for c in conds:
            s, ref = by.get((clip, c)), by.get((clip, NONE))
            if s is None or ref is None:
                cells.append("-")
                continue
            rise = _mean(s.angle["gap"], s.frames["gap"]) - _mean(ref.angle["gap"], ref.frames["gap"])
            cells.append(f"{_fmt(s.recovery, 2)} ({rise:+.1f})")
        lines.append(f"| {clip} | " + " | ".join(cells) + " |")
    lines += ["", "## Definitions", "",
              f"- gap: [{meta['gap_s']:g} s window centred on the clip], after: the "
              f"{RECOVERY_WINDOW_S:g} s after it, elsewhere: every other replayed frame.",
              f"- its bone: the global orientation error of the bone the silent sensor reports "
              f"(its sensor's bone in the table), mean over the gap; in brackets the same bone "
              f"and frames with every sensor.",
              f"- freeze: the longest stretch, in the gap and the window after it, in which the pose "
              f"moves at less than {FREEZE_RATIO:g} x the truth's speed while the truth moves (body: "
              f"mean root-aligned joint speed >= {BODY_MOVING_M_S:g} m/s; bone: angular speed >= "
              f"{BONE_MOVING_DEG_S:g} deg/s); speeds averaged over {SMOOTH_S:g} s. Worst clip.",
              f"- broken frames: a joint's local rotation more than {OUT_OF_RANGE_DEG:g} deg from "
              f"every rotation that joint takes in the training people's motion capture, a joint "
              f"turning faster than {SPEED_MARGIN:g} x the {TOO_FAST_QUANTILE:g} quantile of its "
              f"speed there, a NaN, or a root step > {EXPLODE_ROOT_STEP_M:g} m in one frame, in the "
              f"gap and the window after it, summed over clips; new: not broken in the run with "
              f"every sensor (clips: how many clips have any).",
              f"- frames > 90 deg off (far off): a NaN, a joint angle error > {EXPLODE_ANGLE_DEG:g} "
              f"deg (joint 0: the pelvis's global rotation) or a root step > "
              f"{EXPLODE_ROOT_STEP_M:g} m in one frame, the same windows; new: not far off in the "
              f"run with every sensor.",
              f"- recovery: from the gap's end until the angle and position errors (averaged over "
              f"{SMOOTH_S:g} s, frames after the gap only) are within {RECOVERED_WITHIN:.0%} (+ "
              f"{RECOVERY_SLACK_DEG:g} deg, {RECOVERY_SLACK_CM:g} cm) of the run with every sensor "
              f"and stay there {RECOVERY_HOLD_S:g} s; never: not before the clip ends.",
              "", "Clips: " + ", ".join(clips) + "."]
    if meta.get("notes"):
        lines += [""] + meta["notes"]
    path.parent.mkdir(parents=True, exist_ok=True)
    from .files import atomic_write_bytes
    atomic_write_bytes(("\n".join(lines) + "\n").encode(), path, "the missing-sensor report")
    return path


# ------------------------------------------------------------------------------ command
def run_evaluation(motions, segments=DEFAULT_SENSORS, gap_s: float = GAP_S, model=DEFAULT_MODEL,
                   seed: int = 0, workdir=None, progress=print, sensors=DEFAULT_SENSORS,
                   pose_range=None, rules: tuple = ()) -> list:
    """Every clip's conditions -> [ConditionScore] (clip order, "none" first in each clip);
    pose_range: see score_condition; rules: see evaluate_clip."""
    from .ort import mocapctl_path
    mocapctl = mocapctl_path(require_onnx=True)
    scores = []
    with tempfile.TemporaryDirectory(prefix="missing-sensor-") as tmp:
        root = Path(workdir) if workdir else Path(tmp)
        for i, motion in enumerate(motions):
            d = root / f"{i:02d}-{motion.name}"
            d.mkdir(parents=True, exist_ok=True)
            t0 = time.monotonic()
            clip_scores = evaluate_clip(motion, segments, gap_s, model, d, seed + i,
                                        world="enu" if i % 2 == 0 else "nwu", mocapctl=mocapctl,
                                        sensors=sensors, pose_range=pose_range,
                                        rules=rules)
            scores += clip_scores
            if progress:
                worst = max((s.recovery for s in clip_scores[1:]), default=math.nan)
                progress(f"  {i + 1}/{len(motions)} {motion.name}: {len(clip_scores)} replays in "
                         f"{time.monotonic() - t0:.0f} s, slowest recovery {_fmt(worst)} s")
    return scores


def model_info(model) -> tuple:
    """(contract version, sensor segments, optional segments) a model declares, as `mocapctl
    model-info` reads them (the engine refuses a model that breaks the contract: a CommandError
    here)."""
    from .ort import OnnxRuntimeError, model_info as read_model_info
    try:
        info = read_model_info(model)
    except OnnxRuntimeError as e:
        raise CommandError(f"mocapctl model-info {model}: {e}") from e
    if "contract_version" not in info or "sensor_order" not in info:
        raise CommandError(f"mocapctl model-info {model}: no contract_version or sensor_order line")
    return (int(info["contract_version"]), tuple(info["sensor_order"].split(",")),
            tuple(info.get("optional", [])))


def capture_sensors(model: Path, text) -> tuple:
    """(contract, the model's sensors, its optional ones, the capture's sensors): --sensors (text;
    default the model's), which must hold every sensor the model requires and none it does not
    read."""
    contract, model_sensors, optional = model_info(model)
    sensors = sensor_option(text, "--sensors") if text else model_sensors
    needed = [s for s in model_sensors if s not in optional and s not in sensors]
    if needed:
        raise UsageError(f"--sensors: {model.name} needs {', '.join(needed)} (it can do without "
                         f"{', '.join(optional) or 'none of its sensors'})")
    unread = [s for s in sensors if s not in model_sensors]
    if unread:
        raise UsageError(f"--sensors: {model.name} does not read {', '.join(unread)} "
                         f"({', '.join(model_sensors)})")
    return contract, model_sensors, optional, sensors


def add_source_arguments(p, splits, clips: int, clip_s: float, min_s: float) -> None:
    """Where a command's clips come from (--split / --bvh / --procedural), how many, how long."""
    src = p.add_mutually_exclusive_group()
    src.add_argument("--split", choices=splits, default="val",
                     help=f"CMU subjects, {' / '.join(splits)} (default val)")
    src.add_argument("--bvh", help="a folder of BVH clips (or a motion pack) instead")
    src.add_argument("--procedural", action="store_true",
                     help="the project's procedural motions instead (no data needed)")
    p.add_argument("--clips", type=POSITIVE_INT, default=clips, help=f"clips (default {clips})")
    p.add_argument("--clip-seconds", type=_SECONDS, default=clip_s,
                   help=f"cut clips to this length (default {clip_s:g}); only clips of at least "
                        f"{min_s:g} s (or this, if shorter) are used")


def load_clips(args, min_s: float) -> tuple:
    """(the source in words, the motions) of add_source_arguments' options."""
    if args.procedural:
        return "procedural motions", procedural_clips(args.clips, args.clip_seconds, args.seed)
    from . import dataset
    source = f"BVH folder {args.bvh}" if args.bvh else f"CMU {args.split} split"
    return source, choose_clips(dataset.load_motions(Path(args.bvh) if args.bvh else args.split,
                                                     progress=False),
                                args.clips, args.clip_seconds, min_s)


def pose_range_of(option: str) -> tuple:
    """--pose-range: (the range or None, a note for the report). "train": the CMU training
    people's (built once, cached), or none when the data is not here (the procedural motions need
    none); "none": not counted; else a file that pose-range --out saved."""
    from .pose_range import PoseRange, training_pose_range
    if option == "none":
        return None, "Broken poses were not counted (--pose-range none)."
    if option == "train":
        try:
            r = training_pose_range()
        except FileNotFoundError as e:
            return None, (f"Broken poses were not counted: the range of motion is measured on the "
                          f"CMU training people, and they are not here ({e}).")
    else:
        try:
            r = PoseRange.load(Path(option))
        except (OSError, KeyError, ValueError) as e:
            raise UsageError(f"--pose-range {option}: not a range that pose-range --out saved ({e})") from e
    return r, f"Range of motion (`python3 -m training pose-range`): {r.source}."


def report_path(args, name: str) -> Path:
    """--out, else training/results/NAME (training/results/test/NAME for the test split)."""
    if args.out:
        return Path(args.out)
    test = args.split == "test" and not (args.bvh or args.procedural)
    return (RESULTS_DIR / "test" if test else RESULTS_DIR) / name


def source_argv(args) -> list:
    """add_source_arguments' options as typed, for the report's command line."""
    out = ["--procedural"] if args.procedural else (["--bvh", args.bvh] if args.bvh else ["--split", args.split])
    return out + ["--clips", str(args.clips), "--clip-seconds", f"{args.clip_seconds:g}"]


_SECONDS = number_type(float, lambda v: v > 0, "a positive number of seconds")
# The tolerances mocap_solver_set_pose_limits takes besides 0 (MOCAP_POSE_LIMITS_MIN/MAX_DEG).
POSE_LIMITS_MIN_DEG, POSE_LIMITS_MAX_DEG = 1.0, 90.0
POSE_LIMITS = number_type(float, lambda v: v == 0 or POSE_LIMITS_MIN_DEG <= v <= POSE_LIMITS_MAX_DEG,
                          f"0 (off) or a tolerance from {POSE_LIMITS_MIN_DEG:g} to {POSE_LIMITS_MAX_DEG:g} deg")
CHEST_FOLLOW = number_type(float, lambda v: 0.0 <= v <= 1.0, "a share from 0 (off) to 1")


def add_arguments(p=None):
    p = p or argparse.ArgumentParser(prog="python3 -m training missing-sensor",
                                     description=__doc__.split("\n")[0])
    add_source_arguments(p, ["val", "test"], 15, CLIP_S, MIN_CLIP_S)
    p.add_argument("--seconds", type=_SECONDS, default=GAP_S,
                   help=f"how long the sensor is silent (default {GAP_S:g})")
    p.add_argument("--model", default=str(DEFAULT_MODEL), help="the ONNX model (default: the shipped "
                   "int8 one, the engine's default)")
    p.add_argument("--sensors", default=None,
                   help="the capture's sensors, comma-separated (default: the model's; a contract-2 "
                        "model's optional sensors may be left out, e.g. its six without the chest)")
    p.add_argument("--segments", default=None,
                   help="the sensors to silence in turn, comma-separated (default: each of the capture's)")
    p.add_argument("--seed", type=NON_NEGATIVE_INT, default=0)
    p.add_argument("--out", default=None, help="the report (default training/results/missing_sensor.md, "
                   "training/results/test/missing_sensor.md for --split test)")
    p.add_argument("--keep", default=None, help="keep the captures, poses and truths in this folder")
    p.add_argument("--pose-range", default="train",
                   help="what a broken pose is judged against: train (the CMU training people's "
                        "range of motion, measured once and cached; default), none (not counted), "
                        "or a file that `python3 -m training pose-range --out` saved")
    p.add_argument("--pose-limits", type=POSE_LIMITS, default=0.0, metavar="DEG",
                   help="the engine's pose guard, mocapctl replay --pose-limits DEG (default 0: off)")
    p.add_argument("--chest-follow", type=CHEST_FOLLOW, default=0.0, metavar="SHARE",
                   help="turn the spine SHARE of the way towards a live chest sensor, mocapctl "
                        "replay --chest-follow SHARE (default 0: off)")
    return p


def _shown(path) -> str:
    try:
        return str(Path(path).resolve().relative_to(REPO))
    except ValueError:
        return str(path)


def main(args=None) -> int:
    if args is None or isinstance(args, list):
        args = add_arguments().parse_args(args)
    model = Path(args.model)
    if not model.is_file():
        raise UsageError(f"--model {args.model}: no such file")
    contract, model_sensors, optional, sensors = capture_sensors(model, getattr(args, "sensors", None))
    segments = (sensor_option(args.segments, "--segments", sensors, "the capture") if args.segments
                else sensors)
    min_s = min(MIN_CLIP_S, args.clip_seconds)
    if min_s < args.seconds + 2 * RECOVERY_WINDOW_S:
        raise UsageError(f"--clip-seconds {args.clip_seconds:g} leaves no room for a {args.seconds:g} s "
                         f"gap with {RECOVERY_WINDOW_S:g} s on either side")
    source, motions = load_clips(args, min_s)
    out = report_path(args, "missing_sensor.md")
    print(f"missing-sensor: {len(motions)} clips ({source}) x {1 + len(segments)} conditions, "
          f"{args.seconds:g} s gaps, model {_shown(model)} (contract {contract})")
    started = time.monotonic()
    pose_range, range_note = pose_range_of(args.pose_range)
    notes = [range_note]
    pose_limits = getattr(args, "pose_limits", 0.0)
    chest_follow = getattr(args, "chest_follow", 0.0)
    scores = run_evaluation(motions, segments, args.seconds, model, args.seed, args.keep,
                            sensors=sensors, pose_range=pose_range,
                            rules=rule_options(pose_limits, chest_follow))
    command = "python3 -m training missing-sensor " + " ".join(shlex.quote(a) for a in _argv_of(args))
    left_out = [s for s in model_sensors if s not in sensors]
    if left_out:
        notes.append(f"The capture has {len(sensors)} sensors ({', '.join(sensors)}); the model's "
                     f"{', '.join(left_out)} is absent throughout (masked).")
    from .ort import model_info as read_model_info
    masked = bool(read_model_info(model).get("imu_mask"))
    notes.append(f"The model (contract {contract}) reads {'the' if masked else 'no'} mask: until a "
                 "silent sensor returns, the engine feeds a shin or the head its bone as the model "
                 "posed it in the frame before, at rest (zero acceleration), and a wrist its last "
                 "held sample turned about the vertical as far as the pelvis turned since; a wrist "
                 "or the head moves over 4 s towards its bone's usual orientation"
                 + (" (all marked present: the mask, imu_mask 0 with zero inputs, is for a sensor "
                    "the capture lacks)." if masked else "."))
    if pose_limits:
        notes.append(f"The engine's pose guard is on (mocapctl --pose-limits {pose_limits:g}): a joint "
                     f"further than {pose_limits:g} deg from the range people's joints take is turned "
                     "back to that distance.")
    if chest_follow:
        notes.append(f"Chest following is on (mocapctl --chest-follow {chest_follow:g}): while the "
                     f"chest sensor is live, the spine turns {chest_follow:g} of the way from the "
                     "network's chest bone towards it.")
    notes.append("A silent pelvis is never masked (every model reads the body in its frame): it is "
                 "fed its last sample turned about the vertical by the shins' mean heading change "
                 "since it was last live, at rest (zero acceleration).")
    meta = {"gap_s": args.seconds, "clips": len(motions), "source": source,
            "seconds": sum(m.num_frames / m.fps for m in motions), "model": _shown(model),
            "contract": contract, "command": command.strip(), "elapsed_s": time.monotonic() - started,
            "notes": notes}
    path = write_report(out, scores, meta)
    for cond, v in summarize(scores).items():
        print(f"{cond:12s} angle gap/after/elsewhere {_fmt(v['angle_gap'])} / {_fmt(v['angle_after'])} / "
              f"{_fmt(v['angle_elsewhere'])} deg  pos {_fmt(v['pos_gap'])} / {_fmt(v['pos_after'])} / "
              f"{_fmt(v['pos_elsewhere'])} cm  freeze {_fmt(v['freeze_body'], 1)} s  broken "
              f"{_count(v['broken'])} (new {_count(v['broken_extra']) if cond != NONE else '-'})  "
              f"far off {v['explode']} (new {v['explode_extra'] if cond != NONE else '-'})  "
              f"recovery median {_fmt(v['recovery_median'])} s worst "
              f"{_fmt(v['recovery_max'])} s")
    print(f"missing-sensor: wrote {_shown(path)}")
    return 0


def _argv_of(args) -> list:
    """The options that decide the report, written out (paths relative to the repository), so
    the report says how to make it again."""
    out = source_argv(args) + ["--seconds", f"{args.seconds:g}", "--seed", str(args.seed)]
    if Path(args.model).resolve() != DEFAULT_MODEL.resolve():
        out += ["--model", _shown(args.model)]
    if getattr(args, "sensors", None):
        out += ["--sensors", args.sensors]
    if args.segments:
        out += ["--segments", args.segments]
    if args.out:
        out += ["--out", _shown(args.out)]
    if args.pose_range != "train":
        out += ["--pose-range", args.pose_range if args.pose_range == "none" else _shown(args.pose_range)]
    return out + list(rule_options(getattr(args, "pose_limits", 0.0), getattr(args, "chest_follow", 0.0)))


if __name__ == "__main__":
    sys.exit(main())
