"""The body segments a sensor can ride on, read from the engine's one table, and what a list of
them means for training: which bone each sensor turns with, and which sensor mirrors which.

The table is `Packages/com.mocap.imu/Native~/src/imu/segments.def`, rows
`MOCAP_SEGMENT_ROW(ENUM, id, "name", smpl_joint, default_node)`; C, C# (through the engine) and
this module all read it, so a segment is added in one place. The default sensor set (the six of
model contract 1, docs/model-contract.md) is the rows with a default node id (>= 0), in id order.

A sensor list is a sequence of segment names, in the model's input order. Synthesis, the network
and export take one (default: DEFAULT_SENSORS); `sensor_list` checks it.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import skeleton as sk

REPO = Path(__file__).resolve().parents[1]
SEGMENTS_FILE = REPO / "Packages" / "com.mocap.imu" / "Native~" / "src" / "imu" / "segments.def"
MAX_SENSORS = 16   # MOCAP_MAX_SENSORS of the engine's header

# Where the wrist sensors are: on the back of the hand ("hand", the shipped model's placement:
# the sensor turns with the wrist joint's bone) or as a strap on the distal forearm ("forearm").
# A strap sits just above the wrist joint: it turns with the forearm, including the forearm's
# twist (pronation and supination, which the CMU skeleton and ours keep in the wrist joint), but
# not with the hand's flexion or sideways bend. So it reports the forearm (the parent bone of
# the wrist joint) turned by the twist part of the wrist joint.
WRIST_SENSOR_PLACES = ("hand", "forearm")
WRIST_SEGMENTS = ("left_wrist", "right_wrist")


@dataclass(frozen=True)
class Segment:
    enum: str           # the header's MOCAP_SEGMENT_<enum>
    id: int
    name: str
    joint: int          # SMPL-24 joint (skeleton.JOINT_NAMES) whose bone the sensor follows
    default_node: int   # HiPNUC node id in the default sensor set, -1 = not in it


_COMMENTS = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)
_ROW = re.compile(r'MOCAP_SEGMENT_ROW\s*\(\s*([A-Z0-9_]+)\s*,\s*(-?\d+)\s*,\s*"([^"]*)"\s*,'
                  r'\s*(-?\d+)\s*,\s*(-?\d+)\s*\)')


def parse_segments(text: str, source: str = "segments.def") -> tuple:
    """The table's rows as Segments, in id order. ValueError naming the row for anything the
    engine would not accept either: a malformed row, ids not 0, 1, 2 ..., a name that is not
    lower case or the ENUM's lower case, a repeated name or node id, a joint outside the skeleton."""
    body = _COMMENTS.sub(" ", text)
    segments = []
    rest = body
    for m in _ROW.finditer(body):
        enum, sid, name, joint, node = m.group(1), int(m.group(2)), m.group(3), int(m.group(4)), int(m.group(5))
        row = f"{source}: row {m.group(0)!r}"
        if sid != len(segments):
            raise ValueError(f"{row}: id {sid}, expected {len(segments)} (ids count up from 0)")
        if not re.fullmatch(r"[a-z][a-z0-9_]*", name) or name != enum.lower():
            raise ValueError(f"{row}: name {name!r} must be the lower-case ENUM {enum.lower()!r}")
        if any(s.name == name for s in segments):
            raise ValueError(f"{row}: segment {name!r} is already in the table")
        if not 0 <= joint < sk.NUM_JOINTS:
            raise ValueError(f"{row}: joint {joint} is not a skeleton joint (0..{sk.NUM_JOINTS - 1})")
        if node < -1:
            raise ValueError(f"{row}: default node {node}: a node id >= 0, or -1 for none")
        if node >= 0 and any(s.default_node == node for s in segments):
            raise ValueError(f"{row}: default node {node} is already another segment's")
        segments.append(Segment(enum, sid, name, joint, node))
        rest = rest.replace(m.group(0), " ", 1)
    leftover = rest.strip()
    if leftover:
        raise ValueError(f"{source}: not a MOCAP_SEGMENT_ROW(...) row: {leftover.splitlines()[0][:80]!r}")
    if not segments:
        raise ValueError(f"{source}: no MOCAP_SEGMENT_ROW rows")
    if len(segments) > 32:   # the engine's masks are 32-bit
        raise ValueError(f"{source}: {len(segments)} segments, at most 32")
    return tuple(segments)


def load_segments(path=SEGMENTS_FILE) -> tuple:
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise ValueError(f"the segment table {path} cannot be read: {e.strerror or e}") from e
    return parse_segments(text, str(path.relative_to(REPO) if path.is_relative_to(REPO) else path))


SEGMENTS = load_segments()
SEGMENT_NAMES = tuple(s.name for s in SEGMENTS)
DEFAULT_SENSORS = tuple(s.name for s in SEGMENTS if s.default_node >= 0)
_BY_NAME = {s.name: s for s in SEGMENTS}


def segment(name: str) -> Segment:
    try:
        return _BY_NAME[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown segment {name!r}: expected one of {', '.join(SEGMENT_NAMES)} "
                         f"({SEGMENTS_FILE.name})") from None


def sensor_list(names) -> tuple:
    """names (a sequence of segment names, or one comma-separated string) checked as a model's
    sensor list: 1 to MAX_SENSORS known segments, none twice. Returns them as a tuple."""
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",")]
    names = tuple(names)
    if not 1 <= len(names) <= MAX_SENSORS:
        raise ValueError(f"a sensor list has 1 to {MAX_SENSORS} segments, got {len(names)}")
    for n in names:
        segment(n)
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"segment {', '.join(twice)} listed more than once in {', '.join(names)}")
    return names


def sensor_joints(names=DEFAULT_SENSORS) -> list:
    """The table's joint of each sensor: where it sits, and the bone it turns with when the wrist
    sensors are on the back of the hands."""
    return [segment(n).joint for n in sensor_list(names)]


def sensor_bones(wrist: str = "hand", names=DEFAULT_SENSORS) -> list:
    """The bone each sensor turns with: its table joint; for wrist straps ("forearm") the wrist
    segments' forearm (the wrist joint's parent)."""
    if wrist not in WRIST_SENSOR_PLACES:
        raise ValueError(f"wrist sensor place {wrist!r}: expected one of {WRIST_SENSOR_PLACES}")
    joints = sensor_joints(names)
    if wrist == "forearm":
        joints = [sk.PARENTS[j] if n in WRIST_SEGMENTS else j for n, j in zip(names, joints)]
    return joints


def sensor_bone_orientations(global_rot, local_rot, wrist: str = "hand", names=DEFAULT_SENSORS) -> np.ndarray:
    """What each sensor's bone orientation is, (T,24,3,3) global and local rotations -> (T,N,3,3)
    in the list's order: the global rotation of its bone (`sensor_bones`); for wrist straps, the
    forearm's times the twist of the wrist joint."""
    names = sensor_list(names)
    g = np.asarray(global_rot, dtype=np.float64)
    out = g[:, sensor_bones(wrist, names)].copy()
    if wrist == "forearm":
        local = np.asarray(local_rot, dtype=np.float64)
        for s, n in enumerate(names):
            if n in WRIST_SEGMENTS:
                out[:, s] = out[:, s] @ sk.twist_about_x(local[:, segment(n).joint])
    return out


def mirror_segment(name: str) -> str:
    """The segment on the other side of the body (itself on the midline)."""
    segment(name)
    for a, b in (("left_", "right_"), ("right_", "left_")):
        if name.startswith(a):
            other = b + name[len(a):]
            segment(other)
            return other
    return name


def mirror_indices(names=DEFAULT_SENSORS) -> list:
    """For each sensor, the index of its mirror image in the same list (a left/right pair swaps).
    ValueError when a sensor's counterpart is not in the list."""
    names = sensor_list(names)
    out = []
    for n in names:
        other = mirror_segment(n)
        if other not in names:
            raise ValueError(f"sensor {n} has no mirror image in {', '.join(names)} (add {other})")
        out.append(names.index(other))
    return out


def node_ids(names=DEFAULT_SENSORS) -> list:
    """A HiPNUC node id for each sensor (segment names) of a synthetic capture: the segment's
    default node where it has one, else the lowest id no other sensor of the list uses."""
    names = sensor_list(names)
    taken = {segment(n).default_node for n in names} - {-1}
    out = []
    for n in names:
        node = segment(n).default_node
        if node < 0:
            node = min(set(range(len(names) + len(taken) + 1)) - taken)
            taken.add(node)
        out.append(node)
    return out
