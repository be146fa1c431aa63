"""python3 -m training <command>: the pose model's tooling, from motion data to the shipped ONNX.

Commands: prepare | pack | train | average | export | quantize | evaluate | sensor-gain | chest-follow |
synth-capture | missing-sensor | engine-eval | smoothing-study | cv | stride-scaling | usual-orientation | pose-range |
tip-model.

Each subcommand imports its module lazily, so --help works while a module is missing."""
from __future__ import annotations

import argparse
import importlib
import sys

COMMANDS = {
    "prepare": ("dataset", "extract the CMU archives and convert every clip into the cache"),
    "pack": ("pack_command", "pack retargeted clips into one small file, to train elsewhere"),
    "train": ("train", "train the pose model (checkpoints in training/data/checkpoints)"),
    "average": ("average", "average the weights of checkpoints of one network (model soup)"),
    "export": ("export", "export ONNX fp32 + fp16 per docs/model-contract.md"),
    "quantize": ("quantize", "int8 weights for the fp32 model (mocap_pose_int8.onnx), checked against it"),
    "evaluate": ("evaluate", "metrics of PyTorch / ONNX models on held-out clips"),
    "sensor-gain": ("sensor_gain", "where a seventh sensor would cut the pose error most (an estimate)"),
    "chest-follow": ("chest_follow", "how far the engine turns the spine towards a chest sensor"),
    "synth-capture": ("synth_capture", "BVH clip -> raw HiPNUC capture via mocapctl synth"),
    "missing-sensor": ("dropout_eval", "each sensor silent for 5 s in turn, scored through the engine"),
    "engine-eval": ("engine_eval", "output filter, jitter, latency and drift through the engine's whole path"),
    "smoothing-study": ("smoothing_study", "output smoothing that may wait a frame or two: what it buys"),
    "cv": ("cross_validate", "a training recipe scored by cross-validation over subject folds"),
    "stride-scaling": ("stride_scaling", "how the root speed follows body size: the height input's exponent"),
    "usual-orientation": ("usual_orientation", "the hands' and head's usual orientation, for silent sensors (solver.c)"),
    "pose-range": ("pose_range", "the joints' range of motion and speed, to tell a broken pose from a wrong one"),
    "tip-model": ("tip_model", "TIP-shaped ONNX network, random weights (mocapctl bench tip)"),
}


def _module(name: str):
    try:
        return importlib.import_module(f"training.{name}")
    except ImportError as e:
        return e


def build_parser(argv=None) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python3 -m training", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", metavar="command")
    args = sys.argv[1:] if argv is None else list(argv)
    want = args[0] if args else None
    for cmd, (mod, text) in COMMANDS.items():
        sp = sub.add_parser(cmd, help=text, description=text)
        sp.set_defaults(_module=mod)
        if cmd == want:   # only the requested module is imported (for its options)
            m = _module(mod)
            if not isinstance(m, Exception) and hasattr(m, "add_arguments"):
                m.add_arguments(sp)
    return p


def main(argv=None) -> int:
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    if not getattr(args, "command", None):
        parser.print_help()
        return 0
    m = _module(args._module)
    if isinstance(m, Exception):
        print(f"training {args.command}: module training.{args._module} is not available ({m})",
              file=sys.stderr)
        return 2
    from .cli import check_inputs
    from .errors import one_line
    try:
        check_inputs(args.command, args)
        return int(m.main(args) or 0)
    except _expected_errors() as e:
        # bad input, a damaged or missing file, a failed check: a message, not a traceback
        print(f"training {args.command}: {one_line(e)}", file=sys.stderr)
        return 1


def _expected_errors() -> tuple:
    """The failures main reports as one line: bad user input (errors.UsageError), failed checks
    (errors.CommandError), damaged BVH files, file-system errors and ONNX Runtime refusing a model.
    Everything else is a bug and keeps its traceback."""
    from .bvh import BvhError
    from .errors import CommandError
    errors = [CommandError, BvhError, OSError]
    try:
        from .ort import OnnxRuntimeError
        errors.append(OnnxRuntimeError)
    except ImportError:
        pass
    return tuple(errors)


if __name__ == "__main__":
    sys.exit(main())
