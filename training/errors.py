"""The errors `python3 -m training` prints as one line (`training <command>: <message>`, exit 1)
instead of a traceback.

Only expected failures are these (bad input, a failed check, a missing or unusable file); anything
else is a bug and keeps its traceback. Every module of the package may raise them, so this one
imports nothing of the package.
"""
from __future__ import annotations


class CommandError(Exception):
    """An expected failure of a command (e.g. a failed export check): a message, not a bug."""


class UsageError(CommandError, ValueError):
    """Bad input from the user (a missing file, an empty folder, contradicting options)."""


def one_line(err: BaseException) -> str:
    text = str(err) or type(err).__name__
    return "; ".join(s.strip() for s in text.splitlines() if s.strip())
