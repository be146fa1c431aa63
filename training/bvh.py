"""BVH reader and writer (numpy, vectorised over frames).

Reader semantics
- HIERARCHY with ROOT / JOINT / End Site blocks, any whitespace (tabs, CRLF), any channel list
  per joint (rotation channels in any order, position channels on any joint).
- Rotation channels are intrinsic rotations applied in the listed order:
  `Zrotation Xrotation Yrotation` gives R = Rz(z) Rx(x) Ry(y) (degrees). R maps the joint frame
  into its parent frame; rest pose = all angles zero.
- Position channels give the joint's translation in its parent frame and REPLACE its OFFSET
  (an axis without a channel keeps the OFFSET value). For the root this is `root_pos`.
- MOTION: `Frames: N`, `Frame Time: dt`, then N lines of numbers, each holding exactly one value
  per declared channel (a line with more or fewer is refused: read as one flat array, it would
  shift every later frame onto the wrong channels). Fewer lines than N: a warning, the lines held
  are used (a cut file); more: a warning, the first N are used.
Units are whatever the file uses (cm for the CMU data); nothing is converted here.
Errors are BvhError; read_bvh's messages and warnings name the file.
"""
from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .skeleton import rot_to_euler

_POS = {"Xposition": 0, "Yposition": 1, "Zposition": 2}
_ROT = {"Xrotation": "X", "Yrotation": "Y", "Zrotation": "Z"}


class BvhError(ValueError):
    pass


# Motion capture records 24 to 120+ frames per second (CMU: 1/120 s, re-published at 1/24 and
# 1/12 s). A Frame Time above this is a damaged file, and resampling it to 60 Hz would create 60
# frames per source frame or more (Frame Time 1e6 asked for ~24 GB).
MAX_FRAME_TIME = 1.0


@dataclass
class BvhClip:
    joints: list                      # names, depth-first file order
    parents: list                     # parent index, -1 for the root
    offsets: np.ndarray               # (J,3) OFFSETs in file units
    channels: list                    # per joint: list of channel names as in the file
    frame_time: float                 # seconds per frame, as written in the file
    rotations: np.ndarray             # (F,J,3,3) local rotation matrices (identity without channels)
    root_pos: np.ndarray              # (F,3) root translation (OFFSET when no position channels)
    end_sites: dict = field(default_factory=dict)   # joint index -> (3,) End Site offset
    translations: Optional[np.ndarray] = None       # (F,J,3) local translations when any non-root
                                                    # joint has position channels, else None
    source: str = ""                                # the file it was read from (for messages)

    @property
    def num_frames(self) -> int:
        return int(self.rotations.shape[0])

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    def index(self, name: str) -> int:
        return self.joints.index(name)

    def local_translations(self) -> np.ndarray:
        """(F,J,3) translation of every joint in its parent frame (root: root_pos)."""
        if self.translations is not None:
            t = self.translations.copy()
        else:
            t = np.broadcast_to(self.offsets, (self.num_frames,) + self.offsets.shape).copy()
        t[:, 0] = self.root_pos
        return t

    def global_transforms(self):
        """(global rotations (F,J,3,3), world positions (F,J,3))."""
        F, J = self.num_frames, len(self.joints)
        tr = self.local_translations()
        g = np.empty((F, J, 3, 3))
        p = np.empty((F, J, 3))
        for j in range(J):
            q = self.parents[j]
            if q < 0:
                g[:, j] = self.rotations[:, j]
                p[:, j] = tr[:, j]
            else:
                g[:, j] = g[:, q] @ self.rotations[:, j]
                p[:, j] = p[:, q] + np.einsum("fab,fb->fa", g[:, q], tr[:, j])
        return g, p

    def rest_positions(self) -> np.ndarray:
        """(J,3) joint positions in the rest pose (all rotations zero, root at its OFFSET)."""
        p = np.zeros((len(self.joints), 3))
        for j, q in enumerate(self.parents):
            p[j] = self.offsets[j] if q < 0 else p[q] + self.offsets[j]
        return p


def _parse_hierarchy(tokens):
    joints, parents, offsets, channels, end_sites = [], [], [], [], {}
    stack = []  # indices of open joints (None for an End Site block)
    i, n = 0, len(tokens)
    if n == 0 or tokens[0].upper() != "HIERARCHY":
        raise BvhError("file does not start with HIERARCHY")
    i = 1
    pending = None  # ('joint', name) or ('end',)
    while i < n:
        t = tokens[i]
        tu = t.upper()
        if tu in ("ROOT", "JOINT"):
            if i + 1 >= n:
                raise BvhError("joint name missing")
            if tu == "ROOT" and joints and not stack:
                raise BvhError("more than one ROOT is not supported")
            pending = ("joint", tokens[i + 1])
            i += 2
        elif tu == "END":
            pending = ("end",)
            i += 2 if i + 1 < n and tokens[i + 1].upper() == "SITE" else 1
        elif t == "{":
            if pending is None:
                raise BvhError("unexpected '{'")
            if pending[0] == "joint":
                parent = next((s for s in reversed(stack) if s is not None), -1) if stack else -1
                if parent == -1 and joints:
                    raise BvhError("joint outside the root block")
                joints.append(pending[1])
                parents.append(parent)
                offsets.append(np.zeros(3))
                channels.append([])
                stack.append(len(joints) - 1)
            else:
                if not stack or stack[-1] is None:
                    raise BvhError("End Site outside a joint")
                stack.append(None)
                end_sites[stack[-2]] = np.zeros(3)
            pending = None
            i += 1
        elif t == "}":
            if not stack:
                raise BvhError("unbalanced '}'")
            stack.pop()
            i += 1
        elif tu == "OFFSET":
            if not stack:
                raise BvhError("OFFSET outside a block")
            try:
                v = np.array([float(x) for x in tokens[i + 1:i + 4]])
            except ValueError as e:
                raise BvhError(f"bad OFFSET: {tokens[i + 1:i + 4]}") from e
            if v.shape != (3,):
                raise BvhError("truncated OFFSET")
            if not np.isfinite(v).all():
                raise BvhError(f"OFFSET {tokens[i + 1:i + 4]} is not finite")
            if stack[-1] is None:
                end_sites[stack[-2]] = v
            else:
                offsets[stack[-1]] = v
            i += 4
        elif tu == "CHANNELS":
            if not stack or stack[-1] is None:
                raise BvhError("CHANNELS outside a joint")
            try:
                k = int(tokens[i + 1])
            except (ValueError, IndexError) as e:
                raise BvhError(f"CHANNELS needs a count: {tokens[i + 1:i + 2]}") from e
            chans = tokens[i + 2:i + 2 + k]
            if k < 0 or len(chans) != k:
                raise BvhError(f"CHANNELS {k}: the count does not match the channels that follow")
            for c in chans:
                if c not in _POS and c not in _ROT:
                    raise BvhError(f"unknown channel {c!r}")
            channels[stack[-1]] = list(chans)
            i += 2 + k
        else:
            raise BvhError(f"unexpected token {t!r} in HIERARCHY")
    if stack:
        raise BvhError("unbalanced braces in HIERARCHY")
    if not joints:
        raise BvhError("no joints")
    return joints, parents, np.array(offsets, dtype=np.float64), channels, end_sites


_MOTION_RE = re.compile(r"\bMOTION\b")
_FRAMES_RE = re.compile(r"Frames\s*:[ \t]*(\S*)", re.IGNORECASE)
_FTIME_RE = re.compile(r"Frame\s+Time\s*:[ \t]*(\S*)", re.IGNORECASE)


def _frame_time(value: str) -> float:
    try:
        frame_time = float(value)
    except ValueError:
        raise BvhError(f"Frame Time {value!r} is not a number") from None
    if not (frame_time > 0 and math.isfinite(frame_time)):
        raise BvhError(f"Frame Time {value!r} is not a positive finite number of seconds")
    if frame_time > MAX_FRAME_TIME:
        raise BvhError(f"Frame Time {value} s is implausible (more than {MAX_FRAME_TIME:g} s per frame; "
                       "motion capture records 24 frames per second or more)")
    return frame_time


def _values_per_line(body: str) -> np.ndarray:
    """Number of whitespace-separated values on each line of body, vectorised over the bytes (the
    CMU set has 4 million motion lines; a Python loop over them would double the reading time)."""
    b = np.frombuffer(body.encode("utf-8", "replace"), dtype=np.uint8)
    space = b <= 32                      # whitespace (other control bytes fail as numbers later)
    newlines = np.flatnonzero(b == 10)
    starts = np.flatnonzero(space[:-1] & ~space[1:]) + 1      # first byte of each value
    if b.size and not space[0]:
        starts = np.concatenate([[0], starts])
    return np.bincount(np.searchsorted(newlines, starts), minlength=newlines.size + 1)


def _line_start(body: str, line: int) -> int:
    """Offset of the first character of body's line `line` (0-based)."""
    at = 0
    for _ in range(line):
        at = body.index("\n", at) + 1
    return at


def _first_bad_number(body: str, first_line: int) -> str:
    for k, line in enumerate(body.split("\n")):
        for tok in line.split():
            try:
                float(tok)
            except ValueError:
                return f"line {first_line + k}: {tok!r} is not a number"
    return "a value that is not a number"


def parse_bvh(text: str, source: str = "") -> BvhClip:
    """source: the file name, for warnings and BvhClip.source (read_bvh adds it to errors)."""
    m = _MOTION_RE.search(text)
    if m is None:
        raise BvhError("no MOTION section")
    joints, parents, offsets, channels, end_sites = _parse_hierarchy(text[:m.start()].split())
    mf = _FRAMES_RE.search(text, m.end())
    mt = _FTIME_RE.search(text, m.end())
    if mf is None or mt is None:
        raise BvhError("MOTION needs 'Frames:' and 'Frame Time:'")
    if not re.fullmatch(r"[0-9]+", mf.group(1)):
        raise BvhError(f"Frames {mf.group(1)!r} is not a whole number of frames")
    n_frames = int(mf.group(1))
    frame_time = _frame_time(mt.group(1))
    nl = text.find("\n", max(mt.end(), mf.end()))
    body = text[nl + 1:] if nl >= 0 else ""
    first_line = text.count("\n", 0, nl + 1) + 1          # file line number of body line 0
    n_ch = sum(len(c) for c in channels)
    counts = _values_per_line(body)
    lines = np.flatnonzero(counts)                          # body lines that hold values
    wrong = lines[counts[lines] != n_ch]
    name = source or "BVH"
    if wrong.size == 1 and wrong[0] == lines[-1] and counts[wrong[0]] < n_ch:
        # Only the last line is short: a file cut while it was written. Its whole frames are
        # good; the cut one is left out, as the C# reader does.
        warnings.warn(f"{name}: the last motion line (line {first_line + wrong[0]}) is cut short; "
                      f"it is left out")
        body = body[:_line_start(body, int(wrong[0]))]
        lines, wrong = lines[:-1], wrong[:0]
    if wrong.size:
        raise BvhError(f"line {first_line + wrong[0]} holds {counts[wrong[0]]} values, but the HIERARCHY "
                       f"declares {n_ch} channels (every motion line must hold one value per channel)")
    if n_ch and lines.size < n_frames:
        warnings.warn(f"{name}: declares {n_frames} frames but holds {lines.size}; using {lines.size}")
        n_frames = int(lines.size)
    elif lines.size > n_frames:
        warnings.warn(f"{name}: holds {lines.size} frames but declares {n_frames}; using the first {n_frames}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        data = np.fromstring(body, sep=" ") if body.strip() else np.zeros(0)
    if data.size != lines.size * n_ch:
        # np.fromstring stops at the first bad token: say which one
        try:
            data = np.array(body.split(), dtype=np.float64)
        except ValueError:
            raise BvhError(_first_bad_number(body, first_line)) from None
    data = data[:n_frames * n_ch].reshape(n_frames, n_ch) if n_ch else np.zeros((n_frames, 0))
    bad = np.flatnonzero(~np.isfinite(data).all(axis=1))
    if bad.size:
        # np.fromstring reads "nan" and "inf"; a damaged file must not turn into NaN rotations
        raise BvhError(f"MOTION frame {bad[0] + 1} (line {first_line + lines[bad[0]]}) holds a value "
                       "that is not finite")
    return _build_clip(joints, parents, offsets, channels, end_sites, frame_time, data, source)


def _build_clip(joints, parents, offsets, channels, end_sites, frame_time, data, source="") -> BvhClip:
    F, J = data.shape[0], len(joints)
    rotations = np.empty((F, J, 3, 3))
    rotations[:] = np.eye(3)
    translations = np.broadcast_to(offsets, (F, J, 3)).copy()
    any_child_pos = False
    groups: dict = {}  # rotation order -> (joint indices, column indices)
    col = 0
    for j, chans in enumerate(channels):
        rot_axes, rot_cols = [], []
        for c in chans:
            if c in _POS:
                translations[:, j, _POS[c]] = data[:, col]
                if j != 0:
                    any_child_pos = True
            else:
                rot_axes.append(_ROT[c])
                rot_cols.append(col)
            col += 1
        if rot_axes:
            key = "".join(rot_axes)
            groups.setdefault(key, ([], []))
            groups[key][0].append(j)
            groups[key][1].append(rot_cols)
    for order, (js, cols) in groups.items():
        ang = data[:, np.array(cols)]                    # (F, len(js), k)
        r = np.broadcast_to(np.eye(3), ang.shape[:2] + (3, 3)).copy()
        for k, ax in enumerate(order):                   # intrinsic: multiply on the right
            r = r @ _rot_deg(ax, ang[..., k])
        rotations[:, js] = r
    return BvhClip(joints=list(joints), parents=list(parents), offsets=offsets, channels=channels,
                   frame_time=float(frame_time), rotations=rotations, root_pos=translations[:, 0].copy(),
                   end_sites=end_sites, translations=translations if any_child_pos else None,
                   source=str(source))


def _rot_deg(axis, deg):
    return _axis_rot(axis, np.deg2rad(deg))


def _axis_rot(axis, a):
    c, s = np.cos(a), np.sin(a)
    r = np.zeros(a.shape + (3, 3))
    i = "XYZ".index(axis)
    j, k = (i + 1) % 3, (i + 2) % 3
    r[..., i, i] = 1.0
    r[..., j, j] = c
    r[..., k, k] = c
    r[..., j, k] = -s
    r[..., k, j] = s
    return r


def read_bvh(path) -> BvhClip:
    with open(path, "r", encoding="utf-8", errors="replace", newline=None) as f:
        text = f.read()
    try:
        return parse_bvh(text, source=str(path))
    except BvhError as e:
        raise BvhError(f"{path}: {e}") from None


# ------------------------------------------------------------------------------ writer
def _fmt(v, decimals):
    s = f"{v:.{decimals}f}"
    if "." in s:
        s = s.rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def format_bvh(clip: BvhClip, order: str = "ZXY", decimals: int = 6) -> str:
    """Text of a BVH file for `clip`: root with 3 position + 3 rotation channels, other joints
    with 3 rotation channels (plus position channels where clip.translations is set), rotations
    written as intrinsic Euler angles in `order` ("ZXY" or "XYZ", any Tait-Bryan order works)."""
    order = order.upper()
    if sorted(order) != ["X", "Y", "Z"]:
        raise ValueError("order must be a permutation of XYZ")
    J = len(clip.joints)
    children = [[] for _ in range(J)]
    for j, q in enumerate(clip.parents):
        if q >= 0:
            children[q].append(j)
    rot_ch = [f"{a}rotation" for a in order]
    pos_joint = [j == 0 or clip.translations is not None for j in range(J)]
    lines = ["HIERARCHY"]

    def emit(j, depth):
        ind = "\t" * depth
        lines.append(f"{ind}{'ROOT' if clip.parents[j] < 0 else 'JOINT'} {clip.joints[j]}")
        lines.append(f"{ind}{{")
        off = " ".join(_fmt(v, decimals) for v in clip.offsets[j])
        lines.append(f"{ind}\tOFFSET {off}")
        ch = (["Xposition", "Yposition", "Zposition"] if pos_joint[j] else []) + rot_ch
        lines.append(f"{ind}\tCHANNELS {len(ch)} {' '.join(ch)}")
        for c in children[j]:
            emit(c, depth + 1)
        if not children[j] or j in clip.end_sites:
            e = clip.end_sites.get(j, np.zeros(3))
            lines.append(f"{ind}\tEnd Site")
            lines.append(f"{ind}\t{{")
            lines.append(f"{ind}\t\tOFFSET {' '.join(_fmt(v, decimals) for v in e)}")
            lines.append(f"{ind}\t}}")
        lines.append(f"{ind}}}")

    # joints are written depth-first, which must be the order of clip.joints for the columns
    emit(0, 0)
    F = clip.num_frames
    lines.append("MOTION")
    lines.append(f"Frames: {F}")
    lines.append(f"Frame Time: {clip.frame_time:.7f}")
    eul = rot_to_euler(clip.rotations, order, degrees=False)        # (F,J,3)
    eul = np.rad2deg(np.unwrap(eul, axis=0)) if F > 1 else np.rad2deg(eul)
    trans = clip.local_translations()
    cols = []
    for j in _depth_first(children):
        if pos_joint[j]:
            cols.append(trans[:, j])
        cols.append(eul[:, j])
    data = np.concatenate(cols, axis=1) if cols else np.zeros((F, 0))
    data = np.round(data, decimals)
    data[data == 0] = 0.0  # no "-0"
    fmt = f"%.{decimals}f"
    body = "\n".join(" ".join(fmt % v for v in row) for row in data)
    return "\n".join(lines) + "\n" + body + ("\n" if F else "")


def _depth_first(children):
    out, stack = [], [0]
    while stack:
        j = stack.pop()
        out.append(j)
        stack.extend(reversed(children[j]))
    return out


def write_bvh(path, clip: BvhClip, order: str = "ZXY", decimals: int = 6) -> None:
    children = [[] for _ in clip.joints]
    for j, q in enumerate(clip.parents):
        if q >= 0:
            children[q].append(j)
    if _depth_first(children) != list(range(len(clip.joints))):
        raise ValueError("clip joints must be in depth-first order (parents before children, subtrees contiguous)")
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write(format_bvh(clip, order, decimals))
