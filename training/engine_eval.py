"""engine-eval: what users get, scored through the engine's whole path.

    python3 -m training engine-eval [--split val | --split test | --bvh DIR | --procedural]
        [--clips 40] [--clip-seconds 40] [--model M.onnx] [--sensors A,B,...]
        [--smoothing HZ,BETA[+pinV] ...] [--body-scale S] [--height M] [--seed 0] [--out FILE]
        [--keep DIR]

For each clip (the first --clip-seconds of evenly spaced clips at least MIN_CLIP_S long, enough
for the 10 s drift windows) synth_capture writes a byte-level capture (calibration prelude,
realistic noise, random mountings and headings; --sensors: the capture's sensor set, default the
model's), and `mocapctl replay --model M --truth --pose-csv --metrics-json` runs it through
decode -> filter -> calibrate -> model -> output filter -> drift correction: once with the raw
model output (--smoothing 0) and once per output filter setting (default: the engine's own); a
setting ending in +pinV also holds planted feet (mocapctl replay --foot-pin V, m/s).
--body-scale S synthesises every clip on a body S times the size (skeleton and root path);
--height M gives the engine the performer's height, whose root then moves in the size of the
model's skeleton and is read back in the performer's metres (x M / the model's training height).

Per setting (means over every compared pose of every clip):
  angle, pos     mocapctl's joint angle error (24 joints) and root-aligned position error
  jitter         mean |third difference| of the joint positions; "x truth" is its ratio to the
                 motion capture's own jitter on the same frames (pooled: sum over sum; per
                 clip: geometric mean of the clips' ratios)
  lag            the filter's added latency: the delay d (ms) that best aligns the filtered
                 poses with the raw ones (the mean joint angle between filtered(t) and raw(t - d)
                 is smallest, d within +-0.5 s; sub-frame by a parabola through the best three),
                 median over clips, with its spread; for --smoothing waitN (poses stamped with their
                 own frames, each ready N frames later) that delay plus the N frames
Root drift (m) over windows of 2 / 5 / 10 s starting every second, | predicted - true root
displacement | at the window's end, pooled over the windows of all clips: of the pose root the
engine outputs (drift-corrected) and of the integrated root velocity (the model alone); per clip,
whether the correction helped at 10 s. Foot contacts: precision and recall of the engine's
planted flags against the truth's (a foot slower than synthesis.CONTACT_SPEED). Foot slide: the
mean horizontal speed (cm/s) of the engine's feet (forward kinematics of its poses on the
model's own skeleton, its rest_offsets, from its root) in the frames where it says they are planted (now and in the
frame before), beside the motion capture's own under its planted labels. Broken poses: the share
of poses no person takes, judged on the pose alone (pose_range.py, --pose-range: a joint out of
the training people's range of rotation or turning faster than theirs, or a NaN), and the
joints most often involved.
Writes OUT (default training/results/engine.md; training/results/test/engine.md for --split
test): the tables, the per-clip figures and the command that made it.
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
from .cli import NON_NEGATIVE_INT, number_type
from .errors import CommandError, UsageError

DRIFT_WINDOWS = (2.0, 5.0, 10.0)
MIN_CLIP_S = 15.0            # a 10 s drift window needs clips longer than it
CLIP_S = 40.0
LEAD_IN_S = 1.0
RAW = "0"                    # --smoothing 0: the model's raw output
ENGINE_SMOOTHING = "2,12"    # the engine's default output filter (solver config), as mocapctl prints it
MAX_LAG_FRAMES = 30          # the lag search goes up to 0.5 s at 60 Hz
JITTER_GOAL = 1.5            # x the motion capture's own


# ------------------------------------------------------------------------------ measures
def window_drift(times, pred, true, window_s: float) -> list:
    """Root drift of windows of window_s seconds starting every second (mocapctl's definition):
    | (pred[end] - pred[start]) - (true[end] - true[start]) |, m, one value per window."""
    times, pred, true = (np.asarray(a, np.float64) for a in (times, pred, true))
    out, next_start = [], times[0] if len(times) else 0.0
    for i in range(len(times)):
        if times[i] + 1e-9 < next_start:
            continue
        next_start = times[i] + 1.0
        j = int(np.searchsorted(times, times[i] + window_s - 1e-6))
        if j >= len(times):
            break
        out.append(float(np.linalg.norm((pred[j] - pred[i]) - (true[j] - true[i]))))
    return out


def integrated_root(velocity, fps: float) -> np.ndarray:
    """The root the model's velocity alone gives (no correction), from 0 at the first pose."""
    v = np.asarray(velocity, np.float64)
    return np.concatenate([np.zeros((1, 3)), np.cumsum(v[1:], axis=0) / fps]) if len(v) else v


def filter_lag_ms(filtered_q, raw_q, fps: float, max_frames: int = MAX_LAG_FRAMES) -> float:
    """The delay (ms) that best aligns filtered poses with raw ones: the d minimising the mean
    joint angle between filtered[t] and raw[t - d] (quaternions (T,J,4) of the same poses), d
    searched from -max_frames to max_frames; sub-frame by a parabola through the best frame and
    its neighbours."""
    f, r = np.asarray(filtered_q, np.float64), np.asarray(raw_q, np.float64)
    n = min(len(f), len(r))
    max_frames = min(max_frames, n - 2)
    if max_frames < 1:
        return math.nan
    shifts = np.arange(-max_frames, max_frames + 1)
    cost = np.empty(len(shifts))
    for i, d in enumerate(shifts):
        a, b = (f[d:n], r[:n - d]) if d >= 0 else (f[:n + d], r[-d:n])
        dot = np.abs(np.sum(a * b, axis=-1)).clip(0.0, 1.0)
        cost[i] = float(np.mean(2.0 * np.arccos(dot)))
    k = int(np.argmin(cost))
    shift = float(shifts[k])
    if 0 < k < len(shifts) - 1:
        a, b, c = cost[k - 1], cost[k], cost[k + 1]
        den = a - 2 * b + c
        if den > 0:
            shift += 0.5 * (a - c) / den
    return 1000.0 * shift / fps


def contact_quality(flags_contact, truth_contact) -> tuple:
    """(true positives, predicted planted, truly planted) of (T,2) boolean contact series."""
    p, t = np.asarray(flags_contact, bool), np.asarray(truth_contact, bool)
    return int((p & t).sum()), int(p.sum()), int(t.sum())


# ------------------------------------------------------------------------------ one clip
POSE_CONTACT_LEFT, POSE_CONTACT_RIGHT = 1 << 0, 1 << 1   # MOCAP_POSE_CONTACT_* of mocap_imu.h


@dataclass
class Replay:
    """One replay's poses on the truth's frames."""
    metrics: dict
    times: np.ndarray        # (P,) s, session time
    quats: np.ndarray        # (P,24,4)
    root: np.ndarray         # (P,3) drift-corrected
    velocity: np.ndarray     # (P,3)
    contact: np.ndarray      # (P,2) bool, the engine's planted flags
    truth_index: np.ndarray  # (P,) the truth frame of each pose


@dataclass
class ClipResult:
    name: str
    seconds: float
    runs: dict = field(default_factory=dict)   # smoothing -> Replay
    truth_root: np.ndarray | None = None       # (N,3)
    truth_contact: np.ndarray | None = None    # (N,2) bool
    truth_slide: np.ndarray | None = None      # foot_slide of the motion capture, m/s
    slide: dict = field(default_factory=dict)  # setting -> foot_slide of its replay, m/s
    broken: dict = field(default_factory=dict) # setting -> (P,24) joints broken in each pose
    fps: float = 60.0
    # metres of the performer per metre of the engine's root: with --height the engine moves the
    # root in its skeleton's size, the performer's height / the model's training height
    root_unit: float = 1.0

    @classmethod
    def from_truth(cls, name: str, seconds: float, truth: dict) -> "ClipResult":
        """A clip with no replay yet, its truth's root and planted feet."""
        _, pos = sk.forward_kinematics(np.asarray(truth["local_rot"], np.float64),
                                       np.asarray(truth["root_pos"], np.float64),
                                       np.asarray(truth["offsets"], np.float64))
        contact = truth_contacts(pos, float(truth["fps"]))
        return cls(name, seconds, fps=float(truth["fps"]), truth_root=np.asarray(truth["root_pos"], np.float64),
                   truth_contact=contact, truth_slide=foot_slide(pos, contact, float(truth["fps"])))


def read_replay(poses_csv: Path, metrics_json: Path, truth: dict) -> Replay:
    with open(poses_csv) as f:
        header = f.readline().rstrip("\n").split(",")
    a = np.loadtxt(poses_csv, delimiter=",", skiprows=1, ndmin=2)
    if a.shape[0] == 0 or header[:4] != ["sequence", "frame_sequence", "time_s", "flags"]:
        raise CommandError(f"{poses_csv}: not a pose CSV of mocapctl replay, or no poses")
    col = {name: k for k, name in enumerate(header)}
    fps, n = float(truth["fps"]), len(truth["root_pos"])
    x = (a[:, col["time_s"]] - float(truth["t_session_start"])) * fps
    keep = (x > -1e-3) & (x < n - 1 + 1e-3)
    if not keep.any():
        raise CommandError(f"{poses_csv}: no pose falls on the truth's frames")
    a, x = a[keep], x[keep]
    flags = a[:, col["flags"]].astype(np.int64)
    first_q = col["pelvis_qw"]
    return Replay(json.loads(Path(metrics_json).read_text()), a[:, col["time_s"]],
                  a[:, first_q:first_q + 96].reshape(-1, 24, 4),
                  a[:, [col["root_x"], col["root_y"], col["root_z"]]],
                  a[:, [col["vel_x"], col["vel_y"], col["vel_z"]]],
                  np.stack([(flags & POSE_CONTACT_LEFT) != 0, (flags & POSE_CONTACT_RIGHT) != 0], -1),
                  np.clip(np.round(x).astype(int), 0, n - 1))


FEET = (10, 11)              # left_foot, right_foot: the joints whose contact the model predicts


def foot_slide(positions, planted, fps: float) -> np.ndarray:
    """Horizontal speeds (m/s) of the feet (positions (P,24,3), planted (P,2) bool) over the
    frame pairs where a foot is planted in both."""
    feet = np.asarray(positions, np.float64)[:, FEET][:, :, [0, 2]]
    speed = np.linalg.norm(np.diff(feet, axis=0), axis=-1) * fps
    both = planted[1:] & planted[:-1]
    return speed[both]


def replay_slide(r: "Replay", model_offsets, fps: float) -> np.ndarray:
    """foot_slide of a replay's poses: its rotations on the skeleton the engine poses (the
    model's rest offsets, not the clip's), from the engine's root."""
    _, pos = sk.forward_kinematics(sk.rot_from_quat(r.quats), r.root, np.asarray(model_offsets, np.float64))
    return foot_slide(pos, r.contact, fps)


def truth_contacts(positions, fps: float) -> np.ndarray:
    """(N,2) the truth's planted feet from its joint positions (N,24,3), as training labels them
    (synthesis.foot_contact_labels)."""
    from .synthesis import foot_contact_labels
    return foot_contact_labels(positions, fps) > 0.5


def scaled_motion(motion: sk.Motion, scale: float) -> sk.Motion:
    """The same movement on a body scale times the size (skeleton and root path), as
    `evaluate --body-scale` synthesises it."""
    if scale == 1.0:
        return motion
    return sk.Motion(motion.name, motion.subject, motion.fps, motion.local_rot,
                     (motion.root_pos * scale).astype(np.float32), (motion.offsets * scale).astype(np.float32))


def broken_joints(pose_range, quats, fps: float) -> np.ndarray:
    """(P,24) the joints of each pose (quaternions (P,24,4)) out of the pose range or turning too
    fast; every joint of a pose with a NaN."""
    q = np.asarray(quats, np.float64)
    finite = np.isfinite(q).all(axis=(1, 2))
    norm = np.linalg.norm(np.where(np.isfinite(q), q, 0.0), axis=-1, keepdims=True)
    safe = np.where(finite[:, None, None] & (norm > 0), q / np.where(norm > 0, norm, 1.0), [1.0, 0.0, 0.0, 0.0])
    bad = pose_range.implausible(sk.rot_from_quat(safe), fps)
    out = bad["range"] | bad["speed"]
    out[~finite] = True
    return out


def run_clip(motion: sk.Motion, index: int, model, settings, sensors, workdir: Path, seed: int,
             mocapctl, height: float = 0.0, root_unit: float = 1.0, model_offsets=None,
             pose_range=None) -> ClipResult:
    from .dropout_eval import replay_command
    from .synth_capture import load_truth, synth_capture
    cap = workdir / f"{index:02d}-{motion.name}.cap"
    synth_capture(None, cap, motion=motion, seed=seed, world="enu" if index % 2 == 0 else "nwu",
                  lead_in=LEAD_IN_S, sensors=sensors)
    truth = load_truth(cap.with_suffix(".truth.npz"))
    out = ClipResult.from_truth(motion.name, motion.num_frames / motion.fps, truth)
    out.root_unit = root_unit
    for s in (RAW, *[x for x in settings if x != RAW]):
        tag = "raw" if s == RAW else s.replace(",", "_")
        poses, metrics = cap.with_suffix(f".{tag}.csv"), cap.with_suffix(f".{tag}.json")
        cmd = (replay_command(mocapctl, cap, cap.with_suffix(".truth.csv"), model, poses, metrics, sensors)
               + engine_options(s) + (["--height", f"{height:g}"] if height else []))
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise CommandError(f"mocapctl replay {cap.name} --smoothing {s} failed (status "
                               f"{r.returncode}): " + (r.stderr.strip() or r.stdout.strip()[-500:]))
        out.runs[s] = read_replay(poses, metrics, truth)
        if model_offsets is not None:
            out.slide[s] = replay_slide(out.runs[s], model_offsets, out.fps)
        if pose_range is not None:
            out.broken[s] = broken_joints(pose_range, out.runs[s].quats, out.fps)
    return out


# ------------------------------------------------------------------------------ summary
def clip_drift(clip, setting) -> dict:
    """Window -> (drift windows of the engine's corrected root, of the model's velocity alone) of
    one clip's replay with this output setting."""
    r = clip.runs[setting]
    true = clip.truth_root[r.truth_index]
    model_root = integrated_root(r.velocity, clip.fps) * clip.root_unit
    root = r.root * clip.root_unit
    return {w: (window_drift(r.times, root, true, w), window_drift(r.times, model_root, true, w))
            for w in DRIFT_WINDOWS}


def summarize(clips, settings) -> dict:
    """Setting -> the figures of the tables (see the module's docstring)."""
    out = {}
    for s in (RAW, *settings):
        if s in out:
            continue
        poses = sum(c.runs[s].metrics["poses"] for c in clips)

        def pooled(key):
            return sum(c.runs[s].metrics[key] * c.runs[s].metrics["poses"] for c in clips) / max(poses, 1)
        jit, tjit = pooled("jitter_100m_s3"), pooled("truth_jitter_100m_s3")
        ratios = [c.runs[s].metrics["jitter_100m_s3"] / c.runs[s].metrics["truth_jitter_100m_s3"]
                  for c in clips if (c.runs[s].metrics.get("truth_jitter_100m_s3") or 0) > 0]
        # a waiting smoother's poses are stamped with their own frames, so they align with the raw
        # ones; its latency is the frames it waits for
        lags = [filter_lag_ms(c.runs[s].quats, c.runs[RAW].quats, c.fps) + 1000.0 * wait_frames(setting_parts(s)[0]) / c.fps
                for c in clips] if s != RAW else []
        row = {"poses": poses, "angle": pooled("angle_error_deg"), "pos": pooled("position_error_cm"),
               "jitter": jit, "truth_jitter": tjit, "jitter_ratio": jit / tjit if tjit else math.nan,
               "jitter_ratio_gm": float(np.exp(np.mean(np.log(ratios)))) if ratios else math.nan,
               "lag_ms": float(np.nanmedian(lags)) if lags else 0.0,
               "lag_ms_range": (float(np.nanmin(lags)), float(np.nanmax(lags))) if lags else (0.0, 0.0)}
        drifts = [clip_drift(c, s) for c in clips]
        for w in DRIFT_WINDOWS:
            corr = [x for d in drifts for x in d[w][0]]
            integ = [x for d in drifts for x in d[w][1]]
            row[f"drift_{w:g}s"] = float(np.mean(corr)) if corr else math.nan
            row[f"drift_{w:g}s_model"] = float(np.mean(integ)) if integ else math.nan
            row[f"drift_{w:g}s_windows"] = len(corr)
        # per clip: mean 10 s drift of the engine's root and of the model alone
        row["drift_10s_per_clip"] = [(float(np.mean(d[10.0][0])) if d[10.0][0] else math.nan,
                                      float(np.mean(d[10.0][1])) if d[10.0][1] else math.nan) for d in drifts]
        row["drift_change_per_clip"] = [a - b for a, b in row["drift_10s_per_clip"] if not math.isnan(a)]
        tp = pp = tt = 0
        for c in clips:
            r = c.runs[s]
            t, p, n = contact_quality(r.contact, c.truth_contact[r.truth_index])
            tp, pp, tt = tp + t, pp + p, tt + n
        slide = np.concatenate([c.slide[s] for c in clips if s in c.slide] or [np.zeros(0)])
        truth_slide = np.concatenate([c.truth_slide for c in clips if c.truth_slide is not None] or [np.zeros(0)])
        row["foot_slide_cm_s"] = 100.0 * float(np.mean(slide)) if len(slide) else math.nan
        row["truth_foot_slide_cm_s"] = 100.0 * float(np.mean(truth_slide)) if len(truth_slide) else math.nan
        row["contact_precision"] = tp / pp if pp else math.nan
        row["contact_recall"] = tp / tt if tt else math.nan
        measured = [c.broken[s] for c in clips if s in c.broken]
        if measured and len(measured) == len(clips):
            joints = np.concatenate(measured)
            row["broken_poses"] = int(joints.any(axis=1).sum())
            row["broken_share"] = row["broken_poses"] / len(joints) if len(joints) else math.nan
            row["broken_joints"] = {int(j): int(n) for j, n in enumerate(joints.sum(axis=0)) if n}
            row["broken_clips"] = sum(1 for b in measured if b.any())
        out[s] = row
    return out


# ------------------------------------------------------------------------------ report
def _fmt(v, digits=2) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.{digits}f}"


def _label(s: str) -> str:
    if s == RAW:
        return "raw model output (--smoothing 0)"
    if any(setting_parts(s)[1:]):
        return " ".join(engine_options(s))
    return f"--smoothing {s}" + (" (the engine's default)" if s == ENGINE_SMOOTHING else "")


def write_report(path: Path, clips, settings, meta: dict, summary: dict) -> Path:
    """The report of summarize()'s figures (summary) for these clips."""
    lines = ["# The engine's whole path: output filter, jitter, drift", "",
             f"{len(clips)} clips ({meta['source']}, {sum(c.seconds for c in clips):.0f} s of motion), "
             f"each a byte-level capture of {len(meta['sensors'])} sensors ({', '.join(meta['sensors'])}) "
             f"replayed by `mocapctl replay` through `{meta['model']}`: decode -> filter -> calibrate -> "
             f"model -> output filter -> drift correction. Made by:", "",
             f"    {meta['command']}", "",
             f"({meta['elapsed_s'] / 60:.1f} min on this machine.) Figures are means over every compared "
             "pose of every clip; the docstring of `training/engine_eval.py` defines each.", ""]
    if meta.get("body_scale", 1.0) != 1.0 or meta.get("height"):
        lines += [f"Every clip on a body {meta.get('body_scale', 1.0):g} times the size; "
                  + (f"the engine was told the performer is {meta['height']:g} m tall and its root is read "
                     "back in the performer's metres. " if meta.get("height") else
                     "the engine was told no height. ")
                  + "Positions are those of the model's own skeleton against the scaled truth.", ""]
    lines += ["| output | angle (deg) | position (cm) | jitter (10^2 m/s^3) | x truth, pooled | x truth, "
              "per clip (geo. mean) | added latency ms, median (range) |",
              "|---|---|---|---|---|---|---|"]
    for s, v in summary.items():
        lag = "-" if s == RAW else f"{_fmt(v['lag_ms'], 0)} ({_fmt(v['lag_ms_range'][0], 0)} - {_fmt(v['lag_ms_range'][1], 0)})"
        lines.append(f"| {_label(s)} | {_fmt(v['angle'])} | {_fmt(v['pos'])} | {_fmt(v['jitter'])} | "
                     f"{_fmt(v['jitter_ratio'])} | {_fmt(v['jitter_ratio_gm'])} | {lag} |")
    raw = summary[RAW]
    if "broken_poses" in raw:
        lines += ["", f"Broken poses (a joint out of the range people's takes or turning faster than "
                  f"theirs, or a NaN; {meta.get('pose_range', 'pose_range.py')}):", "",
                  "| output | broken poses | share of poses | clips with any | joints most often broken |",
                  "|---|---|---|---|---|"]
        from .dropout_eval import _top_joints
        for s, v in summary.items():
            lines.append(f"| {_label(s)} | {v['broken_poses']} | {100.0 * v['broken_share']:.3f} % | "
                         f"{v['broken_clips']} of {len(clips)} | {_top_joints(v['broken_joints'])} |")
    lines += ["", f"The motion capture's own jitter on the same frames: {_fmt(raw['truth_jitter'])} x10^2 m/s^3.",
              "", "## Root drift", "",
              "| output | drift 2 s (m) | drift 5 s | drift 10 s | the model alone (integrated velocity) 2 / 5 / 10 s "
              "| correction helped at 10 s (clips) | mean change at 10 s per clip (m) | contacts: precision / recall "
              "| planted feet slide (cm/s) |",
              "|---|---|---|---|---|---|---|---|---|"]
    for s, v in summary.items():
        ch = v["drift_change_per_clip"]
        lines.append(f"| {_label(s)} | {_fmt(v['drift_2s'], 3)} | {_fmt(v['drift_5s'], 3)} | "
                     f"{_fmt(v['drift_10s'], 3)} | {_fmt(v['drift_2s_model'], 3)} / "
                     f"{_fmt(v['drift_5s_model'], 3)} / {_fmt(v['drift_10s_model'], 3)} | "
                     f"{sum(1 for x in ch if x < 0)} of {len(ch)} | "
                     f"{'%+.3f' % float(np.mean(ch)) if ch else '-'} | "
                     f"{_fmt(v['contact_precision'])} / {_fmt(v['contact_recall'])} | "
                     f"{_fmt(v['foot_slide_cm_s'], 1)} |")
    first = next(iter(summary.values()))
    lines += ["", f"Windows: {first['drift_2s_windows']} / {first['drift_5s_windows']} / "
              f"{first['drift_10s_windows']} of 2 / 5 / 10 s. The motion capture's own planted feet "
              f"slide {_fmt(first['truth_foot_slide_cm_s'], 1)} cm/s (its contact labels include the "
              "roll from heel to toe).", ""]
    lines += findings(summary, settings)
    s0 = settings[0] if settings else RAW
    with_broken = "broken_poses" in summary[s0]
    lines += ["", "## Per clip (" + _label(s0) + ")", "",
              "| clip | seconds | angle (deg) | position (cm) | jitter x truth | drift 10 s (m): engine / model alone |"
              + (" broken poses |" if with_broken else ""),
              "|---|---|---|---|---|---|" + ("---|" if with_broken else "")]
    for c, (a, b) in zip(clips, summary[s0]["drift_10s_per_clip"]):
        m = c.runs[s0].metrics
        ratio = m["jitter_100m_s3"] / m["truth_jitter_100m_s3"] if m.get("truth_jitter_100m_s3") else math.nan
        lines.append(f"| {c.name} | {c.seconds:.1f} | {_fmt(m['angle_error_deg'])} | {_fmt(m['position_error_cm'])} | "
                     f"{_fmt(ratio)} | {_fmt(a, 3)} / {_fmt(b, 3)} |"
                     + (f" {int(c.broken[s0].any(axis=1).sum())} |" if with_broken else ""))
    path.parent.mkdir(parents=True, exist_ok=True)
    from .files import atomic_write_bytes
    atomic_write_bytes(("\n".join(lines) + "\n").encode(), path, "the engine report")
    return path


def findings(summary, settings) -> list:
    """The tables' answers to the goals, computed so that a rerun keeps them true."""
    raw = summary[RAW]
    out = ["## What it shows", ""]
    for s in settings:
        if s == RAW:
            continue
        v = summary[s]
        out.append(f"- {_label(s)}: jitter {_fmt(v['jitter_ratio'])} x the motion capture's "
                   f"({'within' if v['jitter_ratio'] <= JITTER_GOAL else 'above'} {JITTER_GOAL:g} x; raw "
                   f"{_fmt(raw['jitter_ratio'])} x), angle error {v['angle'] - raw['angle']:+.3f} deg and "
                   f"position {v['pos'] - raw['pos']:+.3f} cm against the raw output, "
                   f"{_fmt(v['lag_ms'], 0)} ms added latency (median).")
        if setting_parts(s)[1]:
            out.append(f"- {_label(s)}: planted feet slide {_fmt(v['foot_slide_cm_s'], 1)} cm/s (raw output "
                       f"{_fmt(raw['foot_slide_cm_s'], 1)}, the motion capture's own "
                       f"{_fmt(raw['truth_foot_slide_cm_s'], 1)}).")
        ch = v["drift_change_per_clip"]
        out.append(f"- Drift correction ({_label(s)}): 10 s drift {_fmt(v['drift_10s'], 3)} m against "
                   f"{_fmt(v['drift_10s_model'], 3)} m for the model's velocity alone; it helped "
                   f"{sum(1 for x in ch if x < 0)} of {len(ch)} clips, mean change per clip "
                   f"{'%+.3f' % float(np.mean(ch)) if ch else '-'} m.")
    return out


# ------------------------------------------------------------------------------ command
def run_evaluation(motions, model, settings, sensors, seed: int = 0, workdir=None, progress=print,
                   body_scale: float = 1.0, height: float = 0.0, pose_range=None) -> list:
    """body_scale: every clip on a body that many times the size; height: the performer height
    given to the engine (0: none), its root then read back in the performer's metres;
    pose_range (pose_range.PoseRange): what a broken pose is (None: not counted)."""
    from .ort import mocapctl_path, model_info
    mocapctl = mocapctl_path(require_onnx=True)
    root_unit = 1.0
    info = model_info(str(model))
    if height:
        if "training_height" not in info:
            raise UsageError(f"--height: {Path(model).name} has no stride scaling (python3 -m "
                             "training stride-scaling --write)")
        root_unit = height / info["training_height"]
    clips = []
    with tempfile.TemporaryDirectory(prefix="engine-eval-") as tmp:
        root = Path(workdir) if workdir else Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        for i, m in enumerate(motions):
            t0 = time.monotonic()
            clips.append(run_clip(scaled_motion(m, body_scale), i, model, settings, sensors, root,
                                  seed + i, mocapctl, height, root_unit, info["rest_offsets"],
                                  pose_range))
            if progress:
                progress(f"  {i + 1}/{len(motions)} {m.name}: {len(clips[-1].runs)} replays in "
                         f"{time.monotonic() - t0:.0f} s")
    return clips


SMOOTHING = number_type(str, lambda v: _smoothing_ok(v),
                        "HZ or HZ,BETA with HZ >= 0 and BETA >= 0, or waitN (N frames, 1 to 4), "
                        "either followed by +pinV (foot pinning, V m/s from 0 to 1), +limitD (pose "
                        "limits, D deg from 1 to 90) and +chestF (chest following, a share from 0 to 1), "
                        "in that order")
PIN_TAG = "+pin"


LIMIT_TAG = "+limit"
CHEST_TAG = "+chest"


def setting_parts(setting: str) -> tuple:
    """(the --smoothing part, the --foot-pin speed, the --pose-limits tolerance, the
    --chest-follow share; 0.0 for each one absent) of an output setting
    "S[+pinV][+limitD][+chestF]"."""
    rest, ctag, chest = setting.partition(CHEST_TAG)
    rest, tag, limit = rest.partition(LIMIT_TAG)
    smoothing, ptag, pin = rest.partition(PIN_TAG)
    return (smoothing, (float(pin) if ptag else 0.0), (float(limit) if tag else 0.0),
            (float(chest) if ctag else 0.0))


def engine_options(setting: str) -> list:
    """mocapctl's options for an output setting, --smoothing first."""
    from .dropout_eval import rule_options
    smoothing, pin, limit, chest = setting_parts(setting)
    return (["--smoothing", smoothing] + (["--foot-pin", f"{pin:g}"] if pin else [])
            + list(rule_options(limit, chest)))
HEIGHT = number_type(float, lambda v: 1.0 <= v <= 2.5, "a height from 1 to 2.5 m")


def wait_frames(setting: str) -> int:
    """N of a "waitN" setting (smoothing that waits N frames: each pose is ready N frames after
    its own frame), else 0."""
    return int(setting[4:]) if setting.startswith("wait") and setting[4:].isdigit() else 0


def _smoothing_ok(v: str) -> bool:
    from .dropout_eval import POSE_LIMITS_MAX_DEG, POSE_LIMITS_MIN_DEG
    try:
        smoothing, pin, limit, chest = setting_parts(v)
    except ValueError:
        return False
    if CHEST_TAG in v and not 0.0 < chest <= 1.0:
        return False
    if PIN_TAG in v and not 0.0 < pin <= 1.0:
        return False
    if LIMIT_TAG in v and not POSE_LIMITS_MIN_DEG <= limit <= POSE_LIMITS_MAX_DEG:
        return False
    v = smoothing
    if v.startswith("wait"):
        return 1 <= wait_frames(v) <= 4
    try:
        parts = [float(x) for x in v.split(",")]
    except ValueError:
        return False
    return 1 <= len(parts) <= 2 and all(math.isfinite(x) and x >= 0 for x in parts)


def add_arguments(p=None):
    from .dropout_eval import DEFAULT_MODEL, add_source_arguments
    from .evaluate import BODY_SCALE
    p = p or argparse.ArgumentParser(prog="python3 -m training engine-eval",
                                     description=__doc__.split("\n")[0])
    add_source_arguments(p, ["train", "val", "test"], 40, CLIP_S, MIN_CLIP_S)
    p.add_argument("--model", default=str(DEFAULT_MODEL), help="the ONNX model (default: the engine's)")
    p.add_argument("--sensors", default=None, help="the capture's sensors (default: the model's)")
    p.add_argument("--smoothing", nargs="+", type=SMOOTHING, default=[ENGINE_SMOOTHING],
                   help=f"output filter settings beside the raw output (default {ENGINE_SMOOTHING}, the engine's); "
                        "+pinV after one also pins planted feet (--foot-pin V)")
    p.add_argument("--body-scale", dest="body_scale", type=BODY_SCALE, default=1.0,
                   help="every clip on a body this many times the size (0.5-2; default 1)")
    p.add_argument("--height", type=HEIGHT, default=0.0,
                   help="give the engine this performer height, metres (mocapctl replay --height); "
                        "drift is then measured in the performer's metres")
    p.add_argument("--seed", type=NON_NEGATIVE_INT, default=0)
    p.add_argument("--out", default=None, help="the report (default training/results/engine.md, "
                   "training/results/test/engine.md for --split test)")
    p.add_argument("--keep", default=None, help="keep the captures and poses in this folder")
    p.add_argument("--pose-range", default="train",
                   help="what a broken pose is judged against: train (the CMU training people's "
                        "range of motion; default), none (not counted), or a file that "
                        "`python3 -m training pose-range --out` saved")
    return p


def main(args=None) -> int:
    from .dropout_eval import _shown, capture_sensors, load_clips, pose_range_of, report_path, source_argv
    if args is None or isinstance(args, list):
        args = add_arguments().parse_args(args)
    model = Path(args.model)
    if not model.is_file():
        raise UsageError(f"--model {args.model}: no such file")
    sensors = capture_sensors(model, args.sensors)[3]
    source, motions = load_clips(args, min(MIN_CLIP_S, args.clip_seconds))
    settings = list(dict.fromkeys(args.smoothing))
    out = report_path(args, "engine.md")
    print(f"engine-eval: {len(motions)} clips ({source}), {len(sensors)} sensors, model {_shown(model)}, "
          f"output {', '.join(_label(s) for s in [RAW] + settings)}")
    started = time.monotonic()
    pose_range, range_note = pose_range_of(args.pose_range)
    clips = run_evaluation(motions, model, settings, sensors, args.seed, args.keep,
                           body_scale=args.body_scale, height=args.height, pose_range=pose_range)
    argv = source_argv(args) + ["--seed", str(args.seed)]
    if args.body_scale != 1.0:
        argv += ["--body-scale", f"{args.body_scale:g}"]
    if args.height:
        argv += ["--height", f"{args.height:g}"]
    if model.resolve() != Path(add_arguments().get_default("model")).resolve():
        argv += ["--model", _shown(model)]
    if args.sensors:
        argv += ["--sensors", args.sensors]
    if settings != [ENGINE_SMOOTHING]:
        argv += ["--smoothing", *settings]
    if args.out:
        argv += ["--out", _shown(args.out)]
    if args.pose_range != "train":
        argv += ["--pose-range", args.pose_range if args.pose_range == "none" else _shown(args.pose_range)]
    meta = {"pose_range": (f"`python3 -m training pose-range`: {pose_range.source}"
                           if pose_range is not None else range_note), "source": source, "sensors": sensors, "model": _shown(model),
            "body_scale": args.body_scale, "height": args.height,
            "command": "python3 -m training engine-eval " + " ".join(shlex.quote(a) for a in argv),
            "elapsed_s": time.monotonic() - started}
    summary = summarize(clips, settings)
    path = write_report(out, clips, settings, meta, summary)
    for s, v in summary.items():
        print(f"{_label(s):44s} angle {_fmt(v['angle'])} deg  pos {_fmt(v['pos'])} cm  jitter x{_fmt(v['jitter_ratio'])} "
              f"lag {_fmt(v['lag_ms'], 0)} ms  drift 10 s {_fmt(v['drift_10s'], 3)} m (model alone "
              f"{_fmt(v['drift_10s_model'], 3)})")
    print(f"engine-eval: wrote {_shown(path)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
