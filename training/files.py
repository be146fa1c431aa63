"""File helpers every command shares: whether two paths name one file, and writes that never
leave a truncated file behind. Imports nothing of the package but its errors."""
from __future__ import annotations

import io
import os
from pathlib import Path

from .errors import CommandError


def same_file(a, b) -> bool:
    """Both paths name one file: the same file where both exist (links, other spellings), else
    the same resolved path (an output not written yet)."""
    a, b = Path(a), Path(b)
    if a.exists() and b.exists():
        return os.path.samefile(a, b)
    return os.path.realpath(a) == os.path.realpath(b)


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


def atomic_torch_save(obj, path) -> None:
    """torch.save through atomic_write_bytes: an interrupted or failed write (disk full, Ctrl-C)
    leaves the previous file, never a truncated one; a failed write is a CommandError naming
    `path`.

    torch.save serialises into memory and Python writes the file: torch's own file writer, on a
    full disk, raises and then aborts the whole process (C++ terminate in its destructor, exit
    134) before any handler runs. A checkpoint is tens of MB, so the copy in memory is cheap."""
    import torch   # here, not at the top: the commands that only compare paths never load torch
    buffer = io.BytesIO()
    torch.save(obj, buffer)
    atomic_write_bytes(buffer.getbuffer(), path, "checkpoint")
