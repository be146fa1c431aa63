"""synth-capture: a BVH clip -> a raw HiPNUC capture the engine can replay, plus the ground truth.

    python3 -m training synth-capture CLIP.bvh --out CAPTURE [--truth POSE.npz]
        [--truth-csv CSV] [--sensor-truth CSV] [--seed N] [--world nwu|enu] [--noise realistic|none]
        [--lead-in S] [--keep-trajectory] [--sensors SEGMENT,SEGMENT,...]
        [--silence SEGMENT@START+LENGTH ...]

Steps: BVH -> Motion (bvh.read_bvh + retarget.to_smpl_motion, 60 Hz) -> a lead-in of S seconds
(default 1) blending from the rest T-pose (every joint identity, facing +Z, as the calibration
prelude ends) into the clip's first frame -> per-segment sensor signals (bone orientation and
sensor linear acceleration in the model frame, gravity excluded: synthesis.synthesize without
augmentation) resampled to 100 Hz -> the trajectory text file of
Packages/com.mocap.imu/Native~/docs/synth-trajectory.md -> `mocapctl synth --trajectory FILE
--out CAPTURE --truth SENSOR_CSV --noise realistic --seed N --world W`, which adds the
calibration prelude (heading 3 s, strapping 2 s, T-pose 3 s), random mountings and headings and
realistic sensor noise. --silence SEGMENT@START+LENGTH (repeatable) makes that segment's sensor
send nothing from START for LENGTH seconds of the trajectory's time (0 = the start of the
lead-in, the first truth frame; `mocapctl synth --silence`): its blocks are left out of the
frames, as a sensor out of radio range would be, and every other byte is the capture's without it.

Ground truth pose file (--truth, default CAPTURE with suffix .truth.npz), numpy .npz:
    local_rot        (N,24,3,3) float32  joint 0 global (model frame), others local to parent
    root_pos         (N,3) float32       metres, model frame
    offsets          (24,3) float32      the retargeted skeleton's rest offsets
    fps              ()                  frames per second of the truth (60)
    joint_names      (24,) str, parents (24,) int
    motion_start     ()  int             truth frame where the clip itself begins (after lead-in)
    t_session_start  ()  float           session time (s) of truth frame 0 = the replayed frames'
                                         time_s clock (`mocap_frame.time_s`); frame i is at
                                         t_session_start + i / fps
    prelude_s        ()  float           calibration prelude length in the capture
    clip, world, seed                    provenance
    sensors          (N,) str            the capture's segments, in node order of the capture
    silences         (K,) str            the silence windows, "SEGMENT@START+LENGTH" (seconds
                                         after truth frame 0), none when K = 0
The same pose truth as CSV (--truth-csv, default CAPTURE with suffix .truth.csv), for tools
without numpy (`mocapctl replay CAPTURE --model M --truth CAPTURE.truth.csv` prints the pose
accuracy of the whole byte-level pipeline): a header line, then one line per truth frame:
    t_session, motion, root_x, root_y, root_z, then per joint (24, model order) qw, qx, qy, qz
t_session: session time (s) of the frame (t_session_start + i / fps); motion: 0 for the lead-in
frames, 1 for the clip's own; root position in metres, model frame; quaternions (w,x,y,z) of
local_rot (joint 0 global, the others local to their parent). Comma separated, 7 decimals.
The engine's own per-sensor truth (bone quaternions + accelerations per 100 Hz tick, phases) is
written by mocapctl to --sensor-truth (default CAPTURE with suffix .sensors.csv); `mocapctl
replay CAPTURE --truth SENSOR_CSV` compares the calibrated output against it.
"""
from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import skeleton as sk
from .cli import number_type
from .errors import CommandError, UsageError
from .files import same_file
from .sensors import DEFAULT_SENSORS, node_ids, sensor_list

TRAJECTORY_RATE = 100.0
# The sensors of a capture unless --sensors names others: the engine's default set, in the
# table's order, which mocapctl synth also writes without --sensors.
TRAJECTORY_SENSORS = DEFAULT_SENSORS
MAX_LEAD_IN_S = 60.0   # a blend from the T-pose into the clip; minutes of it would be a mistake
MAX_SILENCES = 16      # the generator's SYNTH_MAX_SILENCES


@dataclass(frozen=True)
class Silence:
    """The sensor on `segment` sends nothing from `start_s` for `length_s` seconds (time since
    the capture's motion, lead-in included, began: truth frame 0)."""
    segment: str
    start_s: float
    length_s: float

    def __str__(self) -> str:
        return f"{self.segment}@{float(self.start_s)!r}+{float(self.length_s)!r}"

    @property
    def end_s(self) -> float:
        return self.start_s + self.length_s


def parse_silence(text) -> Silence:
    """"SEGMENT@START+LENGTH" (a Silence passes through); ValueError saying what is wrong."""
    if isinstance(text, Silence):
        segment, start_s, length_s = text.segment, float(text.start_s), float(text.length_s)
    else:
        segment, at, window = str(text).partition("@")
        start, plus, length = window.partition("+")
        try:
            if not (segment and at and plus):
                raise ValueError
            start_s, length_s = float(start), float(length)
        except ValueError:
            raise ValueError(f"{text!r} is not SEGMENT@START+LENGTH (seconds, e.g. "
                             f"left_wrist@10+5)") from None
    if not (math.isfinite(start_s) and start_s >= 0 and math.isfinite(length_s) and length_s > 0):
        raise ValueError(f"{text!r}: the start must be >= 0 s and the length > 0 s")
    return Silence(segment, start_s, length_s)


def silence_list(silences, sensors) -> list:
    """Silence windows (strings or Silence) checked against the capture's segments."""
    out = [parse_silence(s) for s in (silences or ())]
    if len(out) > MAX_SILENCES:
        raise ValueError(f"{len(out)} silence windows, at most {MAX_SILENCES}")
    for s in out:
        if s.segment not in sensors:
            raise ValueError(f"{s}: {s.segment} is not one of the capture's sensors ({', '.join(sensors)})")
    return out


def _smooth(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * u * (u * (6 * u - 15) + 10)


def with_lead_in(motion: sk.Motion, seconds: float = 1.0) -> sk.Motion:
    """The motion preceded by `seconds` of a blend from the rest T-pose (identity rotations, root
    above the first frame's floor point at rest pelvis height) into its first frame."""
    n = int(round(seconds * motion.fps))
    if n <= 0:
        return motion
    u = _smooth(np.arange(n) / n)
    first = motion.local_rot[0].astype(np.float64)
    eye = np.broadcast_to(np.eye(3), first.shape)
    rots = np.stack([sk.slerp_rot(eye, first, ui) for ui in u]).astype(np.float32)
    r0 = motion.root_pos[0].astype(np.float64)
    rest = np.array([r0[0], motion.offsets[0, 1], r0[2]])
    roots = (rest[None] + u[:, None] * (r0 - rest)[None]).astype(np.float32)
    return sk.Motion(motion.name, motion.subject, motion.fps,
                     np.concatenate([rots, motion.local_rot]).astype(np.float32),
                     np.concatenate([roots, motion.root_pos]).astype(np.float32), motion.offsets)


def sensor_signals(motion: sk.Motion, sensors=TRAJECTORY_SENSORS):
    """(orientation (T,N,3,3) bone -> model, acceleration (T,N,3) m/s^2 model frame, gravity
    excluded) of the sensors (segment names) at the motion's frame rate, from
    synthesis.synthesize without augmentation."""
    from .synthesis import synthesize
    sample = synthesize(motion, rng=None, augment=None, sensors=sensors)
    return (np.asarray(sample.imu_orientation, np.float64),
            np.asarray(sample.imu_acceleration, np.float64))


def resample_signals(orientation, acceleration, fps, rate=TRAJECTORY_RATE):
    """Slerp orientations / lerp accelerations (T,N,...) from fps to rate. Returns t, quats
    (M,N,4), acc (M,N,3)."""
    T = orientation.shape[0]
    duration = (T - 1) / fps
    t = np.arange(int(np.floor(duration * rate + 1e-9)) + 1) / rate
    x = t * fps
    i0 = np.minimum(np.floor(x).astype(int), T - 1)
    i1 = np.minimum(i0 + 1, T - 1)
    w = (x - i0)
    q = sk.quat_from_rot(orientation)                              # (T,N,4)
    quats = sk.slerp_quat(q[i0], q[i1], np.broadcast_to(w[:, None], (len(t), q.shape[1])))
    acc = acceleration[i0] + w[:, None, None] * (acceleration[i1] - acceleration[i0])
    return t, quats, acc


def write_trajectory(path, t, quats, acc, comment="", sensors=TRAJECTORY_SENSORS):
    """The text format of Native~/docs/synth-trajectory.md: a `segments` line naming the sensors
    (segment names) in their column order, then 1 + 7 N numbers per line, quats (M,N,4) and acc
    (M,N,3)."""
    if quats.shape[1] != len(sensors) or acc.shape[1] != len(sensors):
        raise ValueError(f"{len(sensors)} sensors, but quats {quats.shape} and acc {acc.shape}")
    with open(path, "w") as f:
        f.write("# synth-capture trajectory" + (f": {comment}" if comment else "") + "\n")
        f.write("segments " + " ".join(sensors) + "\n")
        f.write("# t  then per segment: qw qx qy qz ax ay az\n")
        for k in range(len(t)):
            vals = [f"{t[k]:.5f}"]
            for s in range(len(sensors)):
                vals += [f"{v:.7f}" for v in quats[k, s]] + [f"{v:.5f}" for v in acc[k, s]]
            f.write(" ".join(vals) + "\n")


def _read_motion_start(sensor_csv) -> tuple[float, float]:
    """(session time of the first row, session time of the first motion-phase row)."""
    first = start = None
    with open(sensor_csv) as f:
        for line in f:
            if not line[:1].isdigit() and line[:1] != "-":
                continue
            parts = line.replace(",", " ").split()
            t, phase = float(parts[0]), int(float(parts[1]))
            if first is None:
                first = t
            if phase == 3:
                start = t
                break
    if first is None or start is None:
        raise CommandError(f"{sensor_csv}: no motion phase rows (mocapctl wrote no motion)")
    return first, start


def write_truth_csv(path, local_rot, root_pos, fps, t_session_start, motion_start) -> None:
    """The pose truth as CSV (format in the module docstring)."""
    q = sk.quat_from_rot(np.asarray(local_rot, np.float64))          # (N,24,4)
    n = q.shape[0]
    cols = ["t_session", "motion", "root_x", "root_y", "root_z"]
    for name in sk.JOINT_NAMES:
        cols += [f"{name}_qw", f"{name}_qx", f"{name}_qy", f"{name}_qz"]
    t = t_session_start + np.arange(n) / float(fps)
    flag = (np.arange(n) >= motion_start).astype(np.int64)
    with open(path, "w", newline="\n") as f:
        f.write(",".join(cols) + "\n")
        for i in range(n):
            vals = [f"{t[i]:.7f}", str(int(flag[i]))]
            vals += [f"{v:.7f}" for v in root_pos[i]]
            vals += [f"{v:.7f}" for v in q[i].ravel()]
            f.write(",".join(vals) + "\n")


def _check_outputs(bvh_path, outputs: dict) -> None:
    """Every output is a new or regular file, none is the BVH being read, no two are one file:
    writing one would otherwise destroy the input or another output before it is used."""
    named = list(outputs.items())
    for i, (what, path) in enumerate(named):
        if path.exists() and not path.is_file():
            raise UsageError(f"{what} {path}: not a regular file (a folder or a device)")
        if bvh_path is not None and same_file(path, Path(bvh_path)):
            raise UsageError(f"{what} {path} is the BVH clip this command reads: writing it would destroy it")
        for other, other_path in named[:i]:
            if same_file(path, other_path):
                raise UsageError(f"{other} and {what} name the same file ({path})")


def _remove_new(paths, existed: dict) -> None:
    """After a failure: remove the outputs this run created (a file that was there before is
    left as it is: it may be a user's earlier result)."""
    for path in paths:
        if not existed.get(path, True):
            try:
                path.unlink()
            except OSError:
                pass


def synth_capture(bvh_path, out, truth=None, sensor_truth=None, seed=1, world="nwu",
                  noise="realistic", lead_in=1.0, keep_trajectory=False, motion=None,
                  truth_csv=None, sensors=TRAJECTORY_SENSORS, silences=()):
    """Write CAPTURE, its sensor truth CSV and the pose truth .npz; returns a dict of paths and
    facts. `motion` (a Motion) replaces reading bvh_path when given. sensors: the segments the
    capture carries (node ids from sensors.node_ids). silences: Silence windows (or their
    "SEGMENT@START+LENGTH" text) in which a sensor sends nothing."""
    from .ort import mocapctl_path
    if not (isinstance(seed, (int, np.integer)) and 0 <= int(seed) < 2 ** 64):
        raise UsageError(f"--seed {seed}: a whole number from 0 to 2^64-1")
    if not (math.isfinite(lead_in) and 0.0 <= lead_in <= MAX_LEAD_IN_S):
        raise UsageError(f"--lead-in {lead_in}: seconds from 0 to {MAX_LEAD_IN_S:g}")
    try:
        sensors = sensor_list(sensors)
        from .synthesis import sensor_offsets
        sensor_offsets(sk.DEFAULT_OFFSETS, sensors)   # a segment without a placement: refused now
    except ValueError as e:
        raise UsageError(f"--sensors: {e}") from e
    try:
        silences = silence_list(silences, sensors)
    except ValueError as e:
        raise UsageError(f"--silence {e}") from e
    if str(out).endswith(("/", os.sep)):
        raise UsageError(f"--out {out}: names a folder; give the capture file to write")
    out = Path(out)
    truth = Path(truth) if truth else out.with_suffix(".truth.npz")
    if truth.suffix != ".npz":   # np.savez would append it: name the file it really writes
        truth = truth.with_name(truth.name + ".npz")
    sensor_truth = Path(sensor_truth) if sensor_truth else out.with_suffix(".sensors.csv")
    truth_csv = Path(truth_csv) if truth_csv else out.with_suffix(".truth.csv")
    traj = out.with_suffix(".trajectory.txt")
    outputs = {"--out": out, "--truth": truth, "--sensor-truth": sensor_truth,
               "--truth-csv": truth_csv, "the trajectory": traj}
    _check_outputs(bvh_path if motion is None else None, outputs)
    if motion is None:
        from .bvh import read_bvh
        from .retarget import to_smpl_motion
        from .retarget import detect_source
        name = Path(bvh_path).stem
        if not Path(bvh_path).is_file():
            raise UsageError(f"{bvh_path}: no such BVH file")
        clip = read_bvh(bvh_path)
        if clip.num_frames == 0:
            raise UsageError(f"{bvh_path}: the BVH file has no frames")
        try:
            detect_source(clip.joints)
        except ValueError as e:
            raise UsageError(f"{bvh_path}: {e}") from e
        motion = to_smpl_motion(clip, name=name)
    if motion.num_frames == 0:
        raise UsageError(f"{bvh_path}: the clip is shorter than one frame at {sk.MODEL_FPS} Hz")
    full = with_lead_in(motion, lead_in)
    ori, acc = sensor_signals(full, sensors)
    t, quats, acc100 = resample_signals(ori, acc, full.fps)
    out.parent.mkdir(parents=True, exist_ok=True)
    existed = {p: p.exists() for p in outputs.values()}
    writing = traj
    try:
        write_trajectory(traj, t, quats, acc100, comment=f"{motion.name}, lead-in {lead_in} s",
                         sensors=sensors)
        cmd = [str(mocapctl_path(require_onnx=False)), "synth", "--trajectory", str(traj), "--out",
               str(out), "--truth", str(sensor_truth), "--seed", str(int(seed)), "--world", world,
               "--noise", noise]
        if sensors != DEFAULT_SENSORS:
            cmd += ["--sensors", ",".join(f"{n}={node}" for n, node in zip(sensors, node_ids(sensors)))]
        for silence in silences:
            cmd += ["--silence", str(silence)]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise CommandError("mocapctl synth failed: " + (r.stderr.strip() or f"status {r.returncode}"))
        if not keep_trajectory:
            traj.unlink()
        t_first, t_motion = _read_motion_start(sensor_truth)
        n_lead = full.num_frames - motion.num_frames
        writing = truth
        np.savez(truth, local_rot=full.local_rot, root_pos=full.root_pos, offsets=full.offsets,
                 fps=np.float64(full.fps), joint_names=np.array(sk.JOINT_NAMES),
                 parents=np.array(sk.PARENTS), motion_start=np.int64(n_lead),
                 t_session_start=np.float64(t_motion), prelude_s=np.float64(t_motion - t_first),
                 clip=str(motion.name), world=world, seed=np.int64(seed), sensors=np.array(sensors),
                 silences=np.array([str(s) for s in silences], dtype=str))
        writing = truth_csv
        write_truth_csv(truth_csv, full.local_rot, full.root_pos, full.fps, t_motion, n_lead)
    except OSError as e:
        # A full disk or an unwritable folder: say which file, and leave no half of the set.
        _remove_new(outputs.values(), existed)
        raise CommandError(f"writing {e.filename or writing}: {e.strerror or e}") from e
    except BaseException:
        _remove_new(outputs.values(), existed)
        raise
    return {"capture": out, "truth": truth, "truth_csv": truth_csv, "sensor_truth": sensor_truth,
            "trajectory": traj if keep_trajectory else None, "frames": full.num_frames,
            "motion_start": n_lead, "t_session_start": t_motion, "prelude_s": t_motion - t_first,
            "silences": silences, "mocapctl": r.stdout.strip()}


def load_truth(path) -> dict:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


SEED = number_type(int, lambda v: 0 <= v < 2 ** 64, "a whole number from 0 to 2^64-1")
LEAD_IN = number_type(float, lambda v: 0.0 <= v <= MAX_LEAD_IN_S,
                      f"a number of seconds from 0 to {MAX_LEAD_IN_S:g}")


def add_arguments(p=None):
    p = p or argparse.ArgumentParser(prog="python3 -m training synth-capture",
                                     description=__doc__.split("\n")[0])
    p.add_argument("bvh", help="BVH clip (CMU Daz, cgspeed, or our SMPL-24 skeleton)")
    p.add_argument("--out", required=True, help="capture file to write")
    p.add_argument("--truth", help="pose truth .npz (default: CAPTURE.truth.npz)")
    p.add_argument("--truth-csv", help="pose truth as CSV (default: CAPTURE.truth.csv)")
    p.add_argument("--sensor-truth", help="per-sensor truth CSV from mocapctl (default: CAPTURE.sensors.csv)")
    p.add_argument("--seed", type=SEED, default=1, help="noise and mounting draws (0 to 2^64-1)")
    p.add_argument("--world", choices=["nwu", "enu"], default="nwu")
    p.add_argument("--noise", choices=["realistic", "none"], default="realistic")
    p.add_argument("--lead-in", type=LEAD_IN, default=1.0,
                   help=f"seconds of T-pose -> clip blend (0 to {MAX_LEAD_IN_S:g})")
    p.add_argument("--keep-trajectory", action="store_true", help="keep CAPTURE.trajectory.txt")
    p.add_argument("--sensors", default=",".join(DEFAULT_SENSORS),
                   help="the capture's segments, comma-separated (default: the engine's default "
                        "set); segments without a default node get the lowest free node ids")
    p.add_argument("--silence", action="append", default=[], metavar="SEGMENT@START+LENGTH",
                   help="that segment's sensor sends nothing from START for LENGTH seconds after "
                        "the motion (lead-in included) begins; repeatable")
    return p


def main(args=None):
    if args is None or isinstance(args, list):
        args = add_arguments().parse_args(args)
    info = synth_capture(args.bvh, args.out, args.truth, args.sensor_truth, args.seed, args.world,
                         args.noise, args.lead_in, args.keep_trajectory,
                         truth_csv=getattr(args, "truth_csv", None),
                         sensors=getattr(args, "sensors", None) or TRAJECTORY_SENSORS,
                         silences=getattr(args, "silence", None) or ())
    print(info["mocapctl"])
    print(f"synth-capture: {info['capture']} ({info['frames']} truth frames, clip from frame "
          f"{info['motion_start']}, truth frame 0 at session t={info['t_session_start']:.3f} s "
          f"after a {info['prelude_s']:.1f} s prelude); pose truth {info['truth']} and "
          f"{info['truth_csv']}, sensor truth "
          f"{info['sensor_truth']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
