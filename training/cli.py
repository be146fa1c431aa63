"""Command-line plumbing shared by the subcommands: the errors `python3 -m training` prints as one
line (`training <command>: <message>`, exit 1) instead of a traceback, and the early checks of the
files and folders a command line names.

Only expected failures are turned into messages (bad input, a failed check, a missing or unusable
file, ONNX Runtime refusing a model); anything else is a bug and keeps its traceback.
"""
from __future__ import annotations

import argparse
import math
import os
from pathlib import Path


class CommandError(Exception):
    """An expected failure of a command (e.g. a failed export check): a message, not a bug."""


class UsageError(CommandError, ValueError):
    """Bad input from the user (a missing file, an empty folder, contradicting options)."""


def one_line(err: BaseException) -> str:
    text = str(err) or type(err).__name__
    return "; ".join(s.strip() for s in text.splitlines() if s.strip())


def same_file(a, b) -> bool:
    """Both paths name one file: the same file where both exist (links, other spellings), else
    the same resolved path (an output not written yet)."""
    a, b = Path(a), Path(b)
    if a.exists() and b.exists():
        return os.path.samefile(a, b)
    return os.path.realpath(a) == os.path.realpath(b)


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


POSITIVE_INT = number_type(int, lambda v: v >= 1, "a positive integer")
NON_NEGATIVE_INT = number_type(int, lambda v: v >= 0, "an integer >= 0")
POSITIVE = number_type(float, lambda v: v > 0, "a positive number")
NON_NEGATIVE = number_type(float, lambda v: v >= 0, "a number >= 0")


def require_file(path, option: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise UsageError(f"{option} {path}: no such file")
    if not p.is_file():
        raise UsageError(f"{option} {path}: not a file")
    return p


def atomic_write_bytes(data, path, what: str) -> None:
    """Write `data` (bytes-like) to a temporary file beside `path`, fsync, then os.replace: an
    interrupted or failed write (disk full, Ctrl-C) leaves the previous file, never a truncated
    one. A failed write is a CommandError naming `path` and `what` it was meant to hold."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())   # a full disk can show only here (delayed allocation)
        os.replace(tmp, path)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        kept = "the previous file is kept" if path.exists() else "nothing written"
        raise CommandError(f"{path}: cannot write the {what} ({e.strerror or e}); {kept}") from e
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


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
    "export": [("checkpoint", "file", "--checkpoint")],
    "average": [("checkpoints", "files", "checkpoint")],
    "synth-capture": [("bvh", "file", "BVH")],
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
