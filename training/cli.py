"""Command-line plumbing shared by the subcommands: the errors `python3 -m training` prints as one
line (`training <command>: <message>`, exit 1) instead of a traceback, and the early checks of the
files and folders a command line names.

Only expected failures are turned into messages (bad input, a failed check, a missing or unusable
file, ONNX Runtime refusing a model); anything else is a bug and keeps its traceback.
"""
from __future__ import annotations

from pathlib import Path


class CommandError(Exception):
    """An expected failure of a command (e.g. a failed export check): a message, not a bug."""


class UsageError(CommandError, ValueError):
    """Bad input from the user (a missing file, an empty folder, contradicting options)."""


def one_line(err: BaseException) -> str:
    text = str(err) or type(err).__name__
    return "; ".join(s.strip() for s in text.splitlines() if s.strip())


def require_file(path, option: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise UsageError(f"{option} {path}: no such file")
    if not p.is_file():
        raise UsageError(f"{option} {path}: not a file")
    return p


def require_bvh_folder(path, option: str) -> Path:
    """A folder that exists and holds usable BVH clips (dataset.list_clips: its manifest's ok rows,
    else every *.bvh below it)."""
    p = Path(path)
    if not p.exists():
        raise UsageError(f"{option} {path}: no such folder")
    if not p.is_dir():
        raise UsageError(f"{option} {path}: not a folder")
    from .dataset import list_clips
    if not list_clips(p):
        raise UsageError(f"{option} {path}: no BVH clips in this folder (*.bvh at any depth, or the "
                         f"ok rows of its manifest.csv)")
    return p


# What each command's options name: (attribute, kind, option as typed). Checked before the command
# runs, so a typo fails in a second instead of after minutes of loading data.
INPUTS = {
    "prepare": [("bvh", "bvh_folder", "--bvh")],
    "train": [("bvh", "bvh_folder", "--bvh"), ("val_bvh", "bvh_folder", "--val-bvh"),
              ("init_from", "file", "--init-from")],
    "evaluate": [("bvh", "bvh_folder", "--bvh"), ("checkpoint", "file", "--checkpoint"),
                 ("models", "files", "--models")],
    "export": [("checkpoint", "file", "--checkpoint")],
    "average": [("checkpoints", "files", "checkpoint")],
    "synth-capture": [("bvh", "file", "BVH")],
}


def check_inputs(command: str, args) -> None:
    for attr, kind, option in INPUTS.get(command, ()):
        value = getattr(args, attr, None)
        if not value:
            continue
        if kind == "bvh_folder":
            require_bvh_folder(value, option)
        elif kind == "file":
            require_file(value, option)
        else:
            for v in value:
                require_file(v, option)
