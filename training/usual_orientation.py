"""usual-orientation: where the hands and the head usually are relative to the body, for sensors
that fell silent.

    python3 -m training usual-orientation [--split train] [--every 4] [--frame-step 6]

A model must be fed something while a sensor is silent. A wrist's held
sample stays wherever the hand last was (an arm raised when the sensor dropped stays raised), and
the head as the model last posed it wanders off, so the engine turns them towards their bone's
usual orientation over a few seconds. "Usual" is the mean orientation of the bone (the joint the
sensor is read as) in the frame of the pelvis' heading: the rotation nearest, in the chordal
sense, to every sample of the clips (the SVD projection of their mean matrix), measured on the
training people only.

Prints the rotations as the C initialisers of solver.c's USUAL_LEFT_WRIST, USUAL_RIGHT_WRIST and
USUAL_HEAD, and how spread the orientations are (the mean matrix's singular values: 1 for a bone
that never turns, 1/3 for one with no preferred orientation).
"""
from __future__ import annotations

import argparse

import numpy as np

from . import skeleton as sk
from .cli import POSITIVE_INT
from .errors import UsageError

BONES = {"left_wrist": 20, "right_wrist": 21, "head": 15}   # segment -> the joint it is read as


def heading_rotations(pelvis: np.ndarray) -> np.ndarray:
    """Ry(heading) of pelvis orientations (T, 3, 3): the turn about +Y of the pelvis' forward axis
    on the floor, read as the engine reads it (its up axis keeps it defined when the forward axis
    is vertical)."""
    s = pelvis[:, 0, 2] - pelvis[:, 1, 2] * pelvis[:, 0, 1]
    c = pelvis[:, 2, 2] - pelvis[:, 1, 2] * pelvis[:, 2, 1]
    h = np.arctan2(s, c)
    out = np.zeros((len(h), 3, 3))
    out[:, 0, 0] = out[:, 2, 2] = np.cos(h)
    out[:, 0, 2] = np.sin(h)
    out[:, 2, 0] = -np.sin(h)
    out[:, 1, 1] = 1.0
    return out


def nearest_rotation(m: np.ndarray) -> np.ndarray:
    """The rotation nearest to a 3x3 matrix (Frobenius norm)."""
    u, _, vt = np.linalg.svd(m)
    return u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt


def usual_orientations(motions, frame_step: int = 6, bones=BONES) -> dict:
    """{segment: (mean rotation (3, 3), singular values of the mean matrix (3,))} over every
    frame_step-th frame of the motions, each bone with the pelvis' heading taken out."""
    if not motions:
        raise UsageError("no clips to measure the bones on")
    sums = {name: np.zeros((3, 3)) for name in bones}
    frames = 0
    for m in motions:
        g, _ = sk.forward_kinematics(m.local_rot[::frame_step].astype(np.float64),
                                     m.root_pos[::frame_step].astype(np.float64), m.offsets)
        unturn = np.swapaxes(heading_rotations(g[:, 0]), -1, -2)
        for name, joint in bones.items():
            sums[name] += np.einsum("tab,tbc->ac", unturn, g[:, joint])
        frames += len(g)
    out = {}
    for name, total in sums.items():
        mean = total / frames
        out[name] = (nearest_rotation(mean), np.linalg.svd(mean, compute_uv=False))
    return out


def c_initialiser(rotation: np.ndarray) -> str:
    return "{" + ", ".join(f"{v:.4f}f" for v in rotation.reshape(-1)) + "}"


def add_arguments(p):
    p.add_argument("--split", default="train", choices=["train", "val", "test"],
                   help="clips to measure on (default train: the people the engine's rule is not "
                        "judged on)")
    p.add_argument("--every", type=POSITIVE_INT, default=4, help="every Nth clip of the split (default 4)")
    p.add_argument("--frame-step", type=POSITIVE_INT, default=6,
                   help="every Nth frame of a clip (default 6: 10 per second)")
    return p


def main(args=None) -> int:
    if args is None or isinstance(args, list):
        args = add_arguments(argparse.ArgumentParser(prog="python3 -m training usual-orientation")).parse_args(args)
    from . import dataset
    motions = dataset.load_motions(args.split, progress=False)[::args.every]
    usual = usual_orientations(motions, args.frame_step)
    print(f"usual-orientation: {len(motions)} clips of split {args.split}, every {args.frame_step}th frame")
    for name, (rotation, spread) in usual.items():
        print(f"  {name}: {c_initialiser(rotation)}  (spread {', '.join(f'{v:.3f}' for v in spread)})")
    return 0
