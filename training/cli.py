"""Command-line plumbing shared by the subcommands: argparse types for numbers and the early
checks of the files and folders a command line names (a UsageError, errors.py, before the command
runs)."""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from .errors import UsageError


def number_type(convert, accepts, expected: str):
    """An argparse type: the value converted, or ArgumentTypeError (exit 2 with the usage) when it
    does not parse or is out of range; NaN and inf are never accepted."""
    def parse(text):
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {expected}") from None
        if (isinstance(value, float) and not math.isfinite(value)) or not accepts(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not {expected}")
        return value
    return parse


def number_pair_type(accepts, unreadable: str, out_of_range: str):
    """An argparse type for "A,B": a tuple of two finite floats that `accepts(a, b)`, else
    ArgumentTypeError with `unreadable` (not two numbers) or `out_of_range`, each a format string
    whose {text} is the quoted argument."""
    def parse(text):
        try:
            a, b = (float(x) for x in text.split(","))
        except ValueError:
            raise argparse.ArgumentTypeError(unreadable.format(text=repr(text))) from None
        if not (math.isfinite(a) and math.isfinite(b) and accepts(a, b)):
            raise argparse.ArgumentTypeError(out_of_range.format(text=repr(text)))
        return (a, b)
    return parse


POSITIVE_INT = number_type(int, lambda v: v >= 1, "a positive integer")
NON_NEGATIVE_INT = number_type(int, lambda v: v >= 0, "an integer >= 0")
POSITIVE = number_type(float, lambda v: v > 0, "a positive number")
NON_NEGATIVE = number_type(float, lambda v: v >= 0, "a number >= 0")


def sensor_option(text, option: str, among=None, of: str = "") -> tuple:
    """A comma-separated list of segment names given to `option` (sensors.sensor_list), each
    one of `among` when that is given (`of` names what `among` is, for the message)."""
    from .sensors import sensor_list
    try:
        names = tuple(sensor_list(text))
    except ValueError as e:
        raise UsageError(f"{option}: {e}") from e
    if among is not None:
        unknown = [n for n in names if n not in among]
        if unknown:
            raise UsageError(f"{option}: {', '.join(unknown)} is not a sensor of {of} "
                             f"({', '.join(among)})")
    return names


def require_file(path, option: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise UsageError(f"{option} {path}: no such file")
    if not p.is_file():
        raise UsageError(f"{option} {path}: not a file")
    return p


def require_bvh_folder(path, option: str, pack_ok: bool = False) -> Path:
    """A folder that exists and holds usable BVH clips (dataset.list_clips: its manifest's ok rows,
    else every *.bvh below it), or with pack_ok a motion pack file (motion_pack.py)."""
    p = Path(path)
    if not p.exists():
        raise UsageError(f"{option} {path}: no such {'folder or pack' if pack_ok else 'folder'}")
    if not p.is_dir():
        from .motion_pack import is_pack
        if pack_ok and is_pack(p):
            return p
        raise UsageError(f"{option} {path}: not a folder" + (" or a motion pack" if pack_ok else ""))
    from .dataset import list_clips
    if not list_clips(p):
        raise UsageError(f"{option} {path}: no BVH clips in this folder (*.bvh at any depth, or the "
                         f"ok rows of its manifest.csv)")
    return p


# What each command's options name: (attribute, kind, option as typed). Checked before the command
# runs, so a typo fails in a second instead of after minutes of loading data.
INPUTS = {
    "prepare": [("bvh", "bvh_folder", "--bvh")],
    "pack": [("bvh", "bvh_folder", "--bvh")],
    "train": [("bvh", "bvh_or_pack", "--bvh"), ("val_bvh", "bvh_or_pack", "--val-bvh"),
              ("init_from", "file", "--init-from")],
    "evaluate": [("bvh", "bvh_or_pack", "--bvh"), ("checkpoint", "file", "--checkpoint"),
                 ("models", "files", "--models")],
    "sensor-gain": [("bvh", "bvh_or_pack", "--bvh"), ("checkpoint", "file", "--checkpoint")],
    "chest-follow": [("checkpoint", "file", "--checkpoint")],
    "export": [("checkpoint", "file", "--checkpoint")],
    "quantize": [("model", "file", "--model")],
    "average": [("checkpoints", "files", "checkpoint")],
    "synth-capture": [("bvh", "file", "BVH")],
    "missing-sensor": [("bvh", "bvh_or_pack", "--bvh"), ("model", "file", "--model")],
    "stride-scaling": [("model", "file", "--model"), ("write", "files", "--write")],
}


def check_inputs(command: str, args) -> None:
    for attr, kind, option in INPUTS.get(command, ()):
        value = getattr(args, attr, None)
        if not value:
            continue
        if kind in ("bvh_folder", "bvh_or_pack"):
            require_bvh_folder(value, option, pack_ok=kind == "bvh_or_pack")
        elif kind == "file":
            require_file(value, option)
        else:
            for v in value:
                require_file(v, option)
