"""Motion packs: a split of retargeted clips in one small file, to train where the motion data is not.

    python3 -m training pack --split train --out train.mpack      # from the extracted CMU data
    python3 -m training pack --bvh DIR --out mine.mpack           # any BVH folder
    python3 -m training train --bvh train.mpack --val-bvh val.mpack

A training machine (a rented GPU, say) needs the motions, not the 100 MB of BVH archives behind
them: CMU's training and validation subjects pack into about 28 MB. A pack holds each clip on our
skeleton at its source frame rate, as `retarget.retarget_frames` gives it; loading resamples to
the model rate exactly as `prepare` does, so a packed clip differs from the prepared one only by
the quantisation below.

Quantisation: quaternion components in steps of 1/2048 (a rotation error of at most ~0.05 deg,
far below sensor noise), root positions in steps of 0.1 mm. Each series (one quaternion component
of one joint, one root coordinate) is stored as its second differences over time, zigzag-coded,
split into byte planes and compressed with xz: smooth motion leaves small numbers that compress
well.

File: MAGIC, a little-endian u32 header length, a JSON header (format, scales, clip names,
subjects, source frame counts and frame times, skeleton offsets), then one xz stream with the
rotation planes and the root planes.
"""
from __future__ import annotations

import json
import lzma
import os
import struct
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from . import skeleton as sk
from .errors import CommandError, UsageError
from .files import atomic_write_bytes
from .progress import progress_bar

MAGIC = b"MOCAPPK1"
FORMAT = 1
ROT_SCALE = 2048.0      # quaternion component steps
POS_SCALE = 10000.0     # root position steps per metre (0.1 mm)
_XZ = lzma.PRESET_EXTREME | 9


def is_pack(path) -> bool:
    """Whether path is a file that starts like a motion pack."""
    p = Path(path)
    if not p.is_file():
        return False
    with open(p, "rb") as f:
        return f.read(len(MAGIC)) == MAGIC


def _continuous(q: np.ndarray) -> np.ndarray:
    """Quaternions (F,J,4) with signs chosen so that neighbouring frames agree (q and -q are the
    same rotation; a sign flip would be a large jump to store)."""
    dots = np.sum(q[1:] * q[:-1], axis=-1)
    flips = np.concatenate([np.ones((1,) + q.shape[1:2]), np.cumprod(np.where(dots < 0, -1.0, 1.0), axis=0)])
    return q * flips[..., None]


def _second_differences(x: np.ndarray) -> np.ndarray:
    """Integer series (F,...) -> first value, first difference, then second differences."""
    d = np.diff(x, axis=0, prepend=np.zeros_like(x[:1]))
    return np.diff(d, axis=0, prepend=np.zeros_like(d[:1]))


def _undo_second_differences(d: np.ndarray) -> np.ndarray:
    return np.cumsum(np.cumsum(d, axis=0), axis=0)


def _zigzag(x: np.ndarray, bits: int) -> np.ndarray:
    return (x << 1) ^ (x >> (bits - 1))


def _unzigzag(z: np.ndarray) -> np.ndarray:
    return (z >> 1) ^ -(z & 1)


def _planes(values: np.ndarray, dtype) -> bytes:
    """Unsigned integers -> their bytes, most-significant-first planes after each other."""
    b = np.ascontiguousarray(values.astype(dtype)).view(np.uint8).reshape(-1, np.dtype(dtype).itemsize)
    return b.T.tobytes()


def _from_planes(buf: bytes, count: int, dtype) -> np.ndarray:
    size = np.dtype(dtype).itemsize
    b = np.frombuffer(buf, np.uint8).reshape(size, count)
    return np.ascontiguousarray(b.T).view(dtype).reshape(count)


def _encode_clip(local_rot: np.ndarray, root_pos: np.ndarray) -> tuple:
    q = _continuous(sk.quat_from_rot(local_rot))
    qi = np.round(q * ROT_SCALE).astype(np.int64)
    ri = np.round(np.asarray(root_pos, np.float64) * POS_SCALE).astype(np.int64)
    if np.abs(ri).max(initial=0) > 2 ** 29:
        raise UsageError(f"a root position beyond {2 ** 29 / POS_SCALE:g} m cannot be packed")
    # series-major: each joint component's whole clip is one run of small numbers
    rot = _zigzag(_second_differences(qi).transpose(1, 2, 0).reshape(-1), 32)
    root = _zigzag(_second_differences(ri).T.reshape(-1), 64)
    return rot, root


def _decode_clip(rot: np.ndarray, root: np.ndarray, frames: int) -> tuple:
    J = sk.NUM_JOINTS
    q = _undo_second_differences(_unzigzag(rot).reshape(J, 4, frames).transpose(2, 0, 1)) / ROT_SCALE
    r = _undo_second_differences(_unzigzag(root).reshape(3, frames).T) / POS_SCALE
    if not (np.linalg.norm(q, axis=-1) > 0.5).all():
        raise CommandError("a packed clip decodes to non-rotations (the pack is damaged)")
    return sk.rot_from_quat(q), r


def _retarget(item):
    """Worker: one BVH clip -> (clip, subject, frame time, offsets, encoded rotations, root)."""
    clip, subject, path, elbow = item
    from .bvh import read_bvh
    from .retarget import retarget_frames
    c = read_bvh(path)
    local, root, offsets = retarget_frames(c, elbow)
    rot, rootc = _encode_clip(local, root)
    return clip, int(subject), float(c.frame_time), offsets.astype(np.float32), int(local.shape[0]), rot, rootc


def write_pack(clips, out, workers=None, progress: bool = True) -> dict:
    """Pack (clip, subject, path, elbow_reversed) rows (dataset.list_clips) into `out`; returns a
    summary. Written through a temporary file: a failed write leaves no partial pack."""
    if not clips:
        raise UsageError("no clips to pack")
    workers = max(1, min(workers or os.cpu_count() or 1, len(clips)))
    if workers == 1:
        results = list(progress_bar(map(_retarget, clips), len(clips), "packing", progress))
    else:
        with ProcessPoolExecutor(workers) as ex:
            results = list(progress_bar(ex.map(_retarget, clips, chunksize=4), len(clips), "packing", progress))
    header = {"format": FORMAT, "rot_scale": ROT_SCALE, "pos_scale": POS_SCALE, "joints": sk.NUM_JOINTS,
              "clips": [{"name": r[0], "subject": r[1], "frame_time": r[2], "frames": r[4],
                         "offsets": r[3].tolist()} for r in results]}
    rot = np.concatenate([r[5] for r in results])
    root = np.concatenate([r[6] for r in results])
    payload = lzma.compress(_planes(rot, np.uint32) + _planes(root, np.uint64), preset=_XZ)
    head = json.dumps(header).encode()
    atomic_write_bytes(MAGIC + struct.pack("<I", len(head)) + head + payload, out, "pack")
    frames = sum(r[4] for r in results)
    return {"clips": len(results), "source_frames": frames, "bytes": Path(out).stat().st_size}


def _read_header(data: bytes, path) -> tuple:
    if data[:len(MAGIC)] != MAGIC:
        raise UsageError(f"{path} is not a motion pack (no {MAGIC.decode()} signature)")
    if len(data) < len(MAGIC) + 4:
        raise UsageError(f"{path}: the motion pack is truncated")
    (n,) = struct.unpack_from("<I", data, len(MAGIC))
    start = len(MAGIC) + 4
    try:
        header = json.loads(data[start:start + n].decode())
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise UsageError(f"{path}: the motion pack's header is damaged ({e})") from None
    if header.get("format") != FORMAT or header.get("joints") != sk.NUM_JOINTS:
        raise UsageError(f"{path}: motion pack format {header.get('format')} with {header.get('joints')} joints; "
                         f"this version reads format {FORMAT} with {sk.NUM_JOINTS}")
    if header.get("rot_scale") != ROT_SCALE or header.get("pos_scale") != POS_SCALE:
        raise UsageError(f"{path}: the motion pack's quantisation is not this version's")
    return header, data[start + n:]


def read_pack(path, fps: float = sk.MODEL_FPS) -> list:
    """The Motions of a pack at `fps`, in packed order; a damaged pack is an error naming it."""
    from .retarget import at_rate
    path = Path(path)
    header, payload = _read_header(path.read_bytes(), path)
    clips = header["clips"]
    frames = np.array([int(c["frames"]) for c in clips], np.int64)
    n_rot, n_root = int(frames.sum()) * sk.NUM_JOINTS * 4, int(frames.sum()) * 3
    try:
        raw = lzma.decompress(payload)
    except lzma.LZMAError as e:
        raise UsageError(f"{path}: the motion pack's data is damaged ({e})") from None
    if len(raw) != n_rot * 4 + n_root * 8:
        raise UsageError(f"{path}: the motion pack holds {len(raw)} bytes of data, its header needs "
                         f"{n_rot * 4 + n_root * 8} (truncated or damaged)")
    rot = _from_planes(raw[:n_rot * 4], n_rot, np.uint32).astype(np.int64)
    root = _from_planes(raw[n_rot * 4:], n_root, np.uint64).view(np.int64)
    out = []
    ro = po = 0
    for c, F in zip(clips, frames):
        nr, np_ = int(F) * sk.NUM_JOINTS * 4, int(F) * 3
        local, rootpos = _decode_clip(rot[ro:ro + nr], root[po:po + np_], int(F))
        ro, po = ro + nr, po + np_
        local, rootpos = at_rate(local, rootpos, float(c["frame_time"]), fps)
        m = sk.Motion(name=str(c["name"]), subject=int(c["subject"]), fps=float(fps),
                      local_rot=local.astype(np.float32), root_pos=rootpos.astype(np.float32),
                      offsets=np.asarray(c["offsets"], np.float32).reshape(sk.NUM_JOINTS, 3))
        bad = m.non_finite_field()
        if bad:
            raise UsageError(f"{path}: clip {m.name} decodes to non-finite {bad}")
        out.append(m)
    return out
