"""pose-range: the joint rotations and turning speeds people reach, to tell a pose that broke
from one that is only wrong.

    python3 -m training pose-range [--split train] [--every 1] [--frame-step 2]
        [--check val,test] [--out FILE] [--engine-table FILE.c]

While a sensor is silent the model must guess its bone, and a guess can be far from what the
person did and still be a pose a person takes (the arm hanging while the real one was raised: a
90 deg error, not a breakdown). A pose that broke bends a joint where no person's joint bends, or
snaps it round faster than anyone moves. This measures both against the training people's motion
capture, joint by joint and never against the clip's own truth:
  out of range  the joint's local rotation is more than OUT_OF_RANGE_DEG from every rotation that
                joint takes in the motion capture (a cover of them at COVER_DEG resolution)
  too fast      the joint turns faster than SPEED_MARGIN x the TOO_FAST_QUANTILE of its turning
                speed there (frame to frame, deg/s)
The range is built from every --every-th clip of --split (default train: the people nothing is
judged on), every --frame-step-th frame, and cached under training/data/pose_range/. --check
prints how many frames of those splits' own motion capture it calls implausible (it should call
almost none: a person's pose is plausible by definition); --out saves the range to a file too
(`missing-sensor --pose-range FILE` reads it).

--engine-table writes the engine's copy of the range (Native~/src/pose/pose_range_table.c): a
thinner cover, one rotation per ENGINE_COVER_DEG cell, quantised to int8, which the engine's pose
guard (pose_limits.c, `mocap_solver_set_pose_limits`) pulls a joint back towards when the model
bends it further than the guard's tolerance from all of them. `guard_quats` is the same rule in
numpy, the reference the engine's tests and the evaluations are checked against.
"""
from __future__ import annotations

import argparse
import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import skeleton as sk
from .cli import POSITIVE_INT
from .errors import UsageError

OUT_OF_RANGE_DEG = 30.0
COVER_DEG = 1.0
TOO_FAST_QUANTILE = 0.9999
SPEED_MARGIN = 1.5
# A joint that never turns in the motion capture (the skeleton's fixed joints) still gets a limit,
# so that a model that turns it anyway is caught rather than divided by zero.
MIN_SPEED_LIMIT_DEG_S = 90.0

CACHE_DIR = Path(__file__).resolve().parent / "data" / "pose_range"
ENGINE_TABLE = (Path(__file__).resolve().parent.parent / "Packages" / "com.mocap.imu" / "Native~"
                / "src" / "pose" / "pose_range_table.c")
# The engine's cover: coarse enough to stay small (11,000 rotations), fine enough that its
# distances are within a few degrees of the full cover's. With the guard's tolerance 5 deg inside
# OUT_OF_RANGE_DEG, a guarded pose is never counted out of range for the coarser cover.
ENGINE_COVER_DEG = 15.0
ENGINE_SCALE = 127
# A joint the guard left at the tolerance stays put when guarded again, rounding notwithstanding.
GUARD_SLACK_DEG = 1e-5


def canonical_quats(local_rot) -> np.ndarray:
    """(..., 3, 3) -> unit quaternions (..., 4), w >= 0."""
    q = sk.quat_from_rot(np.asarray(local_rot, np.float64))
    return np.where(q[..., :1] < 0, -q, q)


def chord_to_deg(chord) -> np.ndarray:
    """Euclidean distance of two unit quaternions -> the angle of the rotation between them, deg:
    |q1 - q2| = 2 sin(phi / 2) for the angle phi between the 4-vectors, and the rotation's is 2 phi."""
    return np.degrees(4.0 * np.arcsin(np.clip(np.asarray(chord, np.float64) / 2.0, 0.0, 1.0)))


def deg_to_chord(deg: float) -> float:
    return 2.0 * math.sin(math.radians(deg) / 4.0)


def turning_speed_deg_s(local_rot, fps: float) -> np.ndarray:
    """(T, J, 3, 3) -> (T, J) deg/s from the frame before (frame 0 repeats frame 1's)."""
    r = np.asarray(local_rot, np.float64)
    if len(r) < 2:
        return np.zeros(r.shape[:2])
    rel = np.einsum("tjba,tjbc->tjac", r[:-1], r[1:])
    cos = np.clip((np.trace(rel, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    s = np.degrees(np.arccos(cos)) * fps
    return np.concatenate([s[:1], s])


@dataclass
class PoseRange:
    """Per joint: a cover of the local rotations the motion capture takes (unit quaternions, w >=
    0), and the turning speed past which a joint is too fast (deg/s)."""
    covers: list                # 24 arrays (N_j, 4)
    speed_limit: np.ndarray     # (24,) deg/s
    source: str = ""

    def __post_init__(self):
        from scipy.spatial import cKDTree
        if len(self.covers) != sk.NUM_JOINTS or len(self.speed_limit) != sk.NUM_JOINTS:
            raise ValueError(f"a pose range needs {sk.NUM_JOINTS} joints")
        # q and -q are one rotation: both signs go in, so the nearest point is the nearest rotation.
        self._trees = [cKDTree(np.concatenate([c, -c])) for c in self.covers]

    def distance_deg(self, local_rot) -> np.ndarray:
        """(T, 24, 3, 3) -> (T, 24): each joint's angle to the nearest rotation of the cover, deg
        (NaN where the rotation is not finite)."""
        r = np.asarray(local_rot, np.float64)
        finite = np.isfinite(r).all(axis=(-2, -1))
        q = canonical_quats(np.where(finite[..., None, None], r, np.eye(3)))
        out = np.empty(r.shape[:2])
        for j, tree in enumerate(self._trees):
            chord, _ = tree.query(q[:, j])
            out[:, j] = chord_to_deg(chord)
        out[~finite] = np.nan
        return out

    def implausible(self, local_rot, fps: float) -> dict:
        """(T, 24, 3, 3) -> {"range": (T, 24) out of range, "speed": (T, 24) too fast}."""
        dist = self.distance_deg(local_rot)
        with np.errstate(invalid="ignore"):
            speed = turning_speed_deg_s(local_rot, fps)
            return {"range": ~(dist <= OUT_OF_RANGE_DEG),
                    "speed": ~(speed <= self.speed_limit[None, :])}

    def save(self, path: Path) -> Path:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".tmp.npz")
        np.savez(tmp, speed_limit=self.speed_limit, source=np.array(self.source),
                 **{f"cover_{j}": c.astype(np.float32) for j, c in enumerate(self.covers)})
        tmp.replace(path)
        return path

    @classmethod
    def load(cls, path: Path) -> "PoseRange":
        with np.load(path) as z:
            return cls([z[f"cover_{j}"].astype(np.float64) for j in range(sk.NUM_JOINTS)],
                       z["speed_limit"].astype(np.float64), str(z["source"]))


def build_pose_range(motions, frame_step: int = 2, source: str = "") -> PoseRange:
    """The range of the motions' joints: every frame_step-th frame's rotations, thinned to one per
    cell of a COVER_DEG grid on the quaternion; speeds from every frame."""
    if not motions:
        raise UsageError("no clips to measure the range of motion on")
    grid = deg_to_chord(COVER_DEG)
    cells = [set() for _ in range(sk.NUM_JOINTS)]
    speeds = []
    for m in motions:
        q = canonical_quats(m.local_rot[::frame_step])
        keys = np.round(q / grid).astype(np.int32)
        for j in range(sk.NUM_JOINTS):
            cells[j].update(map(tuple, np.unique(keys[:, j], axis=0)))
        speeds.append(turning_speed_deg_s(m.local_rot, m.fps))
    covers = []
    for j in range(sk.NUM_JOINTS):
        c = np.array(sorted(cells[j]), np.float64) * grid
        covers.append(c / np.linalg.norm(c, axis=-1, keepdims=True))
    limit = np.quantile(np.concatenate(speeds), TOO_FAST_QUANTILE, axis=0) * SPEED_MARGIN
    return PoseRange(covers, np.maximum(limit, MIN_SPEED_LIMIT_DEG_S), source)


def engine_cover(pose_range: PoseRange, cover_deg: float = ENGINE_COVER_DEG) -> list:
    """Per joint, one rotation of the range per cell of a cover_deg grid on the quaternion (the
    first in the cover's order, so a real rotation of the range), quantised as the engine stores
    them: int8 components, ENGINE_SCALE for 1. The root (its global orientation) gets none."""
    grid = deg_to_chord(cover_deg)
    out = [np.zeros((0, 4), np.int8)]
    for c in pose_range.covers[1:]:
        keys = np.round(c / grid).astype(np.int32)
        _, first = np.unique(keys, axis=0, return_index=True)
        pts = c[np.sort(first)]
        out.append(np.clip(np.round(pts * ENGINE_SCALE), -127, 127).astype(np.int8))
    return out


def guard_quats(quats, cover, tolerance_deg: float):
    """The engine's pose guard in numpy: quats (P, 24, 4) local rotations (w, x, y, z) -> (guarded
    copy, (P, 24) bool of the joints it moved). A joint further than tolerance_deg from every
    rotation of its cover (engine_cover) is turned back along the shortest way towards the
    nearest one until it is tolerance_deg from it."""
    q = np.asarray(quats, np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    out, moved = q.copy(), np.zeros(q.shape[:2], bool)
    for j, pts in enumerate(cover):
        if len(pts) == 0:
            continue
        p = pts.astype(np.float64)
        p /= np.linalg.norm(p, axis=-1, keepdims=True)
        dots = q[:, j] @ p.T
        best = np.argmax(np.abs(dots), axis=1)
        d = dots[np.arange(len(q)), best]
        near = p[best] * np.sign(np.where(d == 0, 1.0, d))[:, None]
        half = np.arccos(np.clip(np.abs(d), 0.0, 1.0))          # half the rotation angle
        far = np.degrees(2.0 * half) > tolerance_deg + GUARD_SLACK_DEG
        if not far.any():
            continue
        t = np.radians(tolerance_deg) / (2.0 * half[far])
        sh = np.sin(half[far])
        y = ((np.sin((1.0 - t) * half[far]) / sh)[:, None] * near[far]
             + (np.sin(t * half[far]) / sh)[:, None] * q[far, j])
        out[far, j] = y / np.linalg.norm(y, axis=-1, keepdims=True)
        moved[far, j] = True
    return out, moved


def write_engine_table(path: Path, pose_range: PoseRange, cover_deg: float = ENGINE_COVER_DEG) -> int:
    """The engine's cover as C source (pose_range_table.h's declarations); returns its size."""
    cover = engine_cover(pose_range, cover_deg)
    lines = ["/* The range of each joint's local rotation in the training people's motion capture, for",
             " * the pose guard (pose_limits.c): one rotation per " f"{cover_deg:g}" " deg cell of a cover of them,",
             " * quaternions (w, x, y, z) scaled by POSE_RANGE_SCALE. Written by",
             " * `python3 -m training pose-range --engine-table` from "
             f"{pose_range.source or 'a pose range'};",
             " * not edited by hand. */",
             '#include "pose_range_table.h"', "",
             "const pose_range_span pose_range_joints[POSE_RANGE_JOINTS] = {"]
    first = 0
    for j, pts in enumerate(cover):
        lines.append(f"    {{{first}, {len(pts)}}},   /* {sk.JOINT_NAMES[j]} */")
        first += len(pts)
    lines += ["};", "", f"const int8_t pose_range_points[{max(first, 1)}][4] = {{"]
    for pts in cover:
        for k in range(0, len(pts), 6):
            lines.append("    " + " ".join("{%d,%d,%d,%d}," % tuple(int(v) for v in p)
                                           for p in pts[k:k + 6]))
    lines += ["};", ""]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines))
    return first


def read_engine_table(path: Path = ENGINE_TABLE) -> list:
    """The cover a table of write_engine_table holds (engine_cover's form), read back from its C
    source: what the engine guards with, without the motion capture it was measured on."""
    import re
    text = Path(path).read_text()
    spans = [(int(a), int(b)) for a, b in re.findall(r"\{(\d+), (\d+)\},\s+/\*", text)]
    points = np.array(re.findall(r"\{(-?\d+),(-?\d+),(-?\d+),(-?\d+)\},", text), np.int64)
    if len(spans) != sk.NUM_JOINTS or sum(b for _, b in spans) != len(points):
        raise ValueError(f"{path}: not a pose range table of {sk.NUM_JOINTS} joints")
    return [points[a:a + b].reshape(-1, 4).astype(np.int8) for a, b in spans]


def _source_key(split: str, every: int, frame_step: int) -> str:
    from . import dataset
    h = hashlib.sha1()
    h.update(Path(__file__).read_bytes())
    h.update(f"{dataset.code_version()}|{split}|{every}|{frame_step}".encode())
    return h.hexdigest()[:12]


def training_pose_range(split: str = "train", every: int = 1, frame_step: int = 2,
                        progress=print) -> PoseRange:
    """The range of every `every`-th clip of a CMU split, built once and cached."""
    path = CACHE_DIR / f"{split}-{every}-{frame_step}-{_source_key(split, every, frame_step)}.npz"
    if path.exists():
        return PoseRange.load(path)
    from . import dataset
    if progress:
        progress(f"pose range: measuring every {every}th clip of the CMU {split} split (cached "
                 f"under {CACHE_DIR.name}/ afterwards)")
    motions = dataset.load_motions(split, progress=False, every=every)
    which = "every clip" if every == 1 else f"one clip in {every}"
    frames = "every frame" if frame_step == 1 else f"one frame in {frame_step}"
    r = build_pose_range(motions, frame_step,
                         f"{which} of the CMU {split} split ({len(motions)} clips), {frames}")
    r.save(path)
    return r


def implausible_share(pose_range: PoseRange, motions) -> tuple:
    """(frames, frames with a joint out of range, frames with a joint too fast) of motions."""
    frames = out = fast = 0
    for m in motions:
        bad = pose_range.implausible(m.local_rot, m.fps)
        frames += m.num_frames
        out += int(bad["range"].any(axis=1).sum())
        fast += int(bad["speed"].any(axis=1).sum())
    return frames, out, fast


def add_arguments(p):
    p.add_argument("--split", default="train", choices=["train", "val", "test"],
                   help="clips to measure the range on (default train)")
    p.add_argument("--every", type=POSITIVE_INT, default=1, help="every Nth clip of it (default 1)")
    p.add_argument("--frame-step", type=POSITIVE_INT, default=2,
                   help="every Nth frame of a clip for the rotations (default 2)")
    p.add_argument("--check", default="val,test",
                   help="splits whose motion capture is checked against the range (default "
                        "val,test; empty: none)")
    p.add_argument("--out", default=None, help="save the range to this file as well")
    p.add_argument("--engine-table", default=None, metavar="FILE.c",
                   help=f"write the engine's copy of the range as C source (the engine's own: "
                        f"{ENGINE_TABLE.relative_to(ENGINE_TABLE.parents[4])})")
    return p


def main(args=None) -> int:
    if args is None or isinstance(args, list):
        args = add_arguments(argparse.ArgumentParser(prog="python3 -m training pose-range")).parse_args(args)
    from . import dataset
    checks = [s for s in args.check.split(",") if s]
    bad = [s for s in checks if s not in dataset.SPLITS]
    if bad:
        raise UsageError(f"--check: {', '.join(bad)} is not a split ({', '.join(dataset.SPLITS)})")
    r = training_pose_range(args.split, args.every, args.frame_step)
    print(f"pose-range: {r.source}")
    if args.out:
        print(f"  saved to {r.save(Path(args.out))}")
    if args.engine_table:
        n = write_engine_table(Path(args.engine_table), r)
        print(f"  engine table: {n} rotations, one per {ENGINE_COVER_DEG:g} deg cell, -> {args.engine_table}")
    print(f"  out of range: more than {OUT_OF_RANGE_DEG:g} deg from every rotation of the joint "
          f"(cover of {COVER_DEG:g} deg)")
    print(f"  too fast: over {SPEED_MARGIN:g} x the {TOO_FAST_QUANTILE:g} quantile of the joint's speed")
    print("  joint              cover  speed limit deg/s")
    for j, name in enumerate(sk.JOINT_NAMES):
        print(f"  {j:2d} {name:15s} {len(r.covers[j]):6d} {r.speed_limit[j]:10.0f}")
    for split in checks:
        frames, out, fast = implausible_share(r, dataset.load_motions(split, progress=False))
        print(f"  {split} motion capture: {frames} frames, {out} ({100.0 * out / frames:.3f} %) "
              f"with a joint out of range, {fast} ({100.0 * fast / frames:.3f} %) too fast")
    return 0
