"""A progress bar on stderr for long loops over clips, where tqdm is installed."""
from __future__ import annotations

import sys


def progress_bar(it, total, desc, enabled):
    """`it` wrapped in a tqdm bar counting clips when `enabled` and tqdm is there, else `it`."""
    if not enabled:
        return it
    try:
        from tqdm import tqdm
        return tqdm(it, total=total, desc=desc, unit="clip", file=sys.stderr)
    except ImportError:
        return it
