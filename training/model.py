"""Streaming pose network (owner: model).

PoseNet maps the calibrated IMU signals of its N sensors (ModelConfig.sensors, segment names of
the engine's table, sensors.py; default the six of contract 1: global bone orientations and bone
accelerations, model frame, physical units) to joint rotations, root velocity and foot contact
probabilities. One sensor must be the pelvis. It is causal and its only memory is the LSTM
state (h, c) of shape [STATE_LAYERS, B, STATE_SIZE], so one call with T frames equals T calls
with T = 1 and the per-frame cost does not depend on the session length.

Every normalisation happens inside the module (and so inside the exported ONNX graph):

* heading removal: the pelvis heading is the horizontal direction
  h = f_xz - f_y * u_xz, f = column 2 (forward) and u = column 1 (up) of the pelvis matrix.
  For an upright or bent-over pelvis h points along the projected forward axis; the u term keeps
  it defined when the pelvis forward axis is vertical (lying on the back or front). It rotates
  exactly with any yaw of the whole body. Ry(heading) is built from the normalised (x, z) of h,
  no atan2 (ONNX has none);
* features per frame (24 N - 12 values, 132 for six sensors): the N orientations and
  accelerations in the heading frame (Ry^T R_i, Ry^T a_i) and the N - 1 non-pelvis sensors
  relative to the pelvis (R_p^T R_i, R_p^T (a_i - a_p)); accelerations are divided by ACC_SCALE;
* outputs are mapped back: joint 0 (pelvis) is predicted in the heading frame as a residual on
  the measured heading-free pelvis orientation and rotated back by Ry; joints 1..23 are residuals
  on the identity (rest pose); root velocity is predicted in the heading frame and rotated back.

A masked network (ModelConfig.masked, model contract 2) also takes a mask (B,T,N): 1 where a sensor
is present, 0 where it is missing, with that sensor's inputs zero (as the engine feeds them). A
zero matrix is no rotation, so a missing sensor's orientation is read as the identity and its
acceleration as zero, every feature block of a missing sensor (and every pelvis-relative block
while the pelvis is missing) is zeroed, and the mask itself is appended to the features, so the
network knows what it lacks; an anchored bone of a missing sensor falls back to the rest pose.

Rotations are predicted as 6D (first two matrix columns) and orthonormalised by Gram-Schmidt.
Only export-friendly ops are used (matmul, slicing, elementwise, LSTM, no atan2).
"""
from __future__ import annotations

import functools
import numbers
from dataclasses import dataclass, asdict, replace
from typing import NamedTuple

import torch
import torch.nn as nn

from . import sensors as se
from .skeleton import MIRROR_JOINTS, PARENTS

NUM_JOINTS = 24
ACC_SCALE = 30.0            # m/s^2 -> network units (TransPose uses the same divisor)
OUTPUT_SIZE = NUM_JOINTS * 6 + 3 + 2           # 149
PELVIS = "pelvis"


def feature_size(num_sensors: int, masked: bool = False) -> int:
    """Per-frame features of N sensors: N orientations and accelerations in the heading frame,
    N - 1 of each relative to the pelvis; a masked network adds the N mask values."""
    return num_sensors * (9 + 3) + (num_sensors - 1) * (9 + 3) + (num_sensors if masked else 0)


def feature_labels(sensors, masked: bool = False) -> list:
    """What each per-frame feature reads, in the network's feature order: (block, segment,
    component) with block "ori" / "acc" (heading frame), "rel_ori" / "rel_acc" (relative to the
    pelvis) or "mask". Two networks' first layers line up through these (with_sensors)."""
    others = [n for n in sensors if n != PELVIS]
    labels = [("ori", n, k) for n in sensors for k in range(9)]
    labels += [("acc", n, k) for n in sensors for k in range(3)]
    labels += [("rel_ori", n, k) for n in others for k in range(9)]
    labels += [("rel_acc", n, k) for n in others for k in range(3)]
    if masked:
        labels += [("mask", n, 0) for n in sensors]
    return labels


def _ancestors(joints):
    out = set()
    for j in joints:
        p = PARENTS[j]
        while p > 0:
            out.add(p)
            p = PARENTS[p]
    return out


def _index(x: torch.Tensor, dim: int, idx: list) -> torch.Tensor:
    """x's entries idx along dim: a slice where idx is a run (the graph keeps a Slice), else a
    gather."""
    if idx == list(range(idx[0], idx[0] + len(idx))):
        return x.narrow(dim, idx[0], len(idx))
    return x.index_select(dim, torch.tensor(idx, device=x.device))


class _AnchorPlan(NamedTuple):
    sensors: list      # input index of each anchored sensor (the pelvis is never re-anchored)
    joints: list       # its bone
    levels: list       # forward kinematics below the root: (joints, index of each one's parent
                       # in the level above) per tree depth, only the joints the parents need
    parent_at: list    # each bone's parent in the levels (root first) laid end to end
    order: list        # the 24 joints from [network rotations, anchored rotations]


@functools.lru_cache(maxsize=None)
def _anchor_plan(anchors: tuple) -> _AnchorPlan:
    """How _anchor_sensor_bones batches the sensor bones `anchors` (a joint per sensor)."""
    picked = {j: s for s, j in enumerate(anchors) if j != 0}      # the last sensor of a bone wins
    joints = sorted(picked, key=picked.get)
    sensors = [picked[j] for j in joints]
    parents = [PARENTS[j] for j in joints]
    needed = set(parents) | _ancestors(parents)
    depth = {0: 0}
    for j in range(1, NUM_JOINTS):
        depth[j] = depth[PARENTS[j]] + 1
    laid, levels = [[0]], []
    for d in range(1, max((depth[j] for j in needed), default=0) + 1):
        level = sorted(j for j in needed if depth[j] == d)
        levels.append((level, [laid[-1].index(PARENTS[j]) for j in level]))
        laid.append(level)
    flat = [j for level in laid for j in level]
    order = [NUM_JOINTS + joints.index(j) if j in picked else j for j in range(NUM_JOINTS)]
    return _AnchorPlan(sensors, joints, levels, [flat.index(p) for p in parents], order)


@dataclass
class ModelConfig:
    embed: int = 256          # per-frame MLP width
    hidden: int = 384         # LSTM state size H
    layers: int = 2           # LSTM layers L
    head: int = 256           # output MLP width
    dropout: float = 0.0      # training only: after the frame MLP, between and after LSTM layers
    anchored: bool = False    # sensor bones' local rotations are residuals on the measured ones
    # The bone the wrist sensors report, as trained (train --wrist-sensor): "hand" (a sensor on the
    # back of the hand: the shipped model) or "forearm" (a wrist strap, sensors.sensor_bones).
    # Anchored networks anchor it.
    wrist_anchor: str = "hand"
    # The input sensors, segment names in input order (sensors.py). Checkpoints written before
    # it existed have the default six.
    sensors: tuple = se.DEFAULT_SENSORS
    # Which of `sensors` the network can do without (model contract 2's mocap.sensor_required
    # 0), and whether it takes the mask input that says, frame by frame, which sensors are
    # present. False is the network of contract 1 (no mask: every sensor always present).
    optional: tuple = ()
    masked: bool = False
    # The recurrent core between the frame MLP and the heads: "lstm" (the shipped network: an
    # LSTM of `layers` x `hidden`) or "transformer", the class of the seed system's TIP for the
    # architecture comparison (`train --size tip`): `blocks` causal self-attention blocks of
    # `heads` heads and feed-forward width `ff`, each frame attending to the last `window` frames,
    # then a tanh RNN of `layers` x `hidden`. Only "lstm" follows the engine's state contract.
    core: str = "lstm"
    window: int = 40
    blocks: int = 4
    heads: int = 16
    ff: int = 1024

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> "ModelConfig":
        """From a checkpoint's config; unknown keys are ignored, and a checkpoint written before
        `wrist_anchor` existed was trained with the wrist sensors on the hands."""
        known = cls.__dataclass_fields__
        d = {k: v for k, v in d.items() if k in known}
        d.setdefault("wrist_anchor", "hand")
        if d["wrist_anchor"] not in se.WRIST_SENSOR_PLACES:
            raise ValueError(f"wrist_anchor {d['wrist_anchor']!r}: expected one of {list(se.WRIST_SENSOR_PLACES)}")
        d["sensors"] = check_sensors(d.get("sensors", se.DEFAULT_SENSORS))
        d["masked"] = d.get("masked", False)
        if not isinstance(d["masked"], bool):
            raise ValueError(f"masked {d['masked']!r}: expected true or false")
        d["optional"] = check_optional(d["sensors"], d.get("optional", ()), d["masked"])
        # A damaged or hand-edited config would otherwise fail deep inside torch (e.g. nn.LSTM
        # with hidden -5), far from the file that holds it.
        if d.get("core", "lstm") not in CORES:
            raise ValueError(f"core {d['core']!r}: expected one of {list(CORES)}")
        for k in ("embed", "hidden", "layers", "head", "window", "blocks", "heads", "ff"):
            v = d.get(k, known[k].default)
            if isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < 1:
                raise ValueError(f"{k} {v!r}: expected a positive integer")
        if d.get("core") == "transformer":
            check_attention_dims(*(d.get(k, known[k].default) for k in ("embed", "heads", "window")))
        dropout = d.get("dropout", 0.0)
        if isinstance(dropout, bool) or not isinstance(dropout, numbers.Real) or not 0.0 <= dropout < 1.0:
            raise ValueError(f"dropout {dropout!r}: expected a number in [0, 1)")
        return cls(**d)


CORES = ("lstm", "transformer")


def check_sensors(names) -> tuple:
    """A network's sensor list (sensors.sensor_list) that holds the pelvis, whose heading every
    feature is expressed in; ValueError otherwise."""
    names = se.sensor_list(names)
    if PELVIS not in names:
        raise ValueError(f"sensors {', '.join(names)}: the network needs a {PELVIS} sensor (its heading frame)")
    return names


def check_optional(sensors, optional, masked: bool) -> tuple:
    """The optional sensors (segment names, or one comma-separated string) checked against the
    network's sensor list and returned in its order; ValueError for a name not in the list, an
    optional pelvis (every feature is expressed in its heading frame and relative to it), or
    optional sensors on a network without the mask input."""
    if isinstance(optional, str):
        optional = [n.strip() for n in optional.split(",") if n.strip()]
    optional = tuple(optional or ())
    for n in optional:
        if n not in sensors:
            raise ValueError(f"optional sensor {n!r} is not one of the network's sensors "
                             f"({', '.join(sensors)})")
    if PELVIS in optional:
        raise ValueError(f"the {PELVIS} cannot be optional: the network expresses every other sensor "
                         f"in the pelvis heading frame and relative to the pelvis")
    if optional and not masked:
        raise ValueError(f"optional sensors ({', '.join(optional)}) need a masked network (masked: the "
                         f"mask input tells it which sensors are present)")
    return tuple(n for n in sensors if n in optional)


def check_attention_dims(embed: int, heads: int, window: int) -> None:
    """ValueError for a transformer core that cannot be built: heads must split the width, and a
    frame must see at least one frame before it."""
    if embed % heads:
        raise ValueError(f"embed {embed} is not a multiple of heads {heads}")
    if window < 2:
        raise ValueError(f"window {window}: a frame must see at least one frame before it")


# The network writes each joint's 6D rotation as column 0 then column 1: this gather lays the
# 144 values out as (joint, row, column), so a reshape gives the columns without a transpose.
_COLUMN_ORDER = [j * 6 + c * 3 + r for j in range(NUM_JOINTS) for r in range(3) for c in range(2)]

DEFAULT_CONFIG = ModelConfig()
STATE_LAYERS = DEFAULT_CONFIG.layers
STATE_SIZE = DEFAULT_CONFIG.hidden


# ----------------------------------------------------------------------------- graph economy
# A frame of the exported model is a few hundred microseconds at most, and ONNX Runtime pays a
# fixed price per operator, so the helpers below keep the graph small: shapes that copy their
# leading dimensions (ONNX Reshape's 0) instead of computing them, one Split instead of slices
# at a run-time batch size. Outside an export they are the plain PyTorch operations.
class _ReshapeTail(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x, keep, tail):
        return x.reshape(tuple(x.shape[:keep]) + tuple(tail))

    @staticmethod
    def symbolic(g, x, keep, tail):
        tail = list(tail)
        if -1 not in tail:   # the exporter's shape inference needs a -1 beside the 0s
            tail[0] = -1
        shape = torch.tensor([0] * keep + tail, dtype=torch.int64)
        return g.op("Reshape", x, g.op("Constant", value_t=shape))


class _Halves(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x, dim):
        n = x.shape[dim] // 2
        return x.narrow(dim, 0, n), x.narrow(dim, n, n)

    @staticmethod
    def symbolic(g, x, dim):
        return g.op("Split", x, axis_i=dim, outputs=2)


def _reshape_tail(x: torch.Tensor, keep: int, tail) -> torch.Tensor:
    """x.reshape(x.shape[:keep] + tail); tail may hold one -1."""
    if torch.onnx.is_in_onnx_export():
        return _ReshapeTail.apply(x, keep, tuple(tail))
    return x.reshape(tuple(x.shape[:keep]) + tuple(tail))


def _halves(x: torch.Tensor, dim: int) -> tuple:
    """x's first and second half along dim (of even length)."""
    if torch.onnx.is_in_onnx_export():
        return _Halves.apply(x, dim)
    n = x.shape[dim] // 2
    return x.narrow(dim, 0, n), x.narrow(dim, n, n)


# ----------------------------------------------------------------------------- rotation helpers
def _norm(v: torch.Tensor, dim: int = -1, eps: float = 1e-8) -> torch.Tensor:
    return torch.sqrt((v * v).sum(dim, keepdim=True) + eps)


class _Unit(torch.autograd.Function):
    @staticmethod
    def forward(ctx, v, dim):
        return v / _norm(v, dim)

    @staticmethod
    def symbolic(g, v, dim):
        return g.op("LpNormalization", v, axis_i=dim, p_i=2)


def _unit(v: torch.Tensor, dim: int = -1) -> torch.Tensor:
    """v scaled to unit length along dim; one operator once exported."""
    if torch.onnx.is_in_onnx_export():
        return _Unit.apply(v, dim)
    return v / _norm(v, dim)


# a x b = a[yzx] * b[zxy] - a[zxy] * b[yzx], the rows gathered in those orders
_YZX, _ZXY = [1, 2, 0], [2, 0, 1]


def gram_schmidt(cols: torch.Tensor) -> torch.Tensor:
    """(..., 3, 2) two columns -> (..., 3, 3) rotation: the first column normalised, the second
    made orthogonal to it and normalised, the third their cross product."""
    a1, a2 = cols[..., 0:1], cols[..., 1:2]
    b1 = _unit(a1, -2)
    b2 = a2 - (b1 * a2).sum(-2, keepdim=True) * b1
    b2 = _unit(b2, -2)
    b3 = b1[..., _YZX, :] * b2[..., _ZXY, :] - b1[..., _ZXY, :] * b2[..., _YZX, :]
    return torch.cat([b1, b2, b3], dim=-1)


# Ry(heading) laid out row by row = (s, c) @ _RY_BASIS + _RY_UP, (s, c) the normalised (x, z) of h
_RY_BASIS = torch.tensor([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0],
                          [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]])
_RY_UP = torch.tensor([0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0])


def heading_rotation(pelvis: torch.Tensor) -> torch.Tensor:
    """Ry(heading) of pelvis orientations (..., 3, 3), built without atan2 as a weighted sum of
    constant matrices."""
    xz = pelvis[..., [0, 2], :]                                   # rows x and z: (..., 2, 3)
    h = xz[..., 2] - pelvis[..., 1:2, 2] * xz[..., 1]             # f_xz - f_y * u_xz
    sc = _unit(h)                                                 # (sin, cos) of the heading
    rows = sc @ _RY_BASIS.to(pelvis.device, pelvis.dtype) + _RY_UP.to(pelvis.device, pelvis.dtype)
    return _reshape_tail(rows, pelvis.dim() - 2, (3, 3))


def forward_kinematics_torch(local_rot: torch.Tensor, offsets: torch.Tensor, parents) -> tuple:
    """local_rot (..., 24, 3, 3) with joint 0 global, offsets (..., 24, 3) broadcastable.

    Returns (global_rot (..., 24, 3, 3), positions (..., 24, 3) relative to the root joint)."""
    g = [local_rot[..., 0, :, :]]
    p = [torch.zeros_like(local_rot[..., 0, :, 0])]
    for j in range(1, len(parents)):
        par = parents[j]
        g.append(g[par] @ local_rot[..., j, :, :])
        off = offsets[..., j, :].unsqueeze(-1)
        p.append(p[par] + (g[par] @ off).squeeze(-1))
    return torch.stack(g, dim=-3), torch.stack(p, dim=-2)


class _WindowedAttentionBlock(nn.Module):
    """One pre-norm transformer block in which each frame attends to itself and the window - 1
    frames before it, with a learned bias per head and frame distance (no absolute positions, so
    every chunk of a stream is computed alike). Its memory between calls is its own input over
    the last window - 1 frames, from which it recomputes their keys and values."""

    def __init__(self, width: int, heads: int, ff: int, window: int):
        super().__init__()
        self.heads, self.window = heads, window
        self.norm1, self.norm2 = nn.LayerNorm(width), nn.LayerNorm(width)
        self.qkv = nn.Linear(width, 3 * width)
        self.proj = nn.Linear(width, width)
        self.ff = nn.Sequential(nn.Linear(width, ff), nn.ReLU(), nn.Linear(ff, width))
        self.distance_bias = nn.Parameter(torch.zeros(heads, window))

    def forward(self, x, memory, dropout: float):
        """x (B,S,D), memory (B,window-1,D) -> (B,S,D), the new memory."""
        b, s, d = x.shape
        w, past, heads = self.window, self.window - 1, self.heads
        dh = d // heads
        full = torch.cat([memory, x], dim=1)                                # (B, past+S, D)
        q, k, v = self.qkv(self.norm1(full)).chunk(3, dim=-1)
        # Queries in blocks of `window` frames, each block against the 2 * window - 1 frames that
        # any of its queries can see: half the work of queries x all keys for training windows,
        # and linear in the chunk length instead of quadratic.
        n = -(-s // w)
        pad = n * w - s
        q = nn.functional.pad(q[:, past:] * dh ** -0.5, (0, 0, 0, pad))
        k, v = (nn.functional.pad(t, (0, 0, 0, pad)) for t in (k, v))
        q = q.reshape(b, n, w, heads, dh).permute(0, 3, 1, 2, 4)             # (B,h,n,w,dh)
        k, v = (t.reshape(b, past + n * w, heads, dh).permute(0, 2, 1, 3)
                .unfold(2, past + w, w) for t in (k, v))                    # (B,h,n,dh,past+w)
        scores = q @ k + self._bias()                                        # (B,h,n,w,past+w)
        y = torch.softmax(scores, dim=-1) @ v.transpose(-1, -2)             # (B,h,n,w,dh)
        y = y.permute(0, 2, 3, 1, 4).reshape(b, n * w, d)[:, :s]
        x = x + nn.functional.dropout(self.proj(y), dropout, dropout > 0)
        x = x + nn.functional.dropout(self.ff(self.norm2(x)), dropout, dropout > 0)
        return x, full[:, full.shape[1] - past:]

    def _bias(self):
        """(h, window, 2 * window - 1): query r of a block sees key c at distance window - 1 + r - c,
        only distances 0 .. window - 1 (itself and the frames before it)."""
        w = self.window
        distance = (torch.arange(w, device=self.distance_bias.device)[:, None] + w - 1
                    - torch.arange(2 * w - 1, device=self.distance_bias.device)[None, :])
        visible = (distance >= 0) & (distance < w)
        bias = self.distance_bias[:, distance.clamp(0, w - 1)]
        return bias.masked_fill(~visible, float("-inf")).unsqueeze(1)        # (h,1,w,2w-1)


class WindowedTransformerCore(nn.Module):
    """The TIP-class core (ModelConfig.core "transformer"): causal windowed self-attention blocks,
    a layer norm, then a tanh RNN. Its state is (memory [blocks * (window - 1), B, embed], rnn [layers, B,
    hidden]), shaped like the LSTM's so that the training loop's per-stream reset applies
    unchanged, and a call with T frames equals T calls with one. Stacked, the blocks see
    blocks * (window - 1) frames back. Long inputs go through in chunks, so attention costs
    chunk x (chunk + window) per block instead of T x T."""

    CHUNK = 256

    def __init__(self, c: ModelConfig):
        super().__init__()
        check_attention_dims(c.embed, c.heads, c.window)
        self.past = c.window - 1
        self.blocks = nn.ModuleList(_WindowedAttentionBlock(c.embed, c.heads, c.ff, c.window)
                                    for _ in range(c.blocks))
        # The blocks' residual sum grows with training (RMS ~14 after 1,000 steps without this),
        # which saturated the tanh RNN: 98 % of its outputs beyond 0.95. TIP's encoder (post-norm)
        # ends normalised too.
        self.norm = nn.LayerNorm(c.embed)
        self.rnn = nn.RNN(c.embed, c.hidden, num_layers=c.layers, nonlinearity="tanh", batch_first=True)

    def zero_state(self, c: ModelConfig, batch: int, device=None) -> tuple:
        return (torch.zeros((c.blocks * self.past, batch, c.embed), device=device),
                torch.zeros((c.layers, batch, c.hidden), device=device))

    def forward(self, x, state, dropout: float):
        memory, h = state
        memories = list(memory.permute(1, 0, 2).split(self.past, dim=1))
        outputs = []
        for start in range(0, x.shape[1], self.CHUNK):
            y = x[:, start:start + self.CHUNK]
            for i, block in enumerate(self.blocks):
                y, memories[i] = block(y, memories[i], dropout)
            outputs.append(y)
        y, h = self.rnn(self.norm(torch.cat(outputs, dim=1)), h)
        return y, (torch.cat(memories, dim=1).permute(1, 0, 2), h)


# ----------------------------------------------------------------------------- network
class PoseNet(nn.Module):
    """Streaming IMU -> pose network. See the module docstring."""

    def __init__(self, config: ModelConfig | None = None):
        super().__init__()
        self.config = replace(config) if config else ModelConfig()   # own copy: set_dropout edits it
        c = self.config
        c.sensors = check_sensors(c.sensors)
        c.optional = check_optional(c.sensors, c.optional, c.masked)
        self.pelvis = c.sensors.index(PELVIS)
        self.others = [i for i in range(len(c.sensors)) if i != self.pelvis]
        self.embed = nn.Sequential(
            nn.Linear(feature_size(len(c.sensors), c.masked), c.embed), nn.ReLU(),
            nn.Linear(c.embed, c.embed), nn.ReLU())
        if c.core == "transformer":
            self.core = WindowedTransformerCore(c)
        else:
            self.lstm = nn.LSTM(c.embed, c.hidden, num_layers=c.layers, batch_first=True,
                                dropout=c.dropout if c.layers > 1 else 0.0)
        self.head = nn.Sequential(nn.Linear(c.hidden, c.head), nn.ReLU(),
                                  nn.Linear(c.head, OUTPUT_SIZE))
        # Small last layer: an untrained model outputs roughly the rest pose with the measured
        # pelvis orientation, zero velocity and 50 % contact.
        with torch.no_grad():
            self.head[-1].weight.mul_(0.01)
            self.head[-1].bias.zero_()
        self.register_buffer("identity3", torch.eye(3), persistent=False)
        # what each joint's predicted columns are residuals on: the measured pelvis for joint 0
        # (pelvis_only picks it), the rest pose for the others
        rest = torch.eye(3)[:, :2].repeat(NUM_JOINTS, 1, 1)
        rest[0] = 0.0
        self.register_buffer("rest_columns", rest, persistent=False)
        pelvis_only = torch.zeros(NUM_JOINTS, 1, 1)
        pelvis_only[0] = 1.0
        self.register_buffer("pelvis_only", pelvis_only, persistent=False)

    @property
    def required_flags(self) -> list:
        """1 for each required sensor, 0 for each optional one (input order)."""
        return [0 if n in self.config.optional else 1 for n in self.config.sensors]

    def full_mask(self, ori: torch.Tensor) -> torch.Tensor:
        """Every sensor present: ones (B,T,N) for inputs (B,T,N,3,3)."""
        return torch.ones(ori.shape[:3], dtype=ori.dtype, device=ori.device)

    def set_dropout(self, p: float) -> None:
        """Dropout has no weights, so a warm start can change it."""
        self.config.dropout = float(p)
        if self.config.core == "lstm":
            self.lstm.dropout = float(p) if self.config.layers > 1 else 0.0

    def enable_anchoring(self) -> None:
        """Switches a non-anchored network to anchored outputs (a warm start): the output rows of
        the sensor bones are zeroed, so it starts from the measured orientations of those bones."""
        if self.config.anchored:
            return
        self.config.anchored = True
        self._zero_output_rows([j for j in self.anchor_joints if j != 0])

    def anchor_wrists_on_forearm(self) -> None:
        """Moves a hand-anchored network's wrist anchoring to the forearm (a warm start): the
        forearm rows become residuals on the wrist sensors and the wrist rows absolute local
        rotations, both starting from zero (forearm = measured, wrist at rest)."""
        if not self.config.anchored or self.config.wrist_anchor == "forearm":
            self.config.wrist_anchor = "forearm"
            return
        self.config.wrist_anchor = "forearm"
        hand = se.sensor_bones("hand", self.config.sensors)
        forearm = se.sensor_bones("forearm", self.config.sensors)
        self._zero_output_rows(sorted({j for a, b in zip(hand, forearm) if a != b for j in (a, b)}))

    def _zero_output_rows(self, joints) -> None:
        last = self.head[-1]
        with torch.no_grad():
            for j in joints:
                last.weight[j * 6:(j + 1) * 6].zero_()
                last.bias[j * 6:(j + 1) * 6].zero_()

    @property
    def anchor_joints(self) -> list:
        """The joint whose local rotation is anchored on each sensor (input order): its bone
        (sensors.sensor_bones), by where the wrist sensors are (config.wrist_anchor)."""
        return se.sensor_bones(self.config.wrist_anchor, self.config.sensors)

    @property
    def state_layers(self) -> int:
        return self.config.layers

    @property
    def state_size(self) -> int:
        return self.config.hidden

    def zero_state(self, batch: int, device=None) -> tuple:
        if self.config.core == "transformer":
            return self.core.zero_state(self.config, batch, device)
        shape = (self.config.layers, batch, self.config.hidden)
        z = torch.zeros(shape, device=device)
        return z, z.clone()

    def features(self, ori: torch.Tensor, acc: torch.Tensor, mask: torch.Tensor | None = None) -> tuple:
        """ori (B,T,N,3,3), acc (B,T,N,3) (and for a masked network mask (B,T,N)) -> (features
        (B,T,feature_size), Ry (B,T,3,3), the N orientations in the heading frame (B,T,N,3,3)).

        A masked network reads a missing sensor as identity orientation and zero acceleration (so
        the heading and the relative rotations stay rotations), zeroes its feature blocks (so its
        placeholder says nothing) and appends the mask."""
        p = self.pelvis
        if self.config.masked:
            m4 = mask.unsqueeze(-1)                                # (B,T,N,1)
            m5 = m4.unsqueeze(-1)                                  # (B,T,N,1,1)
            ori = ori * m5 + self.identity3 * (1.0 - m5)
            acc = acc * m4
        r0 = ori[:, :, p]
        ry = heading_rotation(r0)
        rg = ry.transpose(-1, -2).unsqueeze(2) @ ori               # Ry^T R_i (B,T,N,3,3)
        ag = acc @ ry                                              # rows: Ry^T a_i (B,T,N,3)
        rrel = r0.transpose(-1, -2).unsqueeze(2) @ _index(ori, 2, self.others)
        arel = (_index(acc, 2, self.others) - acc[:, :, p:p + 1]) @ r0
        blocks = [rg, ag / ACC_SCALE, rrel, arel / ACC_SCALE]
        if self.config.masked:
            m_rel = (_index(mask, 2, self.others) * mask[:, :, p:p + 1])[..., None]   # both ends
            blocks = [rg * m5, blocks[1] * m4, rrel * m_rel[..., None], blocks[3] * m_rel]
        feat = [_reshape_tail(x, 2, (-1,)) for x in blocks]
        if self.config.masked:
            feat.append(mask)
        return torch.cat(feat, dim=-1), ry, rg

    def _anchor_sensor_bones(self, rot, cols, rg, mask=None) -> tuple:
        """Re-predicts the local rotation of each non-pelvis sensor bone as a residual on the one
        its sensor measures: parent_global^T * sensor_orientation, the parent's global rotation
        from forward kinematics of the predicted ancestors (heading frame). A network with a zero
        residual reproduces the measured bone orientation exactly; training learns how far to
        trust it (calibration error) against the rest of the body. rot (B,T,24,3,3) the
        network's rotations, cols (B,T,24,3,2) its residual columns. Returns (the anchored bones'
        two columns before Gram-Schmidt (B,T,K,3,2), their K joints). Every bone is handled in one
        batch and the kinematics run a level of the tree at a time (a few dozen operators once
        exported)."""
        plan = _anchor_plan(tuple(self.anchor_joints))
        if not plan.sensors:
            return None, []
        levels = [rot[:, :, 0:1]]
        # every level's local rotations taken out in one gather and one split
        local = _index(rot, 2, [j for joints, _ in plan.levels for j in joints])
        local = torch.split(local, [len(joints) for joints, _ in plan.levels], dim=2)
        for (joints, parents), rot_local in zip(plan.levels, local):
            above = levels[-1]
            if above.shape[2] != 1 and parents != list(range(above.shape[2])):
                above = _index(above, 2, parents)
            levels.append(above @ rot_local)
        parent_global = _index(torch.cat(levels, dim=2), 2, plan.parent_at)
        measured = parent_global.transpose(-1, -2) @ _index(rg, 2, plan.sensors)[..., 0:2]
        if mask is not None:   # a missing sensor measures nothing: its bone is a residual on the rest pose
            present = _index(mask, 2, plan.sensors)[..., None, None]
            measured = measured * present + self.identity3[:, :2] * (1.0 - present)
        return _index(cols, 2, plan.joints) + measured, plan.joints

    def _checked_mask(self, ori, mask):
        """The mask a masked network runs with (all present when None); a ValueError for a mask
        given to a network without the mask input, or of the wrong shape."""
        if not self.config.masked:
            if mask is not None:
                raise ValueError("this network has no mask input (ModelConfig.masked is false): every "
                                 "sensor must be present")
            return None
        if mask is None:
            return self.full_mask(ori)
        if tuple(mask.shape) != tuple(ori.shape[:3]):
            raise ValueError(f"imu_mask must be (B,T,N) = {tuple(ori.shape[:3])}, got {tuple(mask.shape)}")
        return mask.to(ori.dtype)

    def forward_raw(self, ori, acc, state=None, mask=None):
        """Returns (joint_rotations, root_velocity, contact_logits, (h, c)). mask (B,T,N): a
        masked network's present sensors (None: all)."""
        columns, vel, logits, st = self.forward_columns(ori, acc, state, mask)
        return gram_schmidt(columns), vel, logits, st

    def forward_columns(self, ori, acc, state=None, mask=None):
        """forward_raw before the last Gram-Schmidt: (the first two columns of every joint's
        rotation (B,T,24,3,2), not yet orthonormal, root_velocity, contact_logits, (h, c))."""
        b = ori.shape[0]
        mask = self._checked_mask(ori, mask)
        feat, ry, rg = self.features(ori, acc, mask)
        p = self.config.dropout if self.training else 0.0
        x = self.embed(feat)
        if p > 0:
            x = torch.nn.functional.dropout(x, p, True)
        if state is None:
            state = self.zero_state(b, ori.device)
        if self.config.core == "transformer":
            y, (h, c) = self.core(x, (state[0], state[1]), p)
        else:
            y, (h, c) = self.lstm(x, (state[0], state[1]))
        if p > 0:
            y = torch.nn.functional.dropout(y, p, True)
        out = self.head(y)
        cols = _reshape_tail(out[..., _COLUMN_ORDER], 2, (NUM_JOINTS, 3, 2))
        base = self.rest_columns + rg[:, :, self.pelvis:self.pelvis + 1, :, 0:2] * self.pelvis_only
        columns = cols + base
        # the output is gathered from [network columns, anchored bones, pelvis rotated back out
        # of the heading frame] in one operation; Gram-Schmidt commutes with the rotation by Ry
        pieces, order = [columns], list(range(NUM_JOINTS))
        if self.config.anchored:
            anchored, joints = self._anchor_sensor_bones(gram_schmidt(columns), cols, rg, mask)
            if joints:
                pieces.append(anchored)
                for i, j in enumerate(joints):
                    order[j] = NUM_JOINTS + i
        order[0] = sum(x.shape[2] for x in pieces)
        pieces.append(ry.unsqueeze(2) @ columns[:, :, 0:1])
        columns = _index(torch.cat(pieces, dim=2), 2, order)
        vel_h = out[..., NUM_JOINTS * 6:NUM_JOINTS * 6 + 3]
        vel = (ry @ vel_h.unsqueeze(-1)).squeeze(-1)
        logits = out[..., NUM_JOINTS * 6 + 3:NUM_JOINTS * 6 + 5]
        return columns, vel, logits, (h, c)

    def forward(self, imu_orientation, imu_acceleration, state=None, imu_mask=None):
        """Contract forward: (joint_rotations, root_velocity, foot_contact (0..1), (h, c));
        imu_mask only for a masked network (None: every sensor present)."""
        rot, vel, logits, st = self.forward_raw(imu_orientation, imu_acceleration, state, imu_mask)
        return rot, vel, torch.sigmoid(logits), st


class MirrorEnsemble(nn.Module):
    """The shipped inference: a PoseNet run twice per frame, on the inputs and on their mirror
    image (reflected in the sagittal plane, left and right sensors swapped), the second answer
    mirrored back and the two averaged (each joint's two predicted columns scaled to unit length,
    summed, then one Gram-Schmidt; velocity and contact probabilities averaged). Training uses
    mirrored clips half the time, so both answers are valid estimates with partly independent
    errors: on the validation subjects the average cut the third training run's errors from 9.66
    to 9.42 deg and from 6.95 to 6.77 cm (averaging the orthonormalised rotations; the unit
    columns give the same figures to 0.01 on the shipped weights, one Gram-Schmidt fewer per
    frame). The result is exactly mirror-equivariant; a frame costs ~1.4x (the weights are read
    once).

    Same interface as PoseNet. Both branches run as one batch of 2B, so the state stays one
    pair of tensors: [L, B, 2H], the plain branch's H values then the mirrored branch's."""

    def __init__(self, net: PoseNet):
        super().__init__()
        self.net = net
        # each sensor's left/right counterpart in the network's own list
        self.mirror_sensors = se.mirror_indices(net.config.sensors)
        # reflecting in the sagittal plane: M R M for a rotation, a M for a vector (M = diag(-1, 1, 1)),
        # written as sign flips
        axis = torch.tensor([-1.0, 1.0, 1.0])
        self.register_buffer("reflect_vector", axis, persistent=False)
        self.register_buffer("reflect_rotation", axis[:, None] * axis[None, :], persistent=False)

    @property
    def config(self) -> ModelConfig:
        return self.net.config

    @property
    def state_layers(self) -> int:
        return self.net.state_layers

    @property
    def state_size(self) -> int:
        return 2 * self.net.state_size

    def zero_state(self, batch: int, device=None) -> tuple:
        return tuple(torch.cat([s, s], dim=-1) for s in self.net.zero_state(batch, device))

    def forward(self, imu_orientation, imu_acceleration, state=None, imu_mask=None):
        mirror = self.mirror_sensors
        ori = torch.cat([imu_orientation, imu_orientation[:, :, mirror] * self.reflect_rotation], dim=0)
        acc = torch.cat([imu_acceleration, imu_acceleration[:, :, mirror] * self.reflect_vector], dim=0)
        if state is None:
            state = self.zero_state(imu_orientation.shape[0], imu_orientation.device)
        inner = tuple(torch.cat(_halves(s, -1), dim=1) for s in state)
        mask = self.net._checked_mask(imu_orientation, imu_mask)
        if mask is not None:   # the mirror image's left sensor is the right one: its mask too
            mask = torch.cat([mask, mask[:, :, mirror]], dim=0)
        cols, vel, logits, (h, c) = self.net.forward_columns(ori, acc, inner, mask)
        contact = torch.sigmoid(logits)
        cols, back = _halves(_unit(cols, -2), 0)
        back = back[:, :, MIRROR_JOINTS] * self.reflect_rotation[:, :2]
        rot = gram_schmidt(cols + back)
        vel, vel_back = _halves(vel, 0)
        vel = 0.5 * (vel + vel_back * self.reflect_vector)
        contact, contact_back = _halves(contact, 0)
        contact = 0.5 * (contact + contact_back.flip(-1))
        h = torch.cat(_halves(h, 1), dim=-1)
        c = torch.cat(_halves(c, 1), dim=-1)
        return rot, vel, contact, (h, c)


class ExportWrapper(nn.Module):
    """Flat signature of the ONNX contract: 4 inputs, 5 outputs."""

    def __init__(self, net: PoseNet):
        super().__init__()
        self.net = net

    def forward(self, imu_orientation, imu_acceleration, state_in_h, state_in_c):
        rot, vel, contact, (h, c) = self.net(imu_orientation, imu_acceleration,
                                             (state_in_h, state_in_c))
        return rot, vel, contact, h, c


class NetworkOnly(nn.Module):
    """The learned part of a PoseNet or MirrorEnsemble alone (model contract 3): features (R,T,F)
    and LSTM state (L,R,H) -> the head's numbers (R,T,149) and the new state, every geometric
    step (heading, features, residuals, anchoring, mirror average, Gram-Schmidt) left to the
    engine (Native~/src/pose/network_geometry.c). The head's last layer is reordered so its
    first 144 numbers are already each joint's columns laid out (joint, row, column)."""

    def __init__(self, net):
        super().__init__()
        inner = net.net if isinstance(net, MirrorEnsemble) else net
        if inner.config.core != "lstm":
            raise ValueError("only an LSTM network has the state the contract carries")
        self.embed = inner.embed
        self.lstm = inner.lstm
        last = inner.head[-1]
        order = _COLUMN_ORDER + list(range(NUM_JOINTS * 6, OUTPUT_SIZE))
        reordered = nn.Linear(last.in_features, last.out_features)
        with torch.no_grad():
            reordered.weight.copy_(last.weight[order])
            reordered.bias.copy_(last.bias[order])
        self.head = nn.Sequential(*list(inner.head)[:-1], reordered)

    def forward(self, network_input, state_in_h, state_in_c):
        y, (h, c) = self.lstm(self.embed(network_input), (state_in_h, state_in_c))
        return self.head(y), h, c


class MaskedExportWrapper(nn.Module):
    """Flat signature of model contract 2: the mask is the third input."""

    def __init__(self, net: PoseNet):
        super().__init__()
        self.net = net

    def forward(self, imu_orientation, imu_acceleration, imu_mask, state_in_h, state_in_c):
        rot, vel, contact, (h, c) = self.net(imu_orientation, imu_acceleration,
                                             (state_in_h, state_in_c), imu_mask)
        return rot, vel, contact, h, c


def with_sensors(net: PoseNet, sensors, optional=(), masked: bool = True) -> PoseNet:
    """A new PoseNet reading `sensors` (with these optional ones, masked or not) that starts from
    net's weights, for a warm start on another sensor set: every weight is copied, and the first
    layer's input columns are matched by what they read (feature_labels), so the columns of a
    new sensor and of the mask start at zero and those of a sensor left out are dropped. A
    contract-1 network widened this way gives its own answer while the new sensors are missing
    (mask 0) and the others present. ValueError for a list the network cannot take."""
    config = replace(net.config, sensors=check_sensors(sensors), optional=tuple(optional or ()),
                     masked=bool(masked))
    out = PoseNet(config).to(next(net.parameters()).device)
    src = net.state_dict()
    dst = out.state_dict()
    old_cols = {label: i for i, label in enumerate(feature_labels(net.config.sensors, net.config.masked))}
    key = "embed.0.weight"
    first = torch.zeros_like(dst[key])
    for i, label in enumerate(feature_labels(config.sensors, config.masked)):
        if label in old_cols:
            first[:, i] = src[key][:, old_cols[label]]
    for k, v in src.items():
        if k == key:
            continue
        if k not in dst or dst[k].shape != v.shape:
            raise ValueError(f"weight {k} does not carry over to the network of sensors "
                             f"{','.join(config.sensors)}")
        dst[k] = v.clone()
    dst[key] = first
    out.load_state_dict(dst)
    return out.train(net.training)


def count_parameters(net: nn.Module) -> int:
    return sum(p.numel() for p in net.parameters())


def non_finite_tensors(state: dict) -> str:
    """The names of the floating-point tensors of a state dict that hold NaN or inf, for a
    message ("a, b, c, ..."; "" when all are finite): weights that make every output NaN,
    whatever the input."""
    bad = [k for k, v in state.items()
           if torch.is_tensor(v) and v.is_floating_point() and not bool(torch.isfinite(v).all())]
    return ", ".join(bad[:3]) + (", ..." if len(bad) > 3 else "")
