"""evaluate: the pose model on held-out motion, against the truth and a kinematic baseline.

    python3 -m training evaluate [--split val | --bvh DIR] [--models M.onnx ...]
        [--checkpoint CKPT] [--out training/results] [--max-clips N] [--max-seconds S]
        [--seed 0] [--no-torch] [--no-mirror] [--no-latency] [--noise realistic|none]
        [--body-scale S]

For every clip: IMU inputs are synthesised WITH realistic sensor errors (eval_augmentation() below, fixed
seed, no body-scale or heading augmentation; --noise none: perfect sensors; --body-scale S: every
clip's skeleton and root path S times the size, a shorter or taller performer), then predicted by
  * PyTorch fp32 (the training checkpoint, mirror-averaged as `training export` ships it:
    model.MirrorEnsemble; --no-mirror evaluates the single network),
  * ONNX fp32 / fp16 (the shipped models, through the REAL ONNX Runtime: training/ort.py),
  * a kinematic baseline: each sensor's orientation applied straight to its bone (pelvis global,
    wrists, shins, head), every other joint at rest, root velocity zero.
Metrics (field-notes section 1; definitions also in training/README.md):
  angle_all   mean joint angle error, deg: angle of pred^T * true of the LOCAL rotations (joint 0:
              global pelvis), over all 24 joints and all frames
  angle_dip   the same over the 15 joints DIP/TransPose evaluate (no pelvis, ankles, feet,
              wrists, hands)
  sip         SIP error, deg: GLOBAL rotation angle error of hips and shoulders (1, 2, 16, 17)
  pos         mean joint position error, cm, both skeletons root-aligned (translation only), the
              clip's own offsets, 24 joints
  drift_Ws    root drift, m: windows of W = 2, 5, 10 s starting every second: | predicted root
              displacement (integrated root_velocity) - true displacement | at the window end
  jitter      mean |third time derivative| of the root-aligned joint positions, 10^2 m/s^3
              (TransPose's unit; the truth's own jitter is listed for reference)
  latency     ONNX Runtime per frame for one character, streaming T = 1 on one intra-op thread
              (mocapctl infer --stream --threads 1): p50 / p99 microseconds per call
Writes OUT/evaluation.md (table, targets, per joint, per subject, hardest clips), OUT/clips.csv
(every clip's angle and position error per method) and PNGs: per-joint error, error over time,
drift vs window length, per-clip position error.
"""
from __future__ import annotations

import argparse
import math
import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from . import skeleton as sk
from .sensors import DEFAULT_SENSORS, WRIST_SENSOR_PLACES, sensor_bones
from .cli import NON_NEGATIVE_INT, POSITIVE_INT, number_type, sensor_option
from .errors import CommandError, UsageError

REPO = Path(__file__).resolve().parent.parent
MODELS_DIR = REPO / "Packages" / "com.mocap.imu" / "Runtime" / "Models"
DEFAULT_MODELS = [MODELS_DIR / "mocap_pose_fp32.onnx", MODELS_DIR / "mocap_pose_fp16.onnx"]
RESULTS_DIR = REPO / "training" / "results"
# The default PyTorch model: what `training export` exports by default (the best checkpoint of
# the last local training run), else the committed weights of the shipped model. Never last.pt:
# a running training job rewrites it every two minutes.
CHECKPOINT_CANDIDATES = ["training/data/checkpoints/best.pt", "training/checkpoints/mocap_pose.pt"]
# PyTorch and the ONNX fp32 export of the same weights agree to ~1e-6 (fp32 rounding); more than
# this means the checkpoint is not the model the ONNX file was exported from.
SAME_MODEL_TOLERANCE = 1e-3

DIP_EXCLUDED = [0, 7, 8, 10, 11, 20, 21, 22, 23]
DIP_JOINTS = [j for j in range(24) if j not in DIP_EXCLUDED]
SIP_JOINTS = [1, 2, 16, 17]
DRIFT_WINDOWS = (2.0, 5.0, 10.0)

# Evaluation inputs: synthesis.Augmentation with its realistic sensor errors (per-sensor
# mounting/calibration error, sensor-world yaw error, orientation noise, accelerometer noise and
# bias, short drop-outs holding the last sample) and nothing else: no body scaling, no random
# heading, no mirroring, no tempo change (the clip's own skeleton, heading and timing are kept).
def eval_augmentation(noise: str = "realistic", body_scale: float = 1.0):
    """noise: "realistic" (the issue's targets are set with it) or "none": perfect sensors, which
    separates what the sensor errors cost from what six sensors cannot observe. body_scale: the
    clip's skeleton and root path scaled (the same motion by a shorter or taller performer)."""
    from .synthesis import Augmentation
    if noise not in NOISE_CHOICES:
        raise UsageError(f"noise {noise!r}: expected one of {', '.join(NOISE_CHOICES)}")
    if not BODY_SCALE_RANGE[0] <= body_scale <= BODY_SCALE_RANGE[1]:
        raise UsageError(f"body scale {body_scale:g}: expected {BODY_SCALE_RANGE[0]:g} to "
                         f"{BODY_SCALE_RANGE[1]:g}")
    aug = Augmentation(scale=(body_scale, body_scale), heading=False, mirror=0.0, speed=(1.0, 1.0))
    if noise == "none":
        aug = replace(aug, mounting_deg=0.0, heading_drift_deg=0.0, orientation_noise_deg=0.0,
                      acc_noise=0.0, acc_bias=0.0, drop_rate=0.0)
    return aug


NOISE_CHOICES = ("realistic", "none")
# 0.5x and 2x a CMU performer: beyond any adult (users are 1.5 to 2.0 m tall)
BODY_SCALE_RANGE = (0.5, 2.0)


TARGETS = {"angle_all": 10.0, "pos": 6.0, "baseline_reduction": 0.40, "params": 4_000_000,
           "latency_ms": 1.0}


# ------------------------------------------------------------------------------ inputs
@dataclass
class Clip:
    name: str
    fps: float
    offsets: np.ndarray            # (24,3)
    imu_orientation: np.ndarray    # (T,N,3,3)
    imu_acceleration: np.ndarray   # (T,N,3)
    local_rot: np.ndarray          # (T,24,3,3) truth
    root_pos: np.ndarray           # (T,3) truth
    subject: int = 0               # 0: unknown (a BVH folder without NN_MM names)
    sensors: tuple = DEFAULT_SENSORS   # segment names of the N sensors
    mask: np.ndarray | None = None     # (T,N) 1 where a sensor is present; None: all present


def without_sensors(clip: Clip, absent) -> Clip:
    """The clip as the engine feeds a masked model whose `absent` sensors (segment names) are
    missing for the whole clip: mask 0, orientation and acceleration zero."""
    absent = tuple(absent)
    if not absent:
        return clip
    unknown = [a for a in absent if a not in clip.sensors]
    if unknown:
        raise UsageError(f"{', '.join(unknown)}: not among the clip's sensors ({', '.join(clip.sensors)})")
    T, n = clip.imu_orientation.shape[:2]
    mask = np.ones((T, n), np.float32) if clip.mask is None else clip.mask.copy()
    for a in absent:
        mask[:, clip.sensors.index(a)] = 0.0
    return replace(clip, imu_orientation=clip.imu_orientation * mask[..., None, None],
                   imu_acceleration=clip.imu_acceleration * mask[..., None], mask=mask)


def synthesize_clip(motion: sk.Motion, rng, wrist: str = "hand", noise: str = "realistic",
                    sensors=DEFAULT_SENSORS, body_scale: float = 1.0) -> Clip:
    """IMU inputs (synthesis.synthesize with eval_augmentation(noise, body_scale)) + the truth.
    wrist: where the wrist sensors are (sensors.sensor_bones); sensors: segment names, the
    model's order."""
    from .synthesis import synthesize
    sample = synthesize(motion, rng=rng, augment=eval_augmentation(noise, body_scale), wrist=wrist,
                        sensors=sensors)
    return Clip(motion.name, float(sample.fps), np.asarray(sample.offsets, np.float64),
                np.asarray(sample.imu_orientation, np.float32),
                np.asarray(sample.imu_acceleration, np.float32),
                np.asarray(sample.local_rot, np.float64), np.asarray(sample.root_pos, np.float64),
                int(motion.subject), sample.sensors)


# ------------------------------------------------------------------------------ predictors
@dataclass
class Prediction:
    local_rot: np.ndarray      # (T,24,3,3)
    root_velocity: np.ndarray  # (T,3)


def predict_baseline(clip: Clip, wrist: str = "hand") -> Prediction:
    T = clip.imu_orientation.shape[0]
    ori = clip.imu_orientation.astype(np.float64)
    local = np.broadcast_to(np.eye(3), (T, 24, 3, 3)).copy()
    present = np.ones(ori.shape[:2], bool) if clip.mask is None else clip.mask > 0.5
    pelvis = ori[:, list(clip.sensors).index("pelvis")] if "pelvis" in clip.sensors else np.eye(3)
    local[:, 0] = pelvis
    # Every ancestor of the sensor bones (other than the pelvis) is at rest, so the parent's
    # global rotation is the pelvis's. A missing sensor leaves its bone at rest.
    for s, j in enumerate(sensor_bones(wrist, clip.sensors)):
        if j != 0:
            local[present[:, s], j] = (np.swapaxes(pelvis, -1, -2) @ ori[:, s])[present[:, s]]
    return Prediction(local, np.zeros((T, 3)))


def _batches(clips, max_batch=16, max_values=60_000_000):
    """Groups of clip indices of similar length (padding is harmless: the models are causal)."""
    order = sorted(range(len(clips)), key=lambda i: clips[i].imu_orientation.shape[0])
    group = []
    for i in order:
        T = clips[i].imu_orientation.shape[0]
        if group and (len(group) >= max_batch or (len(group) + 1) * T * 300 > max_values):
            yield group
            group = []
        group.append(i)
    if group:
        yield group


def _padded(clips, group):
    """(orientation, acceleration, mask) of a group of clips, padded to the longest."""
    T = max(clips[i].imu_orientation.shape[0] for i in group)
    n = clips[group[0]].imu_orientation.shape[1]
    ori = np.tile(np.eye(3, dtype=np.float32), (len(group), T, n, 1, 1))
    acc = np.zeros((len(group), T, n, 3), np.float32)
    mask = np.ones((len(group), T, n), np.float32)
    for b, i in enumerate(group):
        n = clips[i].imu_orientation.shape[0]
        ori[b, :n] = clips[i].imu_orientation
        acc[b, :n] = clips[i].imu_acceleration
        if clips[i].mask is not None:
            mask[b, :n] = clips[i].mask
    return ori, acc, mask


def _has_missing(clips) -> bool:
    return any(c.mask is not None and not (c.mask > 0.5).all() for c in clips)


def predict_onnx(model_path, clips) -> list:
    """The ONNX model through the engine's ONNX Runtime module; a contract-2 model gets each
    clip's mask (imu_mask), a contract-1 model needs every sensor present."""
    from .ort import model_info, run_onnx
    info = model_info(model_path)
    sensors = tuple(info.get("sensor_order", ",".join(DEFAULT_SENSORS)).split(","))
    masked = bool(info.get("imu_mask"))
    _require_sensors(clips, sensors, f"{Path(model_path).name} (model contract "
                     f"{info.get('contract_version', '?')})")
    if not masked and _has_missing(clips):
        raise UsageError(f"{Path(model_path).name} has no imu_mask input: it cannot run with a "
                         "sensor missing")
    out = [None] * len(clips)
    for group in _batches(clips):
        ori, acc, mask = _padded(clips, group)
        r = run_onnx(model_path, ori, acc, mask=mask if masked else None)
        for b, i in enumerate(group):
            n = clips[i].imu_orientation.shape[0]
            out[i] = Prediction(r["joint_rotations"][b, :n].astype(np.float64),
                                r["root_velocity"][b, :n].astype(np.float64))
    return out


def find_checkpoint():
    for c in CHECKPOINT_CANDIDATES:
        if (REPO / c).is_file():
            return REPO / c
    return None


def load_torch_model(path, mirror: bool = False):
    """A PoseNet from a checkpoint: a whole module, or a dict holding the state dict under
    'model' / 'state_dict' / 'model_state' (else the dict itself) and the config under 'config'.
    mirror: wrapped in model.MirrorEnsemble, as `training export` ships it."""
    import torch
    from .model import PoseNet
    from .train import checkpoint_model_config, load_checkpoint_file
    ckpt = load_checkpoint_file(path)
    if isinstance(ckpt, torch.nn.Module):
        return ckpt.eval()
    if not isinstance(ckpt, dict):
        raise UsageError(f"{path} is not a pose model checkpoint (it holds a {type(ckpt).__name__})")
    cfg = ckpt.get("config") or ckpt.get("model_config") or {}
    if isinstance(cfg, dict):
        cfg = checkpoint_model_config(cfg, path)
    net = PoseNet(cfg)
    state = None
    for key in ("model", "state_dict", "model_state", "net"):
        if isinstance(ckpt.get(key), dict):
            state = ckpt[key]
            break
    try:
        net.load_state_dict(state if state is not None else ckpt)
    except RuntimeError as e:
        raise UsageError(f"{path} does not hold the weights of its pose network ("
                         f"{str(e).splitlines()[0]})") from e
    if mirror:
        from .model import MirrorEnsemble
        return MirrorEnsemble(net).eval()
    return net.eval()


def _require_sensors(clips, sensors, what: str) -> None:
    """A UsageError unless every clip carries exactly these sensors, in this order."""
    for c in clips:
        if tuple(c.sensors) != tuple(sensors):
            raise UsageError(f"{what} reads the sensors {','.join(sensors)}; clip {c.name} has "
                             f"{','.join(c.sensors)}")


def predict_torch(net, clips, device: str = "cpu") -> list:
    from .train import setup_threads
    import torch
    _require_sensors(clips, net.config.sensors, "the PyTorch network")
    masked = getattr(getattr(net, "config", None), "masked", False)
    if not masked and _has_missing(clips):
        raise UsageError("the PyTorch network has no sensor mask: it cannot run with a sensor missing")
    setup_threads()  # OpenBLAS threads its own GEMMs; torch threads on top oversubscribe
    out = [None] * len(clips)
    net = net.to(device)
    with torch.no_grad():
        for group in _batches(clips):
            ori, acc, mask = (torch.from_numpy(a).to(device) for a in _padded(clips, group))
            rot, vel, _, _ = net(ori, acc, imu_mask=mask if masked else None)
            rot, vel = rot.cpu(), vel.cpu()
            for b, i in enumerate(group):
                n = clips[i].imu_orientation.shape[0]
                out[i] = Prediction(rot[b, :n].double().numpy(), vel[b, :n].double().numpy())
    return out


# ------------------------------------------------------------------------------ metrics
def rotation_angle_deg(a, b):
    """Angle of a^T b, degrees, for (...,3,3) stacks."""
    tr = np.einsum("...ji,...ji->...", a, b)
    return np.degrees(np.arccos(np.clip((tr - 1.0) / 2.0, -1.0, 1.0)))


def root_aligned_positions(local_rot, offsets):
    g, p = sk.forward_kinematics(local_rot, np.zeros(local_rot.shape[:-3] + (3,)), offsets)
    return g, p


def _window_displacements(pred_vel, true_root, fps, window_s, step_s=1.0) -> tuple:
    """Root displacement over windows starting every step_s: (predicted by the integrated
    velocity, true), each (W, 3); none when the clip is not longer than one window."""
    T = len(true_root)
    w = int(round(window_s * fps))
    if T <= w:
        return np.zeros((0, 3)), np.zeros((0, 3))
    pred_pos = np.concatenate([np.zeros((1, 3)), np.cumsum(pred_vel[1:], axis=0) / fps])
    starts = np.arange(0, T - w, max(1, int(round(step_s * fps))))
    return pred_pos[starts + w] - pred_pos[starts], true_root[starts + w] - true_root[starts]


def drift_errors(pred_vel, true_root, fps, window_s, step_s=1.0):
    """Root drift per window: |integrated predicted displacement - true displacement| (m)."""
    d_pred, d_true = _window_displacements(pred_vel, true_root, fps, window_s, step_s)
    return np.linalg.norm(d_pred - d_true, axis=-1)


def travel_ratios(pred_vel, true_root, fps, window_s=10.0, min_travel=0.5, step_s=1.0):
    """Per window in which the root truly travels more than `min_travel` m horizontally: the
    predicted horizontal distance (integrated velocity) over the true one. Below 1 the model
    reads the motion as slower than it was; the along-track share of drift."""
    d_pred, d_true = _window_displacements(pred_vel, true_root, fps, window_s, step_s)
    true_d = np.linalg.norm(d_true[:, [0, 2]], axis=-1)
    pred_d = np.linalg.norm(d_pred[:, [0, 2]], axis=-1)
    moving = true_d > min_travel
    return pred_d[moving] / true_d[moving]


ELBOWS = [sk.JOINT_NAMES.index("left_elbow"), sk.JOINT_NAMES.index("right_elbow")]


def elbow_angles(local_rot):
    """The rotation angle of both elbows' local rotations, every frame (deg): how far each forearm
    is turned from the straight rest pose (bend and twist together)."""
    r = local_rot[:, ELBOWS]
    return np.degrees(np.arccos(np.clip((np.trace(r, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0))).ravel()


def jitter(positions, fps):
    """Mean |d^3 p / dt^3| over joints and frames, m/s^3."""
    if len(positions) < 4:
        return float("nan")
    d3 = np.diff(positions, n=3, axis=0) * fps ** 3
    return float(np.linalg.norm(d3, axis=-1).mean())


@dataclass
class ClipScore:
    """One clip's means over its frames (and joints), so a report can say where the error is."""
    name: str
    subject: int
    frames: int
    seconds: float
    angle: float   # deg, mean over 24 joints
    pos: float     # cm


@dataclass
class Accumulator:
    """Sums over all frames of all clips of one method."""
    frames: int = 0
    angle_joint: np.ndarray = field(default_factory=lambda: np.zeros(24))
    pos_joint: np.ndarray = field(default_factory=lambda: np.zeros(24))      # cm
    sip_sum: float = 0.0
    pos_sum: float = 0.0
    drift: dict = field(default_factory=lambda: {w: [] for w in DRIFT_WINDOWS})
    drift_curve: dict = field(default_factory=dict)   # window s -> list of errors
    jitter_sum: float = 0.0
    jitter_frames: int = 0
    over_time: list = field(default_factory=list)     # per clip: (T,) mean angle error
    per_clip: list = field(default_factory=list)      # per clip: ClipScore
    travel: list = field(default_factory=list)        # per clip: travel_ratios
    elbows: list = field(default_factory=list)        # per clip: predicted elbow_angles

    def add(self, clip: Clip, pred: Prediction):
        true_l = clip.local_rot
        ang = rotation_angle_deg(pred.local_rot, true_l)          # (T,24)
        g_p, p_p = root_aligned_positions(pred.local_rot, clip.offsets)
        g_t, p_t = root_aligned_positions(true_l, clip.offsets)
        T = ang.shape[0]
        self.frames += T
        self.angle_joint += ang.sum(axis=0)
        self.sip_sum += rotation_angle_deg(g_p[:, SIP_JOINTS], g_t[:, SIP_JOINTS]).mean(axis=1).sum()
        dist_cm = np.linalg.norm(p_p - p_t, axis=-1) * 100.0                  # (T,24)
        self.pos_joint += dist_cm.sum(axis=0)
        self.pos_sum += dist_cm.mean(axis=1).sum()
        for w in DRIFT_WINDOWS:
            self.drift[w].extend(drift_errors(pred.root_velocity, clip.root_pos, clip.fps, w))
        for w in np.arange(1.0, 10.5, 1.0):
            self.drift_curve.setdefault(float(w), []).extend(
                drift_errors(pred.root_velocity, clip.root_pos, clip.fps, w))
        if T >= 4:
            self.jitter_sum += jitter(p_p, clip.fps) * (T - 3)
            self.jitter_frames += T - 3
        self.over_time.append(ang.mean(axis=1))
        self.travel.append(travel_ratios(pred.root_velocity, clip.root_pos, clip.fps))
        self.elbows.append(elbow_angles(pred.local_rot))
        self.per_clip.append(ClipScore(clip.name, clip.subject, T, T / clip.fps,
                                       float(ang.mean()), float(dist_cm.mean())))

    def summary(self) -> dict:
        n = max(self.frames, 1)
        per_joint = self.angle_joint / n
        out = {"angle_all": float(per_joint.mean()), "angle_dip": float(per_joint[DIP_JOINTS].mean()),
               "sip": self.sip_sum / n, "pos": self.pos_sum / n, "per_joint": per_joint,
               "per_joint_pos": self.pos_joint / n,
               "jitter": (self.jitter_sum / self.jitter_frames / 100.0) if self.jitter_frames else float("nan")}
        for w in DRIFT_WINDOWS:
            v = self.drift[w]
            out[f"drift_{w:g}s"] = float(np.mean(v)) if len(v) else float("nan")
            out[f"drift_{w:g}s_n"] = len(v)
        out["drift_curve"] = {w: (float(np.mean(v)) if len(v) else float("nan"))
                              for w, v in sorted(self.drift_curve.items())}
        out["per_clip"] = list(self.per_clip)
        travel = np.concatenate(self.travel) if self.travel else np.zeros(0)
        out["travel_ratio"] = float(np.median(travel)) if len(travel) else float("nan")
        out["travel_windows"] = len(travel)
        elbows = np.concatenate(self.elbows) if self.elbows else np.zeros(0)
        out["elbow_p5"], out["elbow_p95"] = (tuple(float(v) for v in np.percentile(elbows, [5, 95]))
                                             if len(elbows) else (float("nan"), float("nan")))
        return out


def truth_elbows(clips) -> tuple:
    """The motion capture's own elbow angles: 5th and 95th percentile (deg)."""
    a = np.concatenate([elbow_angles(c.local_rot) for c in clips]) if clips else np.zeros(0)
    return tuple(float(v) for v in np.percentile(a, [5, 95])) if len(a) else (float("nan"), float("nan"))


def truth_jitter(clips) -> float:
    s, n = 0.0, 0
    for c in clips:
        T = c.local_rot.shape[0]
        if T >= 4:
            _, p = root_aligned_positions(c.local_rot, c.offsets)
            s += jitter(p, c.fps) * (T - 3)
            n += T - 3
    return s / n / 100.0 if n else float("nan")


# ------------------------------------------------------------------------------ latency / params
def measure_latency(model_path, frames=1800, seed=0) -> dict:
    """ONNX Runtime, one character, T = 1 per call, one intra-op thread (mocapctl infer), every
    sensor of the model present."""
    from .ort import model_info, run_onnx
    info = model_info(model_path)
    sensors = tuple(info.get("sensor_order", ",".join(DEFAULT_SENSORS)).split(","))
    m = __import__("training.procedural", fromlist=["make_motion"]).make_motion(
        "mixed", frames / sk.MODEL_FPS, seed=seed)
    clip = synthesize_clip(m, np.random.default_rng(seed), sensors=sensors)
    mask = np.ones((1,) + clip.imu_orientation.shape[:2], np.float32) if info.get("imu_mask") else None
    r = run_onnx(model_path, clip.imu_orientation[None], clip.imu_acceleration[None], stream=True,
                 threads=1, timing=True, mask=mask)
    timing = r["timing"]
    timing["cpus"] = os.cpu_count()
    timing["load"] = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return timing


def onnx_parameter_count(model_path) -> int:
    import onnx
    m = onnx.load(str(model_path))
    return int(sum(int(np.prod(t.dims)) for t in m.graph.initializer if len(t.dims) >= 1))


# ------------------------------------------------------------------------------ report
def _fmt(v, digits=2):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return f"{v:.{digits}f}"


def _torch_description(meta) -> str:
    """The report's sentence on the PyTorch model: which weights, and whether they are the model
    the ONNX fp32 file was exported from."""
    if "torch" not in meta:
        return ""
    text = f" PyTorch model: {meta['torch']}"
    if meta.get("checkpoint"):
        text += f", weights `{meta['checkpoint']}`"
    text += "."
    diff = meta.get("torch_onnx_diff")
    if diff is not None:
        text += f" Largest joint-rotation difference between PyTorch and ONNX fp32: {diff:.2g}"
        text += (" (**different models**: the checkpoint is not the one the ONNX file was exported "
                 "from)." if diff > SAME_MODEL_TOLERANCE else " (the same model).")
    return text


def _per_joint_table(results) -> list:
    """Where the error is, joint by joint: angle (deg) and position (cm) of each method, so a
    change of model shows which limbs it moved."""
    names = [n for n in results if "per_joint_pos" in results[n]]
    if not names:
        return []
    head = " | ".join(f"{n} angle (deg) | {n} position (cm)" for n in names)
    lines = ["", "## Per joint", "", f"| joint | {head} |", "|---" * (1 + 2 * len(names)) + "|"]
    for j, joint in enumerate(sk.JOINT_NAMES):
        cells = " | ".join(f"{_fmt(float(results[n]['per_joint'][j]))} | "
                           f"{_fmt(float(results[n]['per_joint_pos'][j]))}" for n in names)
        lines.append(f"| {j} {joint} | {cells} |")
    return lines


HARDEST_CLIPS = 10


def _frame_mean(clips, key) -> float:
    """A ClipScore field averaged over frames, as the headline figures are."""
    return sum(getattr(c, key) * c.frames for c in clips) / max(sum(c.frames for c in clips), 1)


def _per_clip_sections(results, model_name) -> list:
    """Where the model's position error comes from: per subject, and the clips it does worst on
    with what they add to the mean, so a missed target can be traced to kinds of motion."""
    if not model_name or not results[model_name].get("per_clip"):
        return []
    clips = results[model_name]["per_clip"]
    # The baseline beside the model shows whether a clip is hard for any method or for the model.
    base = {c.name: c for c in results.get("baseline", {}).get("per_clip", [])} \
        if model_name != "baseline" else {}

    def base_cell(text) -> str:   # the baseline's column, where there is one
        return f" {text} |" if base else ""

    lines = []
    subjects = sorted({c.subject for c in clips})
    if len(subjects) > 1:
        lines += ["", f"## Per subject ({model_name})", "",
                  "| subject | clips | minutes | angle (deg) | position (cm) |" + base_cell("baseline position (cm)"),
                  "|---|---|---|---|---|" + base_cell("---")]
        for subj in subjects:
            mine = [c for c in clips if c.subject == subj]
            in_base = [base[c.name] for c in mine if c.name in base]
            lines.append(f"| {subj if subj else 'unknown'} | {len(mine)} | {sum(c.seconds for c in mine) / 60:.1f} | "
                         f"{_fmt(_frame_mean(mine, 'angle'))} | {_fmt(_frame_mean(mine, 'pos'))} |"
                         + base_cell(_fmt(_frame_mean(in_base, 'pos')) if in_base else '-'))
    worst = sorted(clips, key=lambda c: c.pos, reverse=True)[:min(HARDEST_CLIPS, len(clips) - 1)]
    if worst:
        worst_names = {c.name for c in worst}
        rest_pos = _frame_mean([c for c in clips if c.name not in worst_names], "pos")
        share = 100.0 * sum(c.frames for c in worst) / sum(c.frames for c in clips)
        lines += ["", f"## Hardest clips ({model_name}, by position error)", "",
                  f"These {len(worst)} clips are {share:.1f} % of the frames; without them the mean "
                  f"position error would be {rest_pos:.2f} cm instead of {results[model_name]['pos']:.2f}. "
                  "Every clip's figures are in `clips.csv`.", "",
                  "| clip | subject | seconds | angle (deg) | position (cm) |" + base_cell("baseline position (cm)"),
                  "|---|---|---|---|---|" + base_cell("---")]
        for c in worst:
            b = base.get(c.name)
            lines.append(f"| {c.name} | {c.subject if c.subject else '-'} | {c.seconds:.1f} | {_fmt(c.angle)} | "
                         f"{_fmt(c.pos)} |" + base_cell(_fmt(b.pos) if b else "-"))
    return lines


def write_clip_table(out_dir, results) -> Path:
    """clips.csv: one row per clip, angle and position error of every method."""
    import csv
    names = [n for n in results if results[n].get("per_clip")]
    path = Path(out_dir) / "clips.csv"
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["clip", "subject", "seconds"] + [f"{n} {k}" for n in names
                                                      for k in ("angle (deg)", "position (cm)")])
        for row in zip(*(results[n]["per_clip"] for n in names)):
            c = row[0]
            w.writerow([c.name, c.subject, f"{c.seconds:.3f}"] +
                       [f"{v:.4f}" for r in row for v in (r.angle, r.pos)])
    return path


def _sensor_description(meta) -> str:
    """The report's words on which sensors the models read (nothing for the default six)."""
    sensors, absent = tuple(meta.get("sensors") or DEFAULT_SENSORS), tuple(meta.get("absent") or ())
    if sensors == tuple(DEFAULT_SENSORS) and not absent:
        return ""
    present = [x for x in sensors if x not in absent]
    text = f" Sensors: {len(present)} ({', '.join(present)})"
    if absent:
        text += f"; missing for the whole clip, masked: {', '.join(absent)}"
    return text + "."


def _body_description(meta) -> str:
    """The report's words on a scaled performer (nothing at the clips' own size)."""
    s = float(meta.get("body_scale", 1.0))
    if s == 1.0:
        return ""
    return (f" Every performer {s:g} times their size (skeleton and root path scaled; positions "
            f"and drift are on the scaled body).")


_WRIST_WORDS = {"hand": "back of the hands", "forearm": "forearms (wrist straps)"}


def write_report(out_dir, results, meta, latency, params, truth_jit):
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    base = results.get("baseline")
    lines = ["# Pose model evaluation", "",
             f"Generated by `python3 -m training evaluate` on {meta['when']}. Data: {meta['source']} "
             f"({meta['clips']} clips, {meta['seconds']:.0f} s at {sk.MODEL_FPS} Hz). Inputs "
             f"synthesised {_NOISE_WORDS[meta.get('noise_kind', 'realistic')]} ({meta['noise']}), "
             f"seed {meta['seed']}, "
             f"wrist sensors on the {_WRIST_WORDS[meta.get('wrist', 'hand')]}."
             + _body_description(meta)
             + _sensor_description(meta)
             + _torch_description(meta), "",
             "Synthetic inputs from motion capture: not directly comparable to published numbers on "
             "real sensors (field-notes section 1).", "",
             "| method | angle, all 24 (deg) | angle, DIP 15 (deg) | SIP (deg) | position (cm) | "
             "drift 2 s (m) | drift 5 s (m) | drift 10 s (m) | jitter (10^2 m/s^3) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, s in results.items():
        lines.append(f"| {name} | {_fmt(s['angle_all'])} | {_fmt(s['angle_dip'])} | {_fmt(s['sip'])} | "
                     f"{_fmt(s['pos'])} | {_fmt(s['drift_2s'], 3)} | {_fmt(s['drift_5s'], 3)} | "
                     f"{_fmt(s['drift_10s'], 3)} | {_fmt(s['jitter'])} |")
    lines.append(f"| truth (reference) | 0 | 0 | 0 | 0 | 0 | 0 | 0 | {_fmt(truth_jit)} |")
    lines += ["", f"Drift windows: {results[next(iter(results))].get('drift_2s_n', 0)} / "
              f"{results[next(iter(results))].get('drift_5s_n', 0)} / "
              f"{results[next(iter(results))].get('drift_10s_n', 0)} windows of 2 / 5 / 10 s "
              "(clips shorter than a window contribute none).", ""]
    lines += _speed_and_reach(results, meta.get("truth_elbows"))
    lines += ["## Targets (issue 3)", ""]
    if meta.get("noise_kind", "realistic") != "realistic":
        lines += ["The targets are set for realistic sensor noise; these inputs have none, so the "
                  "figures below show what the model reaches with perfect sensors, not whether it "
                  "meets them.", ""]
    lines += ["| target | required | measured | met |", "|---|---|---|---|"]
    model_name = next((n for n in results if n.startswith("ONNX fp32")), None) or \
        next((n for n in results if n != "baseline"), None)
    if model_name:
        s = results[model_name]
        lines.append(f"| mean joint angle error ({model_name}) | <= {TARGETS['angle_all']:g} deg | "
                     f"{_fmt(s['angle_all'])} deg | {'yes' if s['angle_all'] <= TARGETS['angle_all'] else 'NO'} |")
        lines.append(f"| mean joint position error | <= {TARGETS['pos']:g} cm | {_fmt(s['pos'])} cm | "
                     f"{'yes' if s['pos'] <= TARGETS['pos'] else 'NO'} |")
        if base:
            red = 1.0 - s["angle_all"] / base["angle_all"] if base["angle_all"] > 0 else float("nan")
            lines.append(f"| angle error below the kinematic baseline | >= 40 % | {_fmt(100 * red, 1)} % "
                         f"(baseline {_fmt(base['angle_all'])} deg) | "
                         f"{'yes' if red >= TARGETS['baseline_reduction'] else 'NO'} |")
    if params is not None:
        lines.append(f"| parameters | <= 4 M | {params / 1e6:.2f} M | "
                     f"{'yes' if params <= TARGETS['params'] else 'NO'} |")
    if latency:
        p99_ms = latency["p99_us"] / 1000.0
        lines.append(f"| ONNX Runtime per frame, 1 character, 1 thread | < 1 ms | p50 "
                     f"{latency['p50_us'] / 1000:.3f} ms, p99 {p99_ms:.3f} ms ({latency['calls']} calls, "
                     f"{latency['model']}; {latency.get('cpus', '?')} CPUs, load average {latency.get('load', float('nan')):.1f} "
                     f"while measured) | {'yes' if p99_ms < TARGETS['latency_ms'] else 'NO'} (p99), "
                     f"{'yes' if latency['p50_us'] / 1000 < TARGETS['latency_ms'] else 'NO'} (p50) |")
    lines += _per_joint_table(results)
    lines += _per_clip_sections(results, model_name or ("baseline" if base else None))
    lines += ["", "## Definitions", "",
              "- angle: angle of the relative rotation between predicted and true LOCAL joint "
              "rotations (joint 0 = global pelvis). \"DIP 15\" leaves out the pelvis, ankles, feet, "
              "wrists and hands, as DIP/TransPose/PIP evaluate.",
              "- SIP: global rotation angle error of the hips and shoulders (TransPose).",
              "- position: joint positions by forward kinematics on the clip's own skeleton, both "
              "roots at the origin (orientation kept), mean over 24 joints.",
              "- drift: predicted root velocity integrated at 60 Hz over windows starting every "
              "second, compared with the true root displacement (m).",
              "- jitter: mean norm of the third finite difference of the root-aligned joint "
              "positions, in 10^2 m/s^3 (TransPose's unit; 1 km/s^3 = 10 x 10^2 m/s^3).",
              "- baseline: the sensors' orientations applied to their own bones, all other joints "
              "at rest, no translation.",
              f"- latency: `mocapctl infer --stream --threads 1` on {meta.get('latency_frames', 1800)} "
              "frames, the engine's ONNX Runtime module, first call (warm-up) excluded.", "",
              "Plots: `per_joint_error.png`, `error_over_time.png`, `drift.png`, "
              "`per_clip_error.png`; every clip's errors: `clips.csv`."]
    (out_dir / "evaluation.md").write_text("\n".join(lines) + "\n")
    return out_dir / "evaluation.md"


def _speed_and_reach(results, truth_elbows) -> list:
    """Two ways a model hedges towards the middle: reading motion as slower than it was (the
    along-track part of drift) and keeping the elbows from straightening or bending fully."""
    first = results[next(iter(results))]
    lines = ["## Speed and reach", "",
             "| method | distance travelled, predicted / true (median) | elbow angle p5 / p95 (deg) |",
             "|---|---|---|"]
    for name, s in results.items():
        lines.append(f"| {name} | {_fmt(s.get('travel_ratio'), 3)} | {_fmt(s.get('elbow_p5'), 1)} / "
                     f"{_fmt(s.get('elbow_p95'), 1)} |")
    if truth_elbows:
        lines.append(f"| truth (reference) | 1 | {_fmt(truth_elbows[0], 1)} / {_fmt(truth_elbows[1], 1)} |")
    lines += ["", f"Distance: horizontal root travel over {first.get('travel_windows', 0)} windows of "
              "10 s in which the root truly moved more than 0.5 m. Elbow angle: the rotation angle "
              "of both elbows' local rotations (bend and twist), every frame.", ""]
    return lines


def _finish_plot(fig, ax, xlabel, ylabel, title, path):
    import matplotlib.pyplot as plt
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_plots(out_dir, results, accs, clips):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out_dir = Path(out_dir)
    names = list(results)
    # Per-joint angle error
    fig, axes = plt.subplots(2, 1, figsize=(12, 8), sharex=True)
    width = 0.8 / max(len(names), 1)
    x = np.arange(24)
    for ax, key, label, title in ((axes[0], "per_joint", "mean local angle error (deg)", "Per-joint angle error"),
                                  (axes[1], "per_joint_pos", "mean position error (cm)",
                                   "Per-joint position error (roots aligned)")):
        for k, n in enumerate(names):
            ax.bar(x + (k - (len(names) - 1) / 2) * width, results[n][key], width, label=n)
        ax.set_ylabel(label)
        ax.set_title(title)
        ax.legend(fontsize=8)
    axes[1].set_xticks(x)
    axes[1].set_xticklabels(sk.JOINT_NAMES, rotation=60, ha="right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out_dir / "per_joint_error.png", dpi=110)
    plt.close(fig)
    # Error over time: the longest clip
    longest = int(np.argmax([c.local_rot.shape[0] for c in clips]))
    fig, ax = plt.subplots(figsize=(10, 4))
    for n in names:
        e = accs[n].over_time[longest]
        ax.plot(np.arange(len(e)) / clips[longest].fps, e, label=n, lw=1)
    _finish_plot(fig, ax, "time (s)", "mean angle error over joints (deg)",
                 f"Error over time, clip {clips[longest].name}", out_dir / "error_over_time.png")
    # Drift vs window length
    fig, ax = plt.subplots(figsize=(6, 4))
    for n in names:
        curve = results[n]["drift_curve"]
        ax.plot(list(curve), list(curve.values()), marker="o", label=n)
    _finish_plot(fig, ax, "window (s)", "mean root drift (m)", "Root drift vs window length",
                 out_dir / "drift.png")
    # Per-clip position error, clips sorted by it, each as wide as its share of the frames: how
    # much of the data is above the target, and by how much.
    fig, ax = plt.subplots(figsize=(8, 4))
    for n in names:
        per_clip = sorted(results[n]["per_clip"], key=lambda c: c.pos)
        share = np.cumsum([0] + [c.frames for c in per_clip]) / max(sum(c.frames for c in per_clip), 1)
        ax.stairs([c.pos for c in per_clip], 100.0 * share, baseline=None, label=n)
    ax.axhline(TARGETS["pos"], color="k", ls="--", lw=1, label=f"target {TARGETS['pos']:g} cm")
    _finish_plot(fig, ax, "share of the frames, clips sorted by error (%)",
                 "clip's mean position error (cm)", "Position error per clip", out_dir / "per_clip_error.png")


# ------------------------------------------------------------------------------ driver
def evaluate(motions, models=(), checkpoint=None, out_dir=RESULTS_DIR, seed=0, latency=True,
             latency_frames=1800, source="", progress=True, mirror=True, wrist="hand",
             noise="realistic", sensors=DEFAULT_SENSORS, absent=(), body_scale: float = 1.0,
             torch_device: str = "cpu") -> dict:
    """Evaluate every available method on the motions; writes the report; returns summaries.
    mirror: the PyTorch model is the mirror-averaged pair (model.MirrorEnsemble), as exported.
    wrist: where the synthesised wrist sensors are ("hand": on the back of the hands, where the
    shipped model expects them; "forearm": wrist straps, sensors.sensor_bones).
    noise: "realistic" sensor errors (what the targets are for) or "none" (perfect sensors).
    sensors: the segment names synthesised, in the models' input order; absent: those of them
    missing for the whole of every clip (mask 0, zero inputs: masked models only); body_scale:
    every clip's skeleton and root path scaled by it. torch_device: where the PyTorch model runs
    (a GPU scores a fold of cross-validation in seconds; the CPU is the reference)."""
    for m in motions:
        if m.num_frames == 0:
            raise UsageError(f"motion {m.name}: no frames to evaluate")
    rng = np.random.default_rng(seed)
    clips = [without_sensors(synthesize_clip(m, rng, wrist, noise, sensors, body_scale), absent)
             for m in motions]
    if not clips:
        raise UsageError("no motions to evaluate")
    preds = {"baseline": [predict_baseline(c, wrist) for c in clips]}
    params = None
    if checkpoint:
        from .model import count_parameters
        net = load_torch_model(checkpoint, mirror=mirror)
        params = count_parameters(net)
        preds["PyTorch fp32"] = predict_torch(net, clips, torch_device)
    from .ort import onnx_runtime_available
    lat = None
    for mp in models:
        mp = Path(mp)
        if not mp.is_file():
            print(f"evaluate: {mp} not found; skipped")
            continue
        if not onnx_runtime_available():
            print("evaluate: ONNX Runtime not available (scripts/fetch_onnxruntime.sh); ONNX skipped")
            break
        label = "ONNX fp16" if "fp16" in mp.name else "ONNX fp32" if "fp32" in mp.name else f"ONNX {mp.stem}"
        preds[label] = predict_onnx(mp, clips)
        if params is None:
            params = onnx_parameter_count(mp)
        if latency and lat is None and "fp16" not in mp.name:
            lat = measure_latency(mp, latency_frames, seed)
            lat["model"] = mp.name
    accs, results = {}, {}
    order = [n for n in ("PyTorch fp32", "ONNX fp32", "ONNX fp16") if n in preds] + \
        [n for n in preds if n not in ("PyTorch fp32", "ONNX fp32", "ONNX fp16", "baseline")] + ["baseline"]
    for name in order:
        acc = Accumulator()
        for c, p in zip(clips, preds[name]):
            acc.add(c, p)
        accs[name] = acc
        results[name] = acc.summary()
    _require_finite(results)
    if "PyTorch fp32" in preds and "ONNX fp32" in preds:
        diff = max(float(np.abs(a.local_rot - b.local_rot).max())
                   for a, b in zip(preds["PyTorch fp32"], preds["ONNX fp32"]))
        if diff > SAME_MODEL_TOLERANCE:
            print(f"evaluate: WARNING: the PyTorch checkpoint {checkpoint} is not the model the ONNX "
                  f"fp32 file was exported from (joint rotations differ by up to {diff:.3g}); pass "
                  "--checkpoint with the weights it came from")
    else:
        diff = None
    meta = {"when": time.strftime("%Y-%m-%d %H:%M"), "source": source, "clips": len(clips),
            "seconds": sum(c.local_rot.shape[0] / c.fps for c in clips), "seed": seed,
            "noise": _describe(eval_augmentation(noise, body_scale)), "noise_kind": noise,
            "body_scale": body_scale, "latency_frames": latency_frames, "wrist": wrist,
            "sensors": tuple(sensors), "absent": tuple(absent),
            "torch": "mirror-averaged (model.MirrorEnsemble)" if mirror else "single network",
            "checkpoint": _shown_path(checkpoint) if checkpoint else None, "torch_onnx_diff": diff}
    tj = truth_jitter(clips)
    meta["truth_elbows"] = truth_elbows(clips)
    report = write_report(out_dir, results, meta, lat, params, tj)
    write_clip_table(out_dir, results)
    write_plots(out_dir, results, accs, clips)
    return {"results": results, "latency": lat, "params": params, "report": report,
            "truth_jitter": tj}


# Metrics every clip of at least one frame defines: NaN here is a broken model or input, and a
# report must not show it as "-" (drift and jitter are NaN, "-", when clips are too short).
FINITE_METRICS = ("angle_all", "angle_dip", "sip", "pos")


def _require_finite(results) -> None:
    for name, s in results.items():
        bad = [k for k in FINITE_METRICS if not math.isfinite(s[k])]
        if bad:
            raise CommandError(f"the {name} results are not finite ({', '.join(bad)} = {s[bad[0]]}); "
                               "no report written")


def _shown_path(path) -> str:
    """Repository-relative where possible: reports are committed, absolute paths are not."""
    p = Path(path).resolve()
    try:
        return str(p.relative_to(REPO))
    except ValueError:
        return p.name


_NOISE_WORDS = {"realistic": "with realistic sensor noise",
                "none": "from perfect sensors, without any sensor error"}


def _describe(aug) -> str:
    from dataclasses import asdict
    return ", ".join(f"{k} {v}" for k, v in asdict(aug).items())


def _trim(motions, max_clips, max_seconds):
    if max_clips:
        motions = motions[:max_clips]
    if max_seconds:
        out = []
        for m in motions:
            n = int(max_seconds * m.fps)
            if n < 1:
                raise UsageError(f"--max-seconds {max_seconds:g} is shorter than one frame at {m.fps:g} Hz")
            out.append(sk.Motion(m.name, m.subject, m.fps, m.local_rot[:n], m.root_pos[:n], m.offsets))
        motions = out
    return motions


BODY_SCALE = number_type(float, lambda v: BODY_SCALE_RANGE[0] <= v <= BODY_SCALE_RANGE[1],
                          f"a number from {BODY_SCALE_RANGE[0]:g} to {BODY_SCALE_RANGE[1]:g}")
_POSITIVE_SECONDS = number_type(float, lambda v: v > 0, "a positive finite number of seconds")


def add_arguments(p):
    src = p.add_mutually_exclusive_group()
    src.add_argument("--split", default="val", choices=["train", "val", "test"],
                     help="train / val / test of the CMU data (default val)")
    src.add_argument("--bvh", help="a folder of BVH files instead (any depth; manifest.csv honoured), or a "
                     "motion pack (training pack)")
    p.add_argument("--models", nargs="*", default=None,
                   help="ONNX models (default: the shipped fp32 and fp16, where present)")
    p.add_argument("--checkpoint", default=None, help="PyTorch checkpoint (default: the first that exists "
                   "of " + ", ".join(CHECKPOINT_CANDIDATES) + ")")
    p.add_argument("--no-torch", action="store_true", help="skip the PyTorch model")
    p.add_argument("--no-mirror", dest="no_mirror", action="store_true",
                   help="evaluate the checkpoint as a single network, not mirror-averaged as exported")
    p.add_argument("--out", default=str(RESULTS_DIR))
    p.add_argument("--max-clips", type=POSITIVE_INT, default=0, help="evaluate the first N clips")
    p.add_argument("--max-seconds", type=_POSITIVE_SECONDS, default=0.0, help="cut clips to this length")
    p.add_argument("--seed", type=NON_NEGATIVE_INT, default=0)  # numpy's generators take no negative seeds
    p.add_argument("--wrist-sensor", dest="wrist_sensor", default=None, choices=WRIST_SENSOR_PLACES,
                   help="where the synthesised wrist sensors are: hand (back of the hands) or forearm "
                        "(wrist straps); default: where the checkpoint was trained to expect them "
                        "(hand without one)")
    p.add_argument("--noise", default="realistic", choices=NOISE_CHOICES,
                   help="sensor errors of the synthesised inputs: realistic (default; the targets are "
                        "for it) or none (perfect sensors: what the model reaches without them)")
    p.add_argument("--absent", default=None,
                   help="sensors missing for the whole of every clip, comma-separated (e.g. chest): "
                        "masked (model contract 2) models only")
    p.add_argument("--body-scale", dest="body_scale", type=BODY_SCALE, default=1.0,
                   help="scale every clip's skeleton and root path (a shorter or taller performer doing "
                        f"the same motion), {BODY_SCALE_RANGE[0]:g} to {BODY_SCALE_RANGE[1]:g}; default 1")
    p.add_argument("--no-latency", action="store_true")
    p.add_argument("--no-cache", action="store_true", help="do not cache converted BVH clips")
    return p


def expected_wrist_sensor(checkpoint) -> str:
    """Where a checkpoint's network expects the wrist sensors (ModelConfig.wrist_anchor); "hand"
    without a checkpoint (the shipped model's placement)."""
    if not checkpoint:
        return "hand"
    return load_torch_model(checkpoint, mirror=False).config.wrist_anchor


def expected_sensors(checkpoint, models=()) -> tuple:
    """The segment names a checkpoint's network reads (ModelConfig.sensors); without a
    checkpoint, those of the first ONNX model that exists (its sensor_order), else the default
    set."""
    if checkpoint:
        return tuple(load_torch_model(checkpoint, mirror=False).config.sensors)
    for m in models:
        if Path(m).is_file():
            from .ort import model_info, onnx_runtime_available
            if onnx_runtime_available():
                order = model_info(m).get("sensor_order")
                if order:
                    return tuple(order.split(","))
            break
    return DEFAULT_SENSORS


def absent_sensors(text, sensors) -> tuple:
    """--absent: segment names among `sensors`, never the pelvis (every model needs it)."""
    if not text:
        return ()
    absent = sensor_option(text, "--absent", sensors, "the evaluated models")
    if "pelvis" in absent:
        raise UsageError("--absent: the pelvis cannot be missing (every model needs it)")
    return absent


def main(args=None) -> int:
    if args is None or isinstance(args, list):
        args = add_arguments(argparse.ArgumentParser(prog="python3 -m training evaluate")).parse_args(args)
    from . import dataset
    source = args.bvh if args.bvh else args.split
    motions = dataset.load_motions(Path(args.bvh) if args.bvh else args.split,
                                   cache=not getattr(args, "no_cache", False))
    motions = _trim(motions, args.max_clips, args.max_seconds)
    ckpt = None if args.no_torch else (args.checkpoint or find_checkpoint())
    if not args.no_torch and ckpt is None:
        print("evaluate: no checkpoint found; PyTorch skipped")
    models = [str(m) for m in DEFAULT_MODELS] if args.models is None else args.models
    # Say what is measured: the default checkpoint is a training run's best.pt when one exists,
    # which a scratch run can have replaced.
    print(f"evaluate: {len(motions)} clips ({'BVH folder' if args.bvh else 'split'} {source}); "
          f"PyTorch {_shown_path(ckpt) if ckpt else '-'}; ONNX "
          f"{', '.join(_shown_path(m) for m in models) or '-'}")
    sensors = expected_sensors(ckpt, models)
    r = evaluate(motions, models, ckpt, args.out, args.seed, not args.no_latency,
                 source=f"{'BVH folder ' if args.bvh else 'split '}{source}",
                 mirror=not getattr(args, "no_mirror", False),
                 wrist=getattr(args, "wrist_sensor", None) or expected_wrist_sensor(ckpt),
                 noise=getattr(args, "noise", "realistic"), sensors=sensors,
                 absent=absent_sensors(getattr(args, "absent", None), sensors),
                 body_scale=getattr(args, "body_scale", 1.0))
    def shown(v, digits):   # "-" where clips are too short to measure (as in the report)
        return f"{v:.{digits}f}" if v == v else "-"
    for name, s in r["results"].items():
        print(f"{name:14s} angle {s['angle_all']:6.2f} deg (DIP15 {s['angle_dip']:6.2f})  SIP "
              f"{s['sip']:6.2f}  pos {s['pos']:6.2f} cm  drift 2/5/10 s {shown(s['drift_2s'], 3)} / "
              f"{shown(s['drift_5s'], 3)} / {shown(s['drift_10s'], 3)} m  jitter "
              f"{shown(s['jitter'], 2)} x10^2 m/s^3  travel x{shown(s['travel_ratio'], 3)}  elbow "
              f"p5/p95 {shown(s['elbow_p5'], 1)} / {shown(s['elbow_p95'], 1)} deg")
    if r["latency"]:
        print(f"latency (ORT, T=1, 1 thread): p50 {r['latency']['p50_us']:.0f} us, p99 "
              f"{r['latency']['p99_us']:.0f} us")
    print(f"evaluate: wrote {r['report']} and plots")
    return 0
