"""stride-scaling: how a model's root speed follows the performer's size, for the engine's height input.

    python3 -m training stride-scaling --model M.onnx [--split train] [--every 4]
        [--scales 0.86,0.93,1.07,1.14] [--out DIR] [--write M.onnx ...]

Every CMU clip is on one body (about 1.72 m), and a network reads a performer's size only partly
from the accelerations: on a body S times that size its root velocity comes out too slow (S > 1)
or too fast (S < 1), and the 10 s drift grows (training/results/body-scale.md). When the engine
knows the performer's height it can correct that with a gain S^e on the velocity (in the
skeleton's own size, S^(e - 1): mocap_solver_set_character_height). The exponent e is a property
of each network, so it is measured here, on clips of the split given (the training people by
default: the choice is not made on the people it is judged on):

1. each clip is synthesised on bodies S times the size (evaluate --body-scale: the same motion,
   the same noise draws) and run through the model;
2. for each S, the gain that minimises the mean 10 s drift is found on a grid (reported);
3. e is the exponent whose gains S^e give the least mean 10 s drift over all the sizes at once.

--write stores mocap.training_height (the standing height of the clips' body, metres) and
mocap.stride_exponent (e) in the model files named, leaving everything else in them as it was:
the model measured and the files that share its weights (its fp16 and int8 forms).

Writes OUT/stride_scaling.md with the table and the fit.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from . import onnx_metadata, skeleton as sk
from .cli import POSITIVE_INT
from .errors import CommandError, UsageError

DRIFT_WINDOW_S = 10.0
GAIN_GRID = np.round(np.arange(0.70, 1.4001, 0.005), 3)
EXPONENT_GRID = np.round(np.arange(0.0, 1.5001, 0.01), 2)
DEFAULT_SCALES = (0.86, 0.93, 1.07, 1.14)   # about 1.5 to 2.0 m
HEIGHT_KEY = "mocap.training_height"
EXPONENT_KEY = "mocap.stride_exponent"
# Written into a model after export, once measured: not part of what export writes.
MEASURED_KEYS = (HEIGHT_KEY, EXPONENT_KEY)


def training_height(motions) -> float:
    """Standing height of the clips' body (metres): the default skeleton's height times the mean
    ratio of the clips' leg length to the default one (retargeting scales the skeleton uniformly)."""
    if not motions:
        raise UsageError("no clips to measure the body of")
    ratios = [sk.leg_height(m.offsets) / sk.leg_height(sk.DEFAULT_OFFSETS) for m in motions]
    return float(sk.STANDING_HEIGHT * np.mean(ratios))


def window_drift(velocities, roots, fps_list, gain: float) -> float:
    """Mean drift of every DRIFT_WINDOW_S window of every clip with the velocities times gain."""
    from .evaluate import drift_errors
    errors = [drift_errors(gain * v, r, fps, DRIFT_WINDOW_S)
              for v, r, fps in zip(velocities, roots, fps_list)]
    errors = np.concatenate(errors) if errors else np.zeros(0)
    if errors.size == 0:
        raise UsageError(f"no clip is longer than {DRIFT_WINDOW_S:g} s: nothing to measure drift on")
    return float(errors.mean())


def fit(per_scale: dict) -> dict:
    """per_scale: S -> (velocities, roots, fps list). Best gain per size and the shared exponent."""
    rows = {}
    for s, data in sorted(per_scale.items()):
        curve = np.array([window_drift(*data, gain=g) for g in GAIN_GRID])
        best = int(np.argmin(curve))
        rows[s] = {"drift_gain_1": window_drift(*data, gain=1.0), "best_gain": float(GAIN_GRID[best]),
                   "drift_best": float(curve[best])}
    def total(e):
        return sum(window_drift(*data, gain=float(s) ** e) for s, data in per_scale.items())
    totals = np.array([total(e) for e in EXPONENT_GRID])
    exponent = float(EXPONENT_GRID[int(np.argmin(totals))])
    for s, data in per_scale.items():
        rows[s]["drift_fitted"] = window_drift(*data, gain=float(s) ** exponent)
    return {"rows": rows, "exponent": exponent}


def wrist_sensor_bone(model) -> str:
    """Where the model expects the wrist sensors (mocap.wrist_sensor_bone; absent: the hand)."""
    import onnx
    meta = onnx_metadata.read(onnx.load(str(model), load_external_data=False))
    return meta.get("mocap.wrist_sensor_bone") or "hand"


def measure(motions, model, scales, seed=0, progress=print) -> dict:
    from .evaluate import expected_sensors, predict_onnx, synthesize_clip
    sensors = expected_sensors(None, [model])
    wrist = wrist_sensor_bone(model)
    per_scale = {}
    for s in sorted(set(scales) | {1.0}):
        rng = np.random.default_rng(seed)   # the same noise draws on every body
        clips = [synthesize_clip(m, rng, wrist, "realistic", sensors, body_scale=s) for m in motions]
        preds = predict_onnx(model, clips)
        per_scale[s] = ([p.root_velocity for p in preds], [c.root_pos for c in clips],
                        [c.fps for c in clips])
        progress(f"stride-scaling: body x{s:g}: {len(clips)} clips predicted")
    return fit(per_scale)


def write_metadata(path, height: float, exponent: float) -> None:
    """Sets the two keys in an ONNX file, leaving the graph and every other key as they were."""
    import onnx
    model = onnx.load(str(path))
    if "mocap.contract_version" not in onnx_metadata.read(model):
        raise CommandError(f"{path}: not a mocap pose model (no mocap.contract_version)")
    onnx_metadata.update(model, {HEIGHT_KEY: f"{height:.3f}", EXPONENT_KEY: f"{exponent:.2f}"})
    tmp = Path(str(path) + ".tmp")
    onnx.save(model, str(tmp))
    tmp.replace(path)


def write_report(out_dir, result, meta) -> Path:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    e, h = result["exponent"], meta["training_height"]
    lines = [f"# Stride scaling of {meta['model']}", "",
             f"{meta['clips']} clips of {meta['source']}, realistic sensor noise, each on bodies S times the "
             f"clips' size ({h:.3f} m standing). Drift: mean over every {DRIFT_WINDOW_S:g} s window "
             "(starting every second) of |integrated predicted displacement - true displacement|, "
             "on the scaled body. Made by:", "", f"    {meta['command']}", "",
             "| S | height (m) | drift, gain 1 (m) | best gain | drift at best (m) | "
             f"gain S^{e:.2f} | drift at S^{e:.2f} (m) |",
             "|---|---|---|---|---|---|---|"]
    for s, r in sorted(result["rows"].items()):
        lines.append(f"| {s:g} | {s * h:.2f} | {r['drift_gain_1']:.3f} | {r['best_gain']:.3f} | "
                     f"{r['drift_best']:.3f} | {s ** e:.3f} | {r['drift_fitted']:.3f} |")
    lines += ["", f"Fitted exponent e = {e:.2f} (the one gain law S^e with the least drift summed over "
              "the sizes). The engine applies S^(e - 1) to the root velocity of its own skeleton "
              "(`mocap_solver_set_character_height`), the same correction in the skeleton's size.", ""]
    path = out_dir / "stride_scaling.md"
    path.write_text("\n".join(lines))
    return path


def _scales(text: str) -> tuple:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': expected numbers separated by commas") from None
    from .evaluate import BODY_SCALE_RANGE
    lo, hi = BODY_SCALE_RANGE
    if not values or any(not lo <= v <= hi for v in values) or all(v == 1.0 for v in values):
        raise argparse.ArgumentTypeError(f"'{text}': expected scales from {lo:g} to {hi:g}, at "
                                         "least one other than 1")
    return values


def add_arguments(p):
    p.add_argument("--model", required=True, help="the ONNX pose model to measure")
    p.add_argument("--split", default="train", choices=["train", "val", "test"],
                   help="clips to measure on (default train: the people the model was fitted to)")
    p.add_argument("--every", type=POSITIVE_INT, default=4, help="every Nth clip of the split (default 4)")
    p.add_argument("--max-clips", type=POSITIVE_INT, default=None, help="at most this many clips")
    p.add_argument("--scales", type=_scales, default=DEFAULT_SCALES,
                   help="body sizes besides 1, comma-separated (default 0.86,0.93,1.07,1.14)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="training/results/stride-scaling", help="report folder")
    p.add_argument("--write", nargs="*", default=None, metavar="M.onnx",
                   help="store the fitted mocap.training_height and mocap.stride_exponent in these "
                        "model files (the measured one and those sharing its weights)")
    return p


def main(args=None) -> int:
    if args is None or isinstance(args, list):
        args = add_arguments(argparse.ArgumentParser(prog="python3 -m training stride-scaling")).parse_args(args)
    from . import dataset
    motions = dataset.load_motions(args.split)[::args.every]
    if args.max_clips:
        motions = motions[:args.max_clips]
    height = training_height(motions)
    print(f"stride-scaling: {len(motions)} clips of split {args.split}, body {height:.3f} m; "
          f"sizes {', '.join(f'{s:g}' for s in args.scales)}")
    result = measure(motions, args.model, args.scales, args.seed)
    command = (f"python3 -m training stride-scaling --model {args.model} --split {args.split} "
               f"--every {args.every}" + (f" --max-clips {args.max_clips}" if args.max_clips else "")
               + f" --scales {','.join(f'{s:g}' for s in args.scales)} --seed {args.seed}")
    report = write_report(args.out, result, {"model": Path(args.model).name, "clips": len(motions),
                                             "source": f"split {args.split} (every {args.every})",
                                             "training_height": height, "command": command})
    for s, r in sorted(result["rows"].items()):
        print(f"  S {s:4.2f}: drift 10 s {r['drift_gain_1']:.3f} m at gain 1, best gain "
              f"{r['best_gain']:.3f} ({r['drift_best']:.3f} m), S^e {r['drift_fitted']:.3f} m")
    print(f"stride-scaling: exponent {result['exponent']:.2f}; report {report}")
    for path in args.write or ():
        write_metadata(path, height, result["exponent"])
        print(f"stride-scaling: {HEIGHT_KEY}={height:.3f} {EXPONENT_KEY}={result['exponent']:.2f} -> {path}")
    return 0
