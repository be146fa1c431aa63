"""sensor-gain: how much of the pose model's error one more sensor could take away, per place.

    python3 -m training sensor-gain [--split val | --bvh DIR] [--checkpoint CKPT] [--out DIR]
        [--max-clips N] [--max-seconds S] [--seed 0] [--noise realistic|none]

Six sensors leave the spine's bend and the upper arms to the network, and that is where most of
its position error is (training/results/evaluation.md, per joint). Before anyone adds a seventh
sensor, this answers "where would it help most, and by how much", without training a model for
each place: the clips are synthesised and predicted exactly as `evaluate` does, then each
candidate bone's global orientation is replaced by the truth while every other bone keeps the
orientation the model gave it, and the errors are measured again.

It is an estimate of one kind of gain, not a promise in either direction: a real sensor has
mounting and noise errors (the model would get the bone to within a few degrees, not exactly),
while a network trained with that sensor would also improve the bones next to it (the rest of
the spine, the collars), which this keeps as they are.

Writes OUT/sensor_gain.md: the position and angle error with each candidate known, overall and
per subject, beside the model as it is; OUT/sensor_gain.png: the position errors as bars.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import skeleton as sk
from .errors import CommandError, UsageError

@dataclass(frozen=True)
class Candidate:
    """A place for one more sensor: the joints whose bone it reports (a sensor on a segment
    reports that segment's global orientation, which is its joint's: the upper arm turns with the
    shoulder joint, the chest with spine3). spread_spine: the bend between the pelvis and a known
    chest is shared evenly by the three spine joints, the simplest guess a network could make
    from the two, instead of left as the model predicted it."""
    bones: tuple
    spread_spine: bool = False


CANDIDATES = {
    "chest": Candidate(("spine3",)),
    "chest, bend shared evenly by the spine": Candidate(("spine3",), spread_spine=True),
    "whole spine (3 bones)": Candidate(("spine1", "spine2", "spine3")),
    "left upper arm": Candidate(("left_shoulder",)),
    "right upper arm": Candidate(("right_shoulder",)),
    "both upper arms (8 sensors)": Candidate(("left_shoulder", "right_shoulder")),
    "chest and both upper arms (9 sensors)": Candidate(("spine3", "left_shoulder", "right_shoulder")),
}
SPINE = [3, 6, 9]


def global_rotations(local_rot) -> np.ndarray:
    """(T,24,3,3) local rotations (joint 0 global) -> global rotations."""
    g, _ = sk.forward_kinematics(local_rot, np.zeros(local_rot.shape[:-3] + (3,)))
    return g


def with_known_bones(pred_local, true_local, joints, known=None, spread_spine=False) -> np.ndarray:
    """The predicted pose with the bones of `joints` turned to their true global orientation (or
    to `known`, (T,len(joints),3,3): what a sensor reports of them) and every other bone kept at
    its predicted global orientation; returned as local rotations. spread_spine: the spine's
    three joints then share the turn from the pelvis to spine3 evenly (Candidate)."""
    joints = list(joints)
    if known is None and joints:
        known = global_rotations(true_local)[:, joints]
    return _with_known_globals(global_rotations(pred_local), joints, known, spread_spine)


def _with_known_globals(g_pred, joints, known, spread_spine) -> np.ndarray:
    """with_known_bones on the predicted global rotations, which a caller trying several
    candidates on one clip computes once."""
    g = g_pred.copy()
    if joints:
        g[:, joints] = known
    if spread_spine:
        bend = sk.rot_to_axis_angle(np.swapaxes(g[:, 0], -1, -2) @ g[:, SPINE[-1]])
        third = sk.axis_angle_to_rot(bend / 3.0)
        g[:, SPINE[0]] = g[:, 0] @ third
        g[:, SPINE[1]] = g[:, SPINE[0]] @ third
    return sk.global_to_local(g)


def pose_errors(local_rot, true_local, offsets, true_positions=None) -> tuple:
    """Per frame: mean local joint angle error (deg) and mean root-aligned position error (cm).
    true_positions: the truth's root-aligned positions, when already at hand."""
    from .evaluate import root_aligned_positions, rotation_angle_deg
    ang = rotation_angle_deg(local_rot, true_local).mean(axis=1)
    _, p = root_aligned_positions(local_rot, offsets)
    t = root_aligned_positions(true_local, offsets)[1] if true_positions is None else true_positions
    return ang, np.linalg.norm(p - t, axis=-1).mean(axis=1) * 100.0


def joint_indices(names) -> list:
    return [sk.JOINT_NAMES.index(n) for n in names]


def measure(clips, preds, candidates=CANDIDATES, augment=None, rng=None) -> dict:
    """label -> {"angle", "pos": frame means, "pos_sensed": pos with the bones as sensors with
    `augment`'s errors report them (None: exact), "subjects": {subject: pos}}; the model as it is
    under "model"."""
    from .evaluate import root_aligned_positions
    from .synthesis import with_orientation_errors
    rng = np.random.default_rng(0) if rng is None else rng
    sums = {label: {"frames": 0, "angle": 0.0, "pos": 0.0, "pos_sensed": 0.0, "subjects": {}}
            for label in ["model", *candidates]}

    def add(label, subject, ang, pos, pos_sensed):
        s = sums[label]
        s["frames"] += len(pos)
        s["angle"] += float(ang.sum())
        s["pos"] += float(pos.sum())
        s["pos_sensed"] += float(pos_sensed.sum())
        n, total = s["subjects"].get(subject, (0, 0.0))
        s["subjects"][subject] = (n + len(pos), total + float(pos.sum()))

    for clip, pred in zip(clips, preds):
        g_true, p_true = root_aligned_positions(clip.local_rot, clip.offsets)
        g_pred = global_rotations(pred.local_rot)

        def errors(local):
            return pose_errors(local, clip.local_rot, clip.offsets, p_true)
        ang, pos = errors(pred.local_rot)
        add("model", clip.subject, ang, pos, pos)
        for label, candidate in candidates.items():
            joints, spread = joint_indices(candidate.bones), candidate.spread_spine
            ang, pos = errors(_with_known_globals(g_pred, joints, g_true[:, joints], spread))
            sensed = g_true[:, joints]
            if augment is not None:
                sensed = with_orientation_errors(sensed, rng, augment)[0]
            _, pos_sensed = errors(_with_known_globals(g_pred, joints, sensed, spread))
            add(label, clip.subject, ang, pos, pos_sensed)
    out = {}
    for label, s in sums.items():
        n = max(s["frames"], 1)
        out[label] = {"angle": s["angle"] / n, "pos": s["pos"] / n, "pos_sensed": s["pos_sensed"] / n,
                      "subjects": {k: v[1] / max(v[0], 1) for k, v in sorted(s["subjects"].items())}}
    return out


def write_report(out_dir, results, meta) -> Path:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    model = results["model"]
    lines = [
        "# Where one more sensor would help: a kinematic estimate",
        "",
        f"{meta['clips']} clips ({meta['source']}, {meta['seconds'] / 60:.1f} min), inputs synthesised "
        f"{meta['noise']} (seed {meta['seed']}), PyTorch checkpoint `{meta['checkpoint']}` (mirror-averaged, "
        "as exported). For each candidate, the bones it names get their true global orientation and every "
        "other bone keeps what the model gave it (`python3 -m training sensor-gain`; the module docstring "
        "says what this estimate leaves out).",
        "",
        "*pos, sensed*: the same with the known bones as a sensor with the evaluation's orientation "
        "errors reports them (mounting, world yaw, noise), the errors the six sensors get here. "
        "Angles are of local rotations: a bone set right below a parent still as predicted gets a "
        "local rotation off by the parent's error, so the angle can rise while positions improve "
        "(a network trained with the sensor would make the two agree).",
        "",
        "| sensor added | bones it reports | angle deg | pos cm | pos gain cm | pos gain % | pos, sensed cm |",
        "|---|---|---|---|---|---|---|",
        f"| none (the model as it is) | - | {model['angle']:.2f} | {model['pos']:.2f} | - | - | - |",
    ]
    for label, candidate in meta["candidates"].items():
        names = candidate.bones
        r = results[label]
        gain = model["pos"] - r["pos"]
        share = f"{100.0 * gain / model['pos']:.0f}" if model["pos"] > 0 else "-"
        lines.append(f"| {label} | {', '.join(names)} | {r['angle']:.2f} | {r['pos']:.2f} | {gain:.2f} | "
                     f"{share} | {r['pos_sensed']:.2f} |")
    subjects = list(model["subjects"])
    if len(subjects) > 1:
        lines += ["", "## Position error by subject (cm)", "",
                  "| sensor added | " + " | ".join(f"subject {s}" if s else "unknown" for s in subjects) + " |",
                  "|---|" + "---|" * len(subjects)]
        for label in ["model"] + list(meta["candidates"]):
            name = "none (the model as it is)" if label == "model" else label
            lines.append(f"| {name} | " + " | ".join(f"{results[label]['subjects'][s]:.2f}" for s in subjects) + " |")
    path = out_dir / "sensor_gain.md"
    path.write_text("\n".join(lines) + "\n")
    return path


def write_plot(out_dir, results, candidates) -> Path:
    """Position error per candidate, exact and as sensed, beside the model and the target."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from .evaluate import TARGETS
    labels = ["none (the model as it is)"] + list(candidates)
    keys = ["model"] + list(candidates)
    y = np.arange(len(labels))[::-1]
    fig, ax = plt.subplots(figsize=(8, 0.45 * len(labels) + 1.5))
    ax.barh(y + 0.2, [results[k]["pos"] for k in keys], 0.4, label="bones exact")
    ax.barh(y - 0.2, [results[k]["pos_sensed"] for k in keys], 0.4, label="bones as a sensor reports them")
    ax.axvline(TARGETS["pos"], color="k", ls="--", lw=1, label=f"target {TARGETS['pos']:g} cm")
    ax.set_yticks(y)
    ax.set_yticklabels(labels, fontsize=8)
    ax.set_xlabel("mean joint position error, roots aligned (cm)")
    ax.set_title("Where one more sensor would help (kinematic estimate)")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=3)   # below: no bar hidden
    fig.tight_layout()
    path = Path(out_dir) / "sensor_gain.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def sensor_gain(motions, checkpoint, out_dir, seed=0, source="", noise="realistic",
                candidates=CANDIDATES) -> dict:
    from . import evaluate as ev
    if not motions:
        raise UsageError("no motions to measure")
    for m in motions:
        if m.num_frames == 0:
            raise UsageError(f"motion {m.name}: no frames to measure")
    net = ev.load_torch_model(checkpoint, mirror=True)
    wrist = ev.expected_wrist_sensor(checkpoint)
    rng = np.random.default_rng(seed)
    clips = [ev.synthesize_clip(m, rng, wrist, noise, net.config.sensors) for m in motions]
    preds = ev.predict_torch(net, clips)
    results = measure(clips, preds, candidates, ev.eval_augmentation(noise), np.random.default_rng(seed + 1))
    meta = {"clips": len(clips), "source": source, "seed": seed, "candidates": dict(candidates),
            "seconds": sum(c.local_rot.shape[0] / c.fps for c in clips),
            "noise": ev._NOISE_WORDS[noise], "checkpoint": ev._shown_path(checkpoint)}
    report = write_report(out_dir, results, meta)
    return {"results": results, "report": report, "plot": write_plot(out_dir, results, candidates)}


def add_arguments(p):
    from .cli import NON_NEGATIVE_INT, POSITIVE_INT
    from .evaluate import _POSITIVE_SECONDS, NOISE_CHOICES, RESULTS_DIR
    src = p.add_mutually_exclusive_group()
    src.add_argument("--split", default="val", choices=["train", "val", "test"],
                     help="train / val / test of the CMU data (default val)")
    src.add_argument("--bvh", help="a folder of BVH files instead (any depth), or a motion pack")
    p.add_argument("--checkpoint", default=None,
                   help="PyTorch checkpoint (default: as evaluate, the shipped weights without a local run)")
    p.add_argument("--out", default=str(RESULTS_DIR), help="where sensor_gain.md goes")
    p.add_argument("--max-clips", type=POSITIVE_INT, default=0, help="the first N clips")
    p.add_argument("--max-seconds", type=_POSITIVE_SECONDS, default=0.0, help="cut clips to this length")
    p.add_argument("--seed", type=NON_NEGATIVE_INT, default=0)
    p.add_argument("--noise", default="realistic", choices=NOISE_CHOICES,
                   help="sensor errors of the synthesised inputs (default realistic)")
    p.add_argument("--no-cache", action="store_true", help="do not cache converted BVH clips")
    return p


def main(args=None) -> int:
    if args is None or isinstance(args, list):
        args = add_arguments(argparse.ArgumentParser(prog="python3 -m training sensor-gain")).parse_args(args)
    from . import dataset
    from . import evaluate as ev
    ckpt = args.checkpoint or ev.find_checkpoint()
    if ckpt is None:
        raise CommandError("no checkpoint found; pass --checkpoint")
    source = f"BVH folder {args.bvh}" if args.bvh else f"split {args.split}"
    motions = dataset.load_motions(Path(args.bvh) if args.bvh else args.split, cache=not args.no_cache)
    motions = ev._trim(motions, args.max_clips, args.max_seconds)
    print(f"sensor-gain: {len(motions)} clips ({source}); PyTorch {ev._shown_path(ckpt)}")
    r = sensor_gain(motions, ckpt, args.out, args.seed, source, args.noise)
    model = r["results"]["model"]
    print(f"{'none (the model as it is)':40s} angle {model['angle']:6.2f} deg  pos {model['pos']:6.2f} cm")
    for label in CANDIDATES:
        s = r["results"][label]
        print(f"{label:40s} angle {s['angle']:6.2f} deg  pos {s['pos']:6.2f} cm  "
              f"(-{model['pos'] - s['pos']:.2f} cm; sensed {s['pos_sensed']:6.2f} cm)")
    print(f"sensor-gain: wrote {r['report']} and {r['plot'].name}")
    return 0
