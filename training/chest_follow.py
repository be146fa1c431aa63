"""chest-follow: how far to turn the seven-sensor model's spine towards its chest sensor.

    python3 -m training chest-follow [--split train] [--every 24] [--max-seconds 60]
        [--checkpoint CKPT] [--shares 0.25,0.5,0.75,1] [--seed 0]

The seven-sensor network leaves its chest bone (spine3) several degrees from the chest it was
fed, further than its other sensors' bones from theirs. This synthesises the clips as `evaluate`
does, predicts them with the checkpoint, and scores each way of turning the chest towards the
chest input (`VARIANTS`) at each share, on the split named: the engine's rule
(`mocap_solver_set_chest_follow`, `Native~/src/pose/chest_follow.c`) was chosen this way on the
training people. `follow_chest` is that rule in numpy.
"""
from __future__ import annotations

import argparse

import numpy as np

from . import skeleton as sk
from .errors import CommandError, UsageError

SPINE = (3, 6, 9)
NECK, HEAD = 12, 15
COLLARS, UPPER_ARMS = (13, 14), (16, 17)

# How the body above the spine answers a turned chest: "spine3 only" turns the chest bone alone,
# everything else keeping its global orientation; the others spread the turn over the spine
# (ENGINE_SPREAD) and keep the global orientation of the joints named (their
# descendants follow them), every other joint's local rotation being kept.
VARIANTS = {
    "spine3 only": None,
    "spread, the body above keeps its orientation": tuple(range(10, 24)),
    "spread, the body above turns with the chest": (),
    "spread, head and upper arms keep theirs (the engine's)": (HEAD,) + UPPER_ARMS,
}
ENGINE_VARIANT = "spread, head and upper arms keep theirs (the engine's)"

# How far along the turn spine1 and spine2 go (spine3 goes all of it): cumulative shares, so
# spine1 bends by the first, spine2 by the second less the first, spine3 by the rest. "even"
# bends each joint a third; "as people bend" follows the training motion, whose spine3 never
# bends from spine2 (the CMU skeleton has two back joints where SMPL has three) and whose spine1
# bends about twice as far as spine2 (95th percentile 38 against 18 deg from rest).
SPREADS = {
    "even": (1.0 / 3.0, 2.0 / 3.0),
    "half each of spine1 and spine2": (0.5, 1.0),
    "as people bend (2:1, spine3 none)": (2.0 / 3.0, 1.0),
    "spine1 alone": (1.0, 1.0),
}
ENGINE_SPREAD = SPREADS["as people bend (2:1, spine3 none)"]   # CHEST_FOLLOW_SPINE1/2_PART


def _power(rot, t):
    return sk.axis_angle_to_rot(sk.rot_to_axis_angle(rot) * t)


def _globals(local):
    g, _ = sk.forward_kinematics(local, np.zeros(local.shape[:-3] + (3,)))
    return g


def follow_chest(local_rot, chest, share, keep=(HEAD,) + UPPER_ARMS, spread=ENGINE_SPREAD) -> np.ndarray:
    """local_rot (T,24,3,3) (joint 0 global) with spine3 turned `share` of the way to `chest`
    (T,3,3), the turn spread over the spine by `spread` (SPREADS); the joints in `keep` keep their
    global orientation (None: spine3 alone turns, every other joint keeping its global one).
    Returns local rotations."""
    if not 0.0 <= share <= 1.0:
        raise UsageError(f"share {share:g}: expected 0 to 1")
    if not 0.0 <= spread[0] <= spread[1] <= 1.0:
        raise UsageError(f"spread {spread}: expected 0 <= spine1 <= spine2 <= 1")
    g = _globals(local_rot)
    turn = _power(chest @ np.swapaxes(g[:, 9], -1, -2), share)
    if keep is None:
        h = g.copy()
        h[:, 9] = turn @ g[:, 9]
        return sk.global_to_local(h)
    out = local_rot.copy()
    turned = {3: _power(turn, spread[0]) @ g[:, 3], 6: _power(turn, spread[1]) @ g[:, 6], 9: turn @ g[:, 9]}
    parent_global = {3: g[:, 0], 6: turned[3], 9: turned[6]}
    for j in SPINE:
        out[:, j] = np.swapaxes(parent_global[j], -1, -2) @ turned[j]
    for j in sorted(keep):
        parent = _globals(out)[:, sk.PARENTS[j]]
        out[:, j] = np.swapaxes(parent, -1, -2) @ g[:, j]
    return out


def study(motions, checkpoint, shares, seed=0) -> dict:
    """(variant, share) -> (angle deg, position cm) frame means, each variant with ENGINE_SPREAD;
    (ENGINE_VARIANT, share, spread name) the engine's variant with each of SPREADS; ("model", 0)
    the network's own; "gap" -> the chest bone's mean angle (deg) from the chest input."""
    from . import evaluate as ev
    from .sensor_gain import pose_errors
    net = ev.load_torch_model(checkpoint, mirror=True)
    sensors = list(net.config.sensors)
    if "chest" not in sensors:
        raise UsageError(f"{ev._shown_path(checkpoint)} reads no chest sensor ({', '.join(sensors)})")
    rng = np.random.default_rng(seed)
    clips = [ev.synthesize_clip(m, rng, net.config.wrist_anchor, "realistic", net.config.sensors)
             for m in motions]
    preds = ev.predict_torch(net, clips)
    k = sensors.index("chest")
    sums, gaps = {}, []

    def add(key, local, clip, p_true):
        ang, pos = pose_errors(local, clip.local_rot, clip.offsets, p_true)
        s = sums.setdefault(key, [0, 0.0, 0.0])
        s[0] += len(pos)
        s[1] += float(ang.sum())
        s[2] += float(pos.sum())

    for clip, pred in zip(clips, preds):
        _, p_true = ev.root_aligned_positions(clip.local_rot, clip.offsets)
        chest = clip.imu_orientation[:, k].astype(np.float64)
        g9 = _globals(pred.local_rot)[:, 9]
        gaps.append(ev.rotation_angle_deg(g9, chest))
        add(("model", 0.0), pred.local_rot, clip, p_true)
        for share in shares:
            for name, keep in VARIANTS.items():
                if name != ENGINE_VARIANT:
                    add((name, share), follow_chest(pred.local_rot, chest, share, keep), clip, p_true)
            for spread_name, spread in SPREADS.items():
                local = follow_chest(pred.local_rot, chest, share, VARIANTS[ENGINE_VARIANT], spread)
                add((ENGINE_VARIANT, share, spread_name), local, clip, p_true)
                if spread == ENGINE_SPREAD:   # the engine's variant as the engine runs it
                    add((ENGINE_VARIANT, share), local, clip, p_true)
    out = {key: (a / n, p / n) for key, (n, a, p) in sums.items()}
    out["gap"] = float(np.concatenate(gaps).mean())
    return out


def _shares(text):
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected shares like 0.25,0.5")
    if not values or not all(0.0 < v <= 1.0 for v in values):
        raise argparse.ArgumentTypeError(f"{text!r}: every share must be above 0 and at most 1")
    return values


def add_arguments(p):
    from .cli import NON_NEGATIVE_INT, POSITIVE_INT
    from .evaluate import _POSITIVE_SECONDS
    p.add_argument("--split", default="train", choices=["train", "val", "test"],
                   help="the CMU split (default train: where the rule is chosen)")
    p.add_argument("--every", type=POSITIVE_INT, default=24, help="every Nth clip (default 24)")
    p.add_argument("--max-seconds", type=_POSITIVE_SECONDS, default=60.0, help="cut clips to this length")
    p.add_argument("--checkpoint", default="training/checkpoints/mocap_pose_chest.pt",
                   help="a seven-sensor PyTorch checkpoint (default the shipped chest model's)")
    p.add_argument("--shares", type=_shares, default=[0.25, 0.5, 0.75, 1.0])
    p.add_argument("--seed", type=NON_NEGATIVE_INT, default=0)
    return p


def main(args=None) -> int:
    if args is None or isinstance(args, list):
        args = add_arguments(argparse.ArgumentParser(prog="python3 -m training chest-follow")).parse_args(args)
    from pathlib import Path
    from . import dataset
    from . import evaluate as ev
    if not Path(args.checkpoint).is_file():
        raise CommandError(f"no checkpoint {args.checkpoint}")
    motions = ev._trim(dataset.load_motions(args.split, every=args.every), 0, args.max_seconds)
    print(f"chest-follow: {len(motions)} clips (split {args.split}, every {args.every}); "
          f"PyTorch {ev._shown_path(args.checkpoint)}")
    r = study(motions, args.checkpoint, args.shares, args.seed)
    print(f"the chest bone's mean angle from the chest input: {r['gap']:.2f} deg")
    angle, pos = r[("model", 0.0)]
    print(f"{'the model as it is':58s}        angle {angle:6.3f} deg  pos {pos:6.3f} cm")
    for name in VARIANTS:
        for share in args.shares:
            angle, pos = r[(name, share)]
            print(f"{name:58s} {share:5.2f}  angle {angle:6.3f} deg  pos {pos:6.3f} cm")
    print("the engine's variant, by how the turn is spread over the spine:")
    for spread_name in SPREADS:
        for share in args.shares:
            angle, pos = r[(ENGINE_VARIANT, share, spread_name)]
            print(f"  {spread_name:56s} {share:5.2f}  angle {angle:6.3f} deg  pos {pos:6.3f} cm")
    return 0
