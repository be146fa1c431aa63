"""Training of PoseNet on synthesised IMU data (owner: model).

    python3 -m training train [--budget-minutes 60] [--resume] [--device auto|cpu|cuda] [--smoke]
                              [--data-workers N] [--bvh DIR|PACK --val-bvh DIR|PACK]

Data: motions from dataset.load_motions (train split; val split for model selection), or a BVH
folder (--bvh), or procedural motions (--smoke). IMU signals are synthesised on the fly with
augmentation (synthesis.py; a few ms per clip, negligible next to a training step).

Streams and state (truncated back-propagation through time, "stateful" training): the batch is
B independent streams. Each stream plays one augmented clip window after window (W frames per
step) and carries the LSTM state from one window to the next (detached), exactly as the engine
streams; the state is zeroed only when a stream starts a new clip (half of the time at the clip
start, otherwise at a random frame). So the network is trained both for a cold start (zero state,
as at the start of every engine session) and for long runs with a warm state; a plain
"zero state at every random window" scheme would only ever see states at most W frames old.

Missing sensors (a masked network, model contract 2: --sensors, --optional, --sensor-dropout): each
clip a stream plays lacks each optional sensor with probability --optional-absent, and with
probability --sensor-dropout one present non-pelvis sensor goes silent for a window of
--dropout-seconds; a missing sensor has mask 0 and zero inputs, as the engine feeds a sensor it
has nothing of (SensorMasking; a silent one the engine now stands in for instead).

Losses per frame: rotation (Frobenius distance of the 24 matrices, local, joint 0 global: the
chordal distance 2 sqrt(2) sin(angle / 2), which grows like the angle the metric averages; the
squared distance of earlier runs pulls ambiguous joints to the mean of their possible poses),
joint positions (mean distance of root-relative joints after forward kinematics of the
predicted rotations on the sample's own skeleton), root velocity (MSE, m/s), root drift
(displacement error accumulated over 1 s inside the window), foot contact (BCE on logits).

Schedule: Adam, warm-up then cosine decay over a step count fixed at the start (measured speed
x budget, or --steps) so resumed runs continue the same schedule. --resume needs last.pt and
continues with the options saved in it (resume_config: only budget, steps, --stop-after, device
and the output folders may change; a contradicting option is refused, the network is never
switched over again). A checkpoint holds the random generators, the streams' clips and positions
and the LSTM state they carry, so a run stopped with --stop-after N and resumed takes the same
steps as one that never stopped (on the same device, with a budget that does not cut the
schedule short). Seeded; fp32 on CPU and CUDA (TF32 disabled). Checkpoints in training/data/checkpoints
(last.pt, best.pt by validation loss), log training/results/train_log.json, curves
training/results/loss.png.
"""
from __future__ import annotations

import json
import math
import os
import signal
import sys
import threading
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F

from . import skeleton as sk
from .cli import NON_NEGATIVE, NON_NEGATIVE_INT, POSITIVE, POSITIVE_INT, number_pair_type, number_type
from .errors import CommandError, UsageError
from .files import atomic_torch_save
from .model import (PELVIS, ModelConfig, PoseNet, check_optional, check_sensors, count_parameters,
                    forward_kinematics_torch, non_finite_tensors, with_sensors)
from .rarity import clip_rarity
from .sensors import DEFAULT_SENSORS
from .synthesis import Augmentation, synthesize, vary_motion

REPO = Path(__file__).resolve().parents[1]
CKPT_DIR = REPO / "training" / "data" / "checkpoints"
RESULTS_DIR = REPO / "training" / "results"

SIZES = {"tiny": ModelConfig(32, 32, 1, 32), "small": ModelConfig(256, 256, 2, 256), "medium": ModelConfig(256, 384, 2, 256),
         "large": ModelConfig(256, 512, 2, 256),
         # The seed system's TIP class, for the architecture comparison: its core (4 causal
         # attention blocks of 16 heads, feed-forward 1024, 40-frame window, then a tanh RNN of
         # 512) between this project's frame MLP and heads. Not exportable to the engine.
         "tip": ModelConfig(256, 512, 1, 256, core="transformer", window=40, blocks=4, heads=16, ff=1024)}


@dataclass
class TrainConfig:
    budget_minutes: float = 60.0
    steps: int | None = None          # total optimiser steps (None: from measured speed x budget)
    stop_after: int | None = None     # stop (checkpointed) after this step; --resume goes on
    batch: int = 32
    window: int = 120                 # frames per step per stream (2 s)
    lr: float = 1e-3
    warmup: int = 200
    seed: int = 0
    device: str = "auto"
    size: str = "medium"
    w_rot: float = 1.0
    w_pos: float = 10.0
    w_vel: float = 1.0
    w_drift: float = 2.0
    w_contact: float = 0.5
    arm_swap: float = 0.0             # Augmentation.arm_swap / arm_jitter_deg (motion variety)
    arm_jitter_deg: float = 0.0
    spine_jitter_deg: float = 0.0
    trunk_swap: float = 0.0
    body_scale: tuple = (0.9, 1.1)    # Augmentation.scale: each clip's body U(a, b) x its size
    rare_boost: float = 0.0           # clips drawn by length x rarity^rare_boost (rarity.py)
    rot_loss: str = "chordal"         # "chordal": Frobenius distance per joint (~ angle, like the
                                      # metric); "squared": its square (punishes outliers more)
    dropout: float | None = 0.1       # PoseNet dropout in training (None: the checkpoint's own)
    anchored: bool = True             # sensor bones as residuals on their measured orientations
    wrist_sensor: str = "hand"        # where the wrist sensors are: "hand" or "forearm" (straps)
    # The network's sensors (segment names; None: the default six, or the --init-from network's),
    # which of them are optional (None: none, or the --init-from network's), and whether it takes
    # the mask of model contract 2 (forced by optional sensors or sensor dropout, and kept by a
    # masked --init-from network).
    sensors: tuple | None = None
    optional: tuple | None = None
    masked: bool = False
    optional_absent: float = 0.5      # probability that a clip lacks each optional sensor
    sensor_dropout: float = 0.0       # probability that a clip loses one sensor for a window
    dropout_seconds: tuple = (0.5, 5.0)   # that window's length U(a, b), seconds
    drift_frames: int = 60
    eval_every_s: float = 180.0
    ckpt_every_s: float = 120.0
    val_clips: int = 40
    val_max_frames: int = 1800
    max_clips: int | None = None      # use only the first N training clips (quick runs)
    data_workers: int = 0             # processes synthesising the batches (0: this one; ParallelBatcher)
    train_source: str = "train"       # split name or BVH folder
    val_source: str | None = "val"   # split name or BVH folder; None: a share of train_source
                                      # held out (holdout_validation)
    smoke: bool = False
    resume: bool = False
    init_from: str | None = None      # start from these weights (fresh optimizer and schedule)
    ckpt_dir: str = str(CKPT_DIR)
    results_dir: str = str(RESULTS_DIR)
    progress: bool = True


# ------------------------------------------------------------------------------ environment
def _blas_is_openblas() -> bool:
    try:
        with open("/proc/self/maps") as f:
            return "openblas" in f.read().lower()
    except OSError:
        return False


def setup_threads() -> str:
    """OpenBLAS threads its own GEMMs: torch's intra-op threads on top oversubscribe the cores
    (measured 2.4x slower on 2 cores). The reference BLAS is single-threaded: give torch all."""
    if _blas_is_openblas():
        torch.set_num_threads(1)
        return "openblas"
    torch.set_num_threads(os.cpu_count() or 1)
    return "reference-or-other"


def pick_device(name: str) -> torch.device:
    if name == "auto":
        name = "cuda" if torch.cuda.is_available() else "cpu"
    dev = torch.device(name)
    if dev.type == "cuda":
        torch.backends.cuda.matmul.allow_tf32 = False
        torch.backends.cudnn.allow_tf32 = False
    return dev


# ------------------------------------------------------------------------------ data
# The engine holds a sensor that stops sending for its stale_after_s (mocap_session_config,
# default 0.25 s: mask 1, the last sample repeated). Training then feeds it as missing; the engine
# now feeds a stand-in instead (solver.c, stand_in_silent_sensors), which served the one model
# trained this way better than the mask, though training cannot reproduce it (it needs the
# network's own previous pose).
ENGINE_STALE_AFTER_S = 0.25


@dataclass(frozen=True)
class SensorMasking:
    """Which sensors a masked network's training clips lack, drawn per clip: each optional sensor
    is absent from the whole clip with probability optional_absent; with probability
    window_probability one present non-pelvis sensor stops sending for a window of
    U(window_seconds) s, first held (ENGINE_STALE_AFTER_S) and then missing. Missing frames have
    mask 0 and zero inputs, as the engine feeds a sensor it has nothing of."""
    sensors: tuple
    optional: tuple = ()
    optional_absent: float = 0.5
    window_probability: float = 0.0
    window_seconds: tuple = (0.5, 5.0)

    def apply(self, sample, rng: np.random.Generator) -> tuple:
        """(the sample as the engine would feed it, its mask (T,N) float32)."""
        from dataclasses import replace as replace_fields
        T, fps = sample.num_frames, sample.fps
        mask = np.ones((T, len(self.sensors)), np.float32)
        ori, acc = sample.imu_orientation.copy(), sample.imu_acceleration.copy()
        for k, name in enumerate(self.sensors):
            if name in self.optional and rng.random() < self.optional_absent:
                mask[:, k] = 0.0
        if self.window_probability > 0 and rng.random() < self.window_probability:
            present = [k for k, name in enumerate(self.sensors) if name != PELVIS and mask[0, k] > 0]
            if present:
                k = present[int(rng.integers(len(present)))]
                length = max(1, int(round(rng.uniform(*self.window_seconds) * fps)))
                start = int(rng.integers(0, max(1, T - length + 1)))
                stop = min(T, start + length)
                held = min(stop, start + int(round(ENGINE_STALE_AFTER_S * fps))) if start > 0 else start
                ori[start:held, k] = ori[start - 1, k]
                acc[start:held, k] = acc[start - 1, k]
                mask[held:stop, k] = 0.0
        ori *= mask[..., None, None]
        acc *= mask[..., None]
        return replace_fields(sample, imu_orientation=ori, imu_acceleration=acc), mask


class StreamBatcher:
    """B streams, each playing an augmented clip window by window (see module docstring)."""

    def __init__(self, motions, batch: int, window: int, rng: np.random.Generator,
                 augment: Augmentation | None = Augmentation(), wrist: str = "hand",
                 rare_boost: float = 0.0, sensors=DEFAULT_SENSORS, masking: SensorMasking | None = None):
        self.motions = [m for m in motions if m.num_frames >= window + 1]
        if not self.motions:
            raise UsageError(f"no training clip has more than {window} frames (60 Hz)")
        lengths = np.array([m.num_frames for m in self.motions], dtype=np.float64)
        # Clips are drawn by length, or with rare poses more often (rarity.py; --rare-boost).
        self.rarity = clip_rarity(self.motions) if rare_boost > 0 else np.ones(len(lengths))
        weights = lengths * self.rarity ** rare_boost
        self.p = weights / weights.sum()
        self.total_frames = int(lengths.sum())
        self.batch, self.window, self.rng, self.augment = batch, window, rng, augment
        self.wrist, self.sensors = wrist, tuple(sensors)
        # A masked network's batches carry "imu_mask" (B,W,N); an unmasked one's are unchanged.
        self.masking = masking
        self.samples = [None] * batch
        self.masks = [None] * batch
        self.pos = [0] * batch

    def state_dict(self) -> dict:
        """What the streams are playing and where: with the numpy generator's state, enough for a
        resumed run to draw exactly the batches the uninterrupted run would have drawn."""
        return {"samples": list(self.samples), "pos": list(self.pos), "masks": list(self.masks)}

    def load_state_dict(self, state: dict) -> None:
        if len(state["samples"]) != self.batch:
            raise UsageError(f"the checkpoint's batcher has {len(state['samples'])} streams, not {self.batch}")
        self.samples, self.pos = list(state["samples"]), [int(p) for p in state["pos"]]
        self.masks = list(state.get("masks") or [None] * self.batch)

    def close(self) -> None:
        """Nothing to release (ParallelBatcher's counterpart stops its workers)."""

    def _new(self, i: int) -> None:
        while True:   # a sped-up short clip can end up shorter than a window: draw again
            m = self.motions[int(self.rng.choice(len(self.motions), p=self.p))]
            m = vary_motion(m, self.rng, self.augment, self.motions)   # donors are >= a window too
            s = synthesize(m, self.rng, self.augment, wrist=self.wrist, sensors=self.sensors)
            if s.num_frames >= self.window:
                break
        if self.masking is not None:
            s, self.masks[i] = self.masking.apply(s, self.rng)
        self.samples[i] = s
        span = s.num_frames - self.window
        self.pos[i] = 0 if (span <= 0 or self.rng.random() < 0.5) else int(self.rng.integers(0, span + 1))

    def next(self) -> tuple:
        reset = np.zeros(self.batch, dtype=bool)
        keys = ("imu_orientation", "imu_acceleration", "local_rot", "root_velocity", "foot_contact")
        out = {k: [] for k in keys}
        offsets, masks = [], []
        W = self.window
        for i in range(self.batch):
            if self.samples[i] is None or self.pos[i] + W > self.samples[i].num_frames:
                self._new(i)
                reset[i] = True
            s, a = self.samples[i], self.pos[i]
            for k in keys:
                out[k].append(getattr(s, k)[a:a + W])
            offsets.append(s.offsets)
            if self.masking is not None:
                mask = self.masks[i]
                masks.append(mask[a:a + W] if mask is not None else np.ones((W, len(self.sensors)), np.float32))
            self.pos[i] = a + W
        batch = {k: torch.from_numpy(np.stack(v)) for k, v in out.items()}
        batch["offsets"] = torch.from_numpy(np.stack(offsets))
        if self.masking is not None:
            batch["imu_mask"] = torch.from_numpy(np.stack(masks))
        return batch, torch.from_numpy(reset)


class ParallelBatcher:
    """The streams of a StreamBatcher played by worker processes, for a GPU that one core cannot
    feed (synthesis: ~35 k frames/s per core). Worker k plays its own share of the streams with
    its own generator (seed, k) and the batch joins the shares in worker order, so the batches
    depend on the seed and the worker count, never on timing. A checkpoint holds no stream state
    for them: a resumed run starts its streams afresh (not step for step the same run).

    Batches travel through shared memory, not pipes: each worker owns SLOTS buffers made before
    it is forked, fills a free one and sends only its number; this process copies the shares out
    and hands the buffer back. (Pickling the 36 MB of a 256-stream batch through pipes cost this
    process 140-490 ms per batch on the 2-core machine; copying from shared memory ~2 ms.)"""

    SLOTS = 3

    def __init__(self, base: StreamBatcher, workers: int, seed: int):
        import copy
        import multiprocessing as mp
        self.motions, self.rarity, self.p = base.motions, base.rarity, base.p
        self.total_frames, self.batch, self.window = base.total_frames, base.batch, base.window
        workers = max(1, min(workers, base.batch))
        shares = [base.batch // workers + (1 if k < base.batch % workers else 0) for k in range(workers)]
        # one stream's batch, for the buffers' shapes and types
        probe = copy.copy(base)
        probe.batch, probe.rng, probe.samples, probe.pos = 1, np.random.default_rng(seed), [None], [0]
        probe.masks = [None]
        one, one_reset = probe.next()
        one["reset"] = one_reset
        need = self.SLOTS * sum(v.element_size() * v.numel() for v in one.values()) * base.batch
        _require_shared_memory(need)
        ctx = mp.get_context("fork")   # the workers share the motions and buffers with this process
        self.slots, self.ready, self.free, self.procs = [], [], [], []
        for k, n in enumerate(shares):
            slots = [{key: torch.empty((n,) + tuple(v.shape[1:]), dtype=v.dtype).share_memory_()
                      for key, v in one.items()} for _ in range(self.SLOTS)]
            ready, ready_end = ctx.Pipe(duplex=False)   # worker -> here: numbers of filled slots
            free_end, free = ctx.Pipe(duplex=False)     # here -> worker: numbers of emptied slots
            proc = ctx.Process(target=_play_streams, args=(base, n, seed, k, slots, ready_end, free_end),
                               daemon=True, name=f"train-data-{k}")
            proc.start()
            # Only worker k holds the write end of its `ready` pipe (this process's copy is closed
            # before the next worker is forked): a worker that dies then leaves an end of file
            # here, not a read that waits forever.
            ready_end.close()
            free_end.close()
            self.slots.append(slots)
            self.ready.append(ready)
            self.free.append(free)
            self.procs.append(proc)
        # Two sets of batch tensors, used in turn and allocated once: a fresh 36 MB batch each
        # step cost ~100 ms of page faults here, copying into these ~2 ms. Pinned (page-locked)
        # where a GPU will read them. Made after the forks: pinning starts CUDA in this process.
        pin = torch.cuda.is_available()
        self.out = [{key: torch.empty((base.batch,) + tuple(v.shape[1:]), dtype=v.dtype, pin_memory=pin)
                     for key, v in one.items()} for _ in range(2)]
        self.turn = 0

    def state_dict(self):
        return None

    def load_state_dict(self, state) -> None:
        pass

    def _take(self, k: int) -> int:
        got = None
        try:
            while not self.ready[k].poll(5.0):
                if not self.procs[k].is_alive() and not self.ready[k].poll(0):
                    raise EOFError
            got = self.ready[k].recv()
        except (EOFError, OSError):
            pass
        if got is None:
            self.procs[k].join(timeout=5.0)
            raise CommandError(f"training data worker {k} stopped (exit code {self.procs[k].exitcode}; "
                               f"out of memory?)")
        if isinstance(got, str):
            raise CommandError(f"training data worker {k} failed: {got}")
        return got

    def next(self) -> tuple:
        """The next batch, as StreamBatcher.next gives it. Its tensors are this batcher's own and
        are overwritten by the call after the next one: use them (or copy them) before that."""
        taken = [self._take(k) for k in range(len(self.procs))]
        parts = [self.slots[k][j] for k, j in enumerate(taken)]
        out = self.out[self.turn]
        self.turn = 1 - self.turn
        for key, dest in out.items():
            torch.cat([part[key] for part in parts], out=dest)
        for k, j in enumerate(taken):
            try:
                self.free[k].send(j)
            except OSError:   # the worker is gone: its next batch reports it
                pass
        batch = dict(out)
        return batch, batch.pop("reset")

    def close(self) -> None:
        for proc in self.procs:
            if proc.is_alive():
                proc.terminate()
        for proc in self.procs:
            proc.join(timeout=5.0)
        for conn in self.ready + self.free:
            conn.close()


def _require_shared_memory(need: int, where: str = "/dev/shm") -> None:
    """A UsageError unless `where` (the tmpfs that shared tensors live in) has room for `need`
    bytes: a full one would kill a worker with SIGBUS half way through a batch instead."""
    try:
        st = os.statvfs(where)
    except OSError:
        return   # no such tmpfs: the platform shares memory another way
    free = st.f_bavail * st.f_frsize
    if free < 1.25 * need:
        raise UsageError(f"--data-workers needs {need / 1e6:.0f} MB of shared memory for its batch "
                         f"buffers, {where} has {free / 1e6:.0f} MB free (fewer --batch streams, or a "
                         f"larger {where}: docker run --shm-size)")


def _play_streams(base: StreamBatcher, streams: int, seed: int, k: int, slots, ready, free) -> None:
    """Worker of ParallelBatcher: its share of the streams, batch after batch, into the shared
    buffers `slots`; the pipe `ready` takes the numbers of filled ones, `free` gives back emptied
    ones."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # Ctrl-C is the main process's to handle
    torch.set_num_threads(1)
    base.batch, base.rng = streams, np.random.default_rng([seed, k])
    base.samples, base.pos, base.masks = [None] * streams, [0] * streams, [None] * streams
    own = list(range(len(slots)))
    parent = os.getppid()
    try:
        while True:
            batch, reset = base.next()
            while not own and not free.poll(5.0):
                if os.getppid() != parent:   # the training process is gone: so is the point
                    return
            j = own.pop() if own else free.recv()
            for key, v in batch.items():
                slots[j][key].copy_(v)
            slots[j]["reset"].copy_(reset)
            ready.send(j)
    except (EOFError, BrokenPipeError):   # the training process closed its ends
        return
    except Exception as e:   # the main process reports it and stops
        ready.send(f"{type(e).__name__}: {e}")


def sensor_masking(cfg: TrainConfig, net_config: ModelConfig) -> SensorMasking | None:
    """What a network's training clips lack (None for a network without the mask)."""
    if not net_config.masked:
        return None
    return SensorMasking(net_config.sensors, net_config.optional, cfg.optional_absent, cfg.sensor_dropout,
                         tuple(cfg.dropout_seconds))


def make_batcher(motions, cfg: TrainConfig, rng: np.random.Generator, sensors=DEFAULT_SENSORS,
                 masking: SensorMasking | None = None):
    """sensors: the network's (ModelConfig.sensors), synthesised in its order; masking: what a
    masked network's clips lack (sensor_masking)."""
    base = StreamBatcher(motions, cfg.batch, cfg.window, rng,
                         Augmentation(scale=tuple(cfg.body_scale), arm_swap=cfg.arm_swap,
                                      arm_jitter_deg=cfg.arm_jitter_deg,
                                      spine_jitter_deg=cfg.spine_jitter_deg, trunk_swap=cfg.trunk_swap),
                         wrist=cfg.wrist_sensor, rare_boost=cfg.rare_boost, sensors=sensors, masking=masking)
    return ParallelBatcher(base, cfg.data_workers, cfg.seed) if cfg.data_workers > 0 else base


def rarity_summary(batcher: StreamBatcher) -> str:
    """What the boost does to the draw: the rarest tenth of the frames, by clip, before and after."""
    lengths = np.array([m.num_frames for m in batcher.motions], np.float64)
    order = np.argsort(-batcher.rarity)
    rare = order[:max(1, int(np.searchsorted(np.cumsum(lengths[order]), 0.1 * lengths.sum())) + 1)]
    return (f"the clips with the rarest {100 * lengths[rare].sum() / lengths.sum():.0f} % of the frames "
            f"get {100 * batcher.p[rare].sum():.0f} % of the draws; rarity "
            f"{batcher.rarity.min():.2f} to {batcher.rarity.max():.2f}")


def _procedural_motions(n: int, seconds: float, seed: int) -> list:
    from . import procedural
    kinds = procedural.KINDS
    return [procedural.make_motion(kinds[i % len(kinds)], seconds=seconds, seed=seed + i,
                                   name=f"proc_{i}") for i in range(n)]


def load_data(cfg: TrainConfig) -> tuple:
    if cfg.smoke:
        return _procedural_motions(5, 4.0, cfg.seed), _procedural_motions(2, 4.0, cfg.seed + 100)
    from . import dataset
    train = dataset.load_motions(cfg.train_source, progress=cfg.progress)
    if cfg.val_source is None:
        train, val, how = holdout_validation(train)
        print(f"train: validation on {how} of {cfg.train_source}, held out of training "
              f"({len(train)} training clips)")
    else:
        val = dataset.load_motions(cfg.val_source, progress=cfg.progress)
    if cfg.max_clips:
        rng = np.random.default_rng(cfg.seed)
        idx = rng.permutation(len(train))[:cfg.max_clips]
        train = [train[i] for i in sorted(idx)]
    return train, val


VAL_SHARE = 0.1


def _spread(n: int, share: float) -> list:
    """Evenly spaced indices of about share * n of n items (at least one, never all)."""
    k = min(max(1, round(n * share)), n - 1)
    return sorted({int((i + 0.5) * n / k) for i in range(k)})


def holdout_validation(motions, share: float = VAL_SHARE) -> tuple:
    """(training motions, validation motions, description) of one folder's clips, deterministic.
    By subject when every clip has a subject number (a manifest, or CMU-style NN_MM file names)
    and there are two or more: the CMU rule of dataset.split_of (canonical subject % 10 == 1;
    the test subjects stay in training: this is a validation split only), or where that holds out
    no subject or every subject, every 10th subject in number order. Otherwise by clip: every
    10th clip in folder order. At least one clip stays in training; a single clip has no
    validation."""
    motions = list(motions)
    if len(motions) < 2:
        return motions, [], "no clips (fewer than 2 in the folder)"
    subjects = sorted({int(m.subject) for m in motions})
    if len(subjects) >= 2 and all(int(m.subject) > 0 for m in motions):
        from .dataset import split_of
        held = [s for s in subjects if split_of(s) == "val"]
        rule = "CMU validation subjects"
        if not held or len(held) == len(subjects):
            held = [subjects[i] for i in _spread(len(subjects), share)]
            rule = "every 10th subject"
        val = [m for m in motions if int(m.subject) in held]
        train = [m for m in motions if int(m.subject) not in held]
        return train, val, f"{len(val)} clips of subjects {', '.join(map(str, held))} ({rule})"
    idx = set(_spread(len(motions), share))
    val = [m for i, m in enumerate(motions) if i in idx]
    train = [m for i, m in enumerate(motions) if i not in idx]
    return train, val, (f"{len(val)} clips ({', '.join(m.name for m in val)}; every 10th clip: the "
                        f"file names carry no subject numbers)")


def check_finite_motions(motions, what: str) -> None:
    """A UsageError naming the first clip with NaN or inf values: one such clip makes the loss,
    and after one step every weight, NaN."""
    for m in motions:
        field_name = m.non_finite_field()
        if field_name:
            raise UsageError(f"{what} clip {m.name}: its {field_name} holds NaN or inf values "
                             f"(a damaged source file?); remove or repair it")


# Faster than any sprinter's pelvis (~12 m/s at the peak): a root that moves this fast between two
# frames is a capture glitch (a few CMU clips jump by up to 1.2 m in one frame), and its velocity
# would be a huge outlier in the root-velocity loss.
MAX_ROOT_SPEED = 12.0   # m/s


def without_root_jumps(motions) -> tuple:
    """(the motions whose root never moves faster than MAX_ROOT_SPEED, the names of the others)."""
    kept, dropped = [], []
    for m in motions:
        speed = np.linalg.norm(np.diff(np.asarray(m.root_pos, np.float64), axis=0), axis=-1) * m.fps
        (dropped if speed.size and speed.max() > MAX_ROOT_SPEED else kept).append(m)
    return kept, [m.name for m in dropped]


# Faster than any limb: a hand at the end of a punch or a throw reaches 10-15 m/s, and 30 cm in one
# 60 Hz frame is 18 m/s. A joint that jumps further is a marker swap or a dropped marker in the
# source capture (a few dozen CMU training clips have such frames, some dance and martial arts).
MAX_JOINT_STEP_M = 0.30   # per 1/60 s
MIN_PIECE_S = 2.0         # pieces of a cut clip shorter than this are left out


def joint_jumps(motion) -> np.ndarray:
    """Indices i of the frame steps i -> i+1 in which some joint (world position) moves further
    than MAX_JOINT_STEP_M per 1/60 s."""
    _, pos = sk.forward_kinematics(np.asarray(motion.local_rot, np.float64),
                                   np.asarray(motion.root_pos, np.float64),
                                   np.asarray(motion.offsets, np.float64))
    step = np.linalg.norm(np.diff(pos, axis=0), axis=-1).max(axis=-1) * (motion.fps / 60.0)
    return np.nonzero(step > MAX_JOINT_STEP_M)[0]


def cut_at_joint_jumps(motions) -> tuple:
    """(the motions with every clip that has joint jumps cut into the pieces between them,
    pieces shorter than MIN_PIECE_S left out; the names of the clips cut; frames left out)."""
    out, cut, lost = [], [], 0
    for m in motions:
        jumps = joint_jumps(m)
        if len(jumps) == 0:
            out.append(m)
            continue
        cut.append(m.name)
        edges = [0] + [int(i) + 1 for i in jumps] + [m.num_frames]
        kept = 0
        for k, (a, b) in enumerate(zip(edges[:-1], edges[1:])):
            if (b - a) / m.fps < MIN_PIECE_S:
                continue
            out.append(sk.Motion(f"{m.name}#{k}", m.subject, m.fps, m.local_rot[a:b], m.root_pos[a:b],
                                 m.offsets))
            kept += b - a
        lost += m.num_frames - kept
    return out, cut, lost


def validation_set(motions, cfg: TrainConfig, sensors=DEFAULT_SENSORS, optional=None) -> list:
    """Deterministic: evenly spaced clips, no augmentation, at most val_max_frames each, of the
    network's sensors. optional: a masked network's optional sensors (None: no mask): every
    second clip then lacks them (mask 0, zero inputs), so the best checkpoint serves both sets."""
    if len(motions) > cfg.val_clips:
        idx = np.linspace(0, len(motions) - 1, cfg.val_clips).round().astype(int)
        motions = [motions[i] for i in idx]
    out = []
    for i, m in enumerate(motions):
        s = synthesize(m, wrist=cfg.wrist_sensor, sensors=sensors)
        n = min(s.num_frames, cfg.val_max_frames)
        clip = ({k: torch.from_numpy(getattr(s, k)[:n][None]) for k in
                 ("imu_orientation", "imu_acceleration", "local_rot", "root_velocity", "foot_contact")}
                | {"offsets": torch.from_numpy(s.offsets[None])})
        if optional is not None:
            mask = torch.ones((1, n, len(sensors)))
            if i % 2:
                mask[..., [k for k, name in enumerate(sensors) if name in optional]] = 0.0
            clip["imu_mask"] = mask
            clip["imu_orientation"] = clip["imu_orientation"] * mask[..., None, None]
            clip["imu_acceleration"] = clip["imu_acceleration"] * mask[..., None]
        out.append(clip)
    return out


# ------------------------------------------------------------------------------ losses
def compute_losses(net_out, batch, cfg: TrainConfig) -> dict:
    rot, vel, logits = net_out
    tgt = batch["local_rot"]
    sq = ((rot - tgt) ** 2).sum((-1, -2))
    l_rot = torch.sqrt(sq + 1e-6).mean() if cfg.rot_loss == "chordal" else sq.mean()
    off = batch["offsets"][:, None]                                   # (B,1,24,3)
    _, p_pred = forward_kinematics_torch(rot, off, sk.PARENTS)
    _, p_true = forward_kinematics_torch(tgt, off, sk.PARENTS)
    l_pos = torch.sqrt(((p_pred - p_true) ** 2).sum(-1) + 1e-9).mean()
    dv = vel - batch["root_velocity"]
    l_vel = (dv ** 2).sum(-1).mean()
    n = cfg.drift_frames
    if dv.shape[1] > n:
        e = torch.cumsum(dv, dim=1) / sk.MODEL_FPS
        l_drift = torch.sqrt(((e[:, n:] - e[:, :-n]) ** 2).sum(-1) + 1e-9).mean()
    else:
        l_drift = torch.zeros((), device=dv.device)
    l_con = F.binary_cross_entropy_with_logits(logits, batch["foot_contact"])
    total = (cfg.w_rot * l_rot + cfg.w_pos * l_pos + cfg.w_vel * l_vel + cfg.w_drift * l_drift
             + cfg.w_contact * l_con)
    return {"loss": total, "rot": l_rot, "pos": l_pos, "vel": l_vel, "drift": l_drift, "contact": l_con}


@torch.no_grad()
def validate(net: PoseNet, val: list, cfg: TrainConfig, device) -> dict:
    net.eval()
    sums, n_frames = {}, 0
    ang_sum = pos_sum = con_acc = 0.0
    for v in val:
        b = {k: t.to(device) for k, t in v.items()}
        rot, vel, logits, _ = net.forward_raw(b["imu_orientation"], b["imu_acceleration"], None,
                                              b.get("imu_mask"))
        losses = compute_losses((rot, vel, logits), b, cfg)
        T = rot.shape[1]
        for k, x in losses.items():
            sums[k] = sums.get(k, 0.0) + float(x) * T
        rel = rot.transpose(-1, -2) @ b["local_rot"]
        tr = rel[..., 0, 0] + rel[..., 1, 1] + rel[..., 2, 2]
        ang = torch.rad2deg(torch.arccos(torch.clamp((tr - 1) / 2, -1.0, 1.0)))
        ang_sum += float(ang[..., 1:].mean()) * T
        off = b["offsets"][:, None]
        _, pp = forward_kinematics_torch(rot, off, sk.PARENTS)
        _, pt = forward_kinematics_torch(b["local_rot"], off, sk.PARENTS)
        pos_sum += float(torch.linalg.norm(pp - pt, dim=-1).mean()) * T
        con_acc += float(((logits > 0).float() == b["foot_contact"]).float().mean()) * T
        n_frames += T
    net.train()
    out = {f"val_{k}": s / n_frames for k, s in sums.items()}
    out.update({"val_angle_err_deg": ang_sum / n_frames, "val_pos_err_cm": 100 * pos_sum / n_frames,
                "val_contact_acc": con_acc / n_frames, "val_frames": n_frames})
    return out


# ------------------------------------------------------------------------------ loop
def _lr(step: int, total: int, cfg: TrainConfig, time_frac: float = 0.0) -> float:
    """Warm-up, then cosine decay to 5 %. The decay follows the step count, or the elapsed
    share of the budget when that is further along (a slower machine still anneals fully)."""
    warm = max(1, min(cfg.warmup, total // 10))
    if step < warm:
        return cfg.lr * (step + 1) / warm
    frac = min(1.0, max((step - warm) / max(1, total - warm), time_frac))
    return cfg.lr * (0.05 + 0.95 * 0.5 * (1 + math.cos(math.pi * frac)))


def _portable_paths(config: dict) -> dict:
    """Paths inside the repository as repository-relative, so a committed log names no machine."""
    out = dict(config)
    for key, value in config.items():
        if isinstance(value, str) and os.path.isabs(value):
            try:
                out[key] = str(Path(value).resolve().relative_to(REPO.resolve()))
            except ValueError:
                pass
    return out


def load_weights(path, device="cpu") -> PoseNet:
    """A PoseNet with the weights of a checkpoint (a training checkpoint or a weights-only one
    written by save_weights)."""
    return checkpoint_network(load_checkpoint_file(path, device), path, device)


def save_weights(src, dst) -> None:
    """Write the weights-only checkpoint of a training checkpoint (about a third of its size: no
    optimizer state), the form committed beside the shipped model."""
    ck = load_checkpoint_file(src)
    atomic_torch_save({"model": ck["model"], "config": ck["config"], "step": ck.get("step"),
                       "best": ck.get("best")}, dst)


def load_checkpoint_file(path, device="cpu") -> dict:
    """A checkpoint file's content; a missing or unreadable file is a UsageError naming it."""
    import pickle
    import zipfile
    if not Path(path).is_file():
        raise UsageError(f"{path}: no such checkpoint file")
    try:
        try:   # torch >= 2.6 defaults to weights_only=True; our checkpoints hold plain python too
            return torch.load(str(path), map_location=device, weights_only=False)
        except TypeError:
            return torch.load(str(path), map_location=device)
    except (pickle.UnpicklingError, EOFError, zipfile.BadZipFile, RuntimeError, UnicodeDecodeError) as e:
        raise UsageError(f"{path} is not a PyTorch checkpoint ({str(e).splitlines()[0] if str(e) else type(e).__name__})") from e


def require_pose_checkpoint(ck, path) -> None:
    """A UsageError naming the file unless ck is a pose model checkpoint: a dict with a "model"
    state dict and a "config"."""
    if not isinstance(ck, dict) or not isinstance(ck.get("model"), dict) or not isinstance(ck.get("config"), dict):
        raise UsageError(f"{path} is not a pose model checkpoint (no 'model' weights and 'config')")


def require_finite_weights(state: dict, path, use: str) -> None:
    """A UsageError naming the file when a state dict holds NaN or inf; `use`: what they spoil."""
    bad = non_finite_tensors(state)
    if bad:
        raise UsageError(f"{path}: the weights hold NaN or inf ({bad}); {use}")


def checkpoint_network(ck, path, device="cpu") -> PoseNet:
    """The PoseNet of a loaded checkpoint dict ("model" state dict + "config"), or a UsageError
    naming the file."""
    require_pose_checkpoint(ck, path)
    net = PoseNet(checkpoint_model_config(ck["config"], path)).to(device)
    try:
        net.load_state_dict(ck["model"])
    except RuntimeError as e:
        raise UsageError(f"{path}: the weights do not fit its network config ({str(e).splitlines()[0]})") from e
    require_finite_weights(net.state_dict(), path, "the network would output NaN")
    return net


def checkpoint_model_config(config: dict, path) -> ModelConfig:
    """The ModelConfig of a checkpoint's network config dict, or a UsageError naming the file."""
    try:
        return ModelConfig.from_dict(config)
    except (ValueError, TypeError, AttributeError) as e:
        raise UsageError(f"{path}: invalid network config ({e})") from e


def _save(path: Path, net, opt, step, total, cfg, history, best, rng, batcher, state) -> None:
    # The last line of defence: a NaN checkpoint would replace a good one and be exported.
    bad = non_finite_tensors(net.state_dict())
    if bad:
        raise CommandError(f"step {step}: the weights hold NaN or inf ({bad}); {path} "
                           f"not written (a learning rate that is too high?)")
    # The batcher's streams and the LSTM state they carry make a resumed run continue exactly
    # where this one stands (same batches, same recurrent state), not from fresh clips.
    atomic_torch_save({"model": net.state_dict(), "optimizer": opt.state_dict(), "step": step,
                       "total_steps": total, "config": net.config.to_dict(), "train_config": asdict(cfg),
                       "history": history, "best": best, "numpy_rng": rng.bit_generator.state,
                       "torch_rng": torch.get_rng_state(), "batcher": batcher.state_dict(),
                       "lstm_state": [t.detach().cpu() for t in state]}, path)


def plot_losses(history: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    tr, va = history.get("train", []), history.get("val", [])
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    if tr:
        st = [r["step"] for r in tr]
        for k in ("loss", "rot", "vel", "drift"):
            axes[0].plot(st, [r[k] for r in tr], label=f"train {k}")
    if va:
        st = [r["step"] for r in va]
        axes[0].plot(st, [r["val_loss"] for r in va], "k--o", label="val loss")
        axes[1].plot(st, [r["val_angle_err_deg"] for r in va], "o-", label="val angle err (deg)")
        axes[1].plot(st, [r["val_pos_err_cm"] for r in va], "s-", label="val position err (cm)")
        axes[2].plot(st, [r["val_contact_acc"] for r in va], "o-", label="val contact accuracy")
    axes[0].set_yscale("log")
    for a, t in zip(axes, ("losses", "validation errors", "contact")):
        a.set_xlabel("step"); a.set_title(t); a.legend(fontsize=8); a.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def network_sensors(cfg: TrainConfig, base: ModelConfig | None) -> tuple:
    """(sensors, optional, masked) of the network a run trains: what cfg asks for, else the
    --init-from network's own (base), else the default six without a mask. Optional sensors and
    sensor dropout need the mask, and a masked network stays masked. A UsageError for a list the
    network cannot take (no pelvis, an optional pelvis, an optional sensor not in the list)."""
    try:
        sensors = check_sensors(cfg.sensors) if cfg.sensors else (base.sensors if base else DEFAULT_SENSORS)
        if cfg.optional is not None:
            optional = tuple(cfg.optional)
        else:
            optional = tuple(n for n in (base.optional if base else ()) if n in sensors)
        masked = bool(cfg.masked or optional or cfg.sensor_dropout > 0 or (base is not None and base.masked))
        return sensors, check_optional(sensors, optional, masked), masked
    except ValueError as e:
        raise UsageError(f"--sensors / --optional: {e}") from None


def train(cfg: TrainConfig, motions=None, val_motions=None) -> dict:
    blas = setup_threads()
    if blas != "openblas" and not cfg.smoke:
        print("train: WARNING: torch is not using OpenBLAS (Debian's reference BLAS is ~10-20x "
              "slower here): apt-get install libopenblas0-pthread")
    device = pick_device(cfg.device)
    torch.manual_seed(cfg.seed)
    rng = np.random.default_rng(cfg.seed)
    ckpt_dir, results_dir = Path(cfg.ckpt_dir), Path(cfg.results_dir)
    ck = None
    if cfg.resume:   # before loading data: a wrong resume fails in a second
        last = ckpt_dir / "last.pt"
        if not last.is_file():
            raise UsageError(_nothing_to_resume(ckpt_dir))
        ck = load_checkpoint_file(last, device)
        check_resume_config(cfg, ck, last)
    if ck is None:   # a sensor list the network cannot take fails before the data is loaded
        base = None
        if cfg.init_from:
            warm = load_checkpoint_file(cfg.init_from)
            require_pose_checkpoint(warm, cfg.init_from)
            base = checkpoint_model_config(warm["config"], cfg.init_from)
        network_sensors(cfg, base)
    if motions is None:
        motions, val_motions = load_data(cfg)
    check_finite_motions(motions, "training")
    check_finite_motions(val_motions or [], "validation")
    motions, jumping = without_root_jumps(motions)
    if jumping:   # validation keeps every clip: it measures, it does not teach
        print(f"train: {len(jumping)} clips left out, their root jumps faster than {MAX_ROOT_SPEED:g} m/s "
              f"(capture glitches): {', '.join(jumping[:10])}{' ...' if len(jumping) > 10 else ''}")
        if not motions:
            raise UsageError("every training clip has root jumps; nothing left to train on")
    motions, cut, lost = cut_at_joint_jumps(motions)
    if cut:
        print(f"train: {len(cut)} clips cut where a joint jumps more than {100 * MAX_JOINT_STEP_M:g} cm "
              f"in one 60 Hz frame (capture glitches; {lost} frames left out): "
              f"{', '.join(cut[:10])}{' ...' if len(cut) > 10 else ''}")
        if not motions:
            raise UsageError("every training clip is cut to pieces under "
                             f"{MIN_PIECE_S:g} s by joint jumps; nothing left to train on")
    step, total, history, best = 0, cfg.steps, {"train": [], "val": []}, None
    if ck is not None:
        # The network exactly as saved: its anchoring, wrist placement and dropout are the run's
        # own (check_resume_config made sure cfg agrees); nothing is switched over again.
        net = checkpoint_network(ck, ckpt_dir / "last.pt", device)
        opt = torch.optim.Adam(net.parameters(), lr=cfg.lr)
        opt.load_state_dict(ck["optimizer"])
        step, history, best = ck["step"], ck["history"], ck["best"]
        total = cfg.steps if cfg.steps is not None else ck["total_steps"]
        rng.bit_generator.state = ck["numpy_rng"]
        torch.set_rng_state(ck["torch_rng"])
        print(f"train: resumed at step {step} of {total}")
    else:
        if cfg.init_from:
            # A warm start: the weights only (e.g. the shipped training/checkpoints/*.pt, which a
            # fresh machine has while training/data/checkpoints/ is gone), so a later run continues
            # from the shipped model on its own schedule instead of from scratch.
            net = load_weights(cfg.init_from, device)
            print(f"train: weights from {cfg.init_from}")
            sensors, optional, masked = network_sensors(cfg, net.config)
            if (sensors, optional, masked) != (net.config.sensors, net.config.optional, net.config.masked):
                # Another sensor set (e.g. the shipped six plus an optional chest): every weight
                # carries over, the new inputs start at zero (model.with_sensors).
                net = with_sensors(net, sensors, optional, masked)
                print(f"train: the network now reads {','.join(sensors)}"
                      + (f" (optional: {','.join(optional)})" if optional else "")
                      + (", with the sensor mask" if masked else ""))
        else:
            sensors, optional, masked = network_sensors(cfg, None)
            model_cfg = replace(SIZES[cfg.size], anchored=cfg.anchored, wrist_anchor=cfg.wrist_sensor,
                                sensors=sensors, optional=optional, masked=masked)
            net = PoseNet(model_cfg).to(device)
        opt = torch.optim.Adam(net.parameters(), lr=cfg.lr)
        if cfg.dropout is not None:
            net.set_dropout(cfg.dropout)
        if cfg.anchored:
            net.enable_anchoring()
        if net.config.wrist_anchor != cfg.wrist_sensor:
            if cfg.wrist_sensor != "forearm":
                raise UsageError(f"the weights read the wrist sensors as the {net.config.wrist_anchor}; "
                                 f"training them for the {cfg.wrist_sensor} is not supported")
            net.anchor_wrists_on_forearm()
            print("train: the wrist sensors move from the hands to the forearms (wrist straps)")
    batcher = make_batcher(motions, cfg, rng, net.config.sensors, sensor_masking(cfg, net.config))
    if cfg.rare_boost > 0:
        print(f"train: rare poses boosted ({rarity_summary(batcher)})")
    val = (validation_set(val_motions, cfg, net.config.sensors,
                          net.config.optional if net.config.masked else None) if val_motions else [])
    steps_per_epoch = max(1, math.ceil(batcher.total_frames / (cfg.batch * cfg.window)))
    print(f"train: {len(batcher.motions)} clips, {batcher.total_frames} frames "
          f"({steps_per_epoch} steps/epoch), {len(val)} val clips, device {device}, blas {blas}, "
          f"{count_parameters(net)} parameters")
    state = net.zero_state(cfg.batch, device)
    if ck is not None and ck.get("batcher") is not None:   # older or parallel runs: fresh streams
        batcher.load_state_dict(ck["batcher"])
        state = tuple(t.to(device) for t in ck["lstm_state"])
    t_start = time.time()
    budget_s = cfg.budget_minutes * 60.0
    last_eval = last_ckpt = time.time()
    acc, acc_n, t_log = {}, 0, time.time()
    step_times, data_times = [], []
    pbar = None
    if cfg.progress:
        from tqdm import tqdm
        # into a log file (not a terminal), one line every 30 s instead of ten a second
        pbar = tqdm(total=total, initial=step, desc="train", unit="step", dynamic_ncols=True,
                    mininterval=0.1 if sys.stderr.isatty() else 30.0)
    net.train()
    # Ctrl-C finishes the step under way and saves last.pt as of its end, so `--resume` goes on
    # exactly from there (a step interrupted half way would leave weights, optimizer and random
    # state out of step with each other); a second Ctrl-C stops at once.
    interrupted = []

    def on_interrupt(signum, frame):
        if interrupted:
            raise KeyboardInterrupt
        interrupted.append(step)
        print("\ntrain: Ctrl-C: finishing this step, then saving last.pt (Ctrl-C again to stop at "
              "once)", file=sys.stderr)
    in_main_thread = threading.current_thread() is threading.main_thread()
    previous_handler = signal.signal(signal.SIGINT, on_interrupt) if in_main_thread else None
    # A stopped run (non-finite loss, full disk) closes its progress bar first, so the error
    # line that follows stands on a line of its own.
    try:
        while True:
            if total is not None and step >= total:
                break
            if interrupted:
                break
            if cfg.stop_after is not None and step >= cfg.stop_after:
                print(f"train: stopped after step {step} (--stop-after); --resume continues the run")
                break
            if time.time() - t_start > budget_s:
                print("train: budget reached")
                break
            t0 = time.time()
            batch, reset = batcher.next()
            batch = {k: v.to(device) for k, v in batch.items()}
            data_times.append(time.time() - t0)
            keep = (~reset).to(device).float()[None, :, None]
            h, c = state[0] * keep, state[1] * keep
            for g in opt.param_groups:
                g["lr"] = _lr(step, total or 10 ** 9, cfg, (time.time() - t_start) / budget_s)
            rot, vel, logits, (h, c) = net.forward_raw(batch["imu_orientation"], batch["imu_acceleration"], (h, c),
                                                       batch.get("imu_mask"))
            state = (h.detach(), c.detach())
            losses = compute_losses((rot, vel, logits), batch, cfg)
            # Stop before a non-finite loss or gradient reaches the weights: one such step makes every
            # weight NaN, and the run would go on to save and select NaN checkpoints.
            if not math.isfinite(float(losses["loss"])):
                parts = ", ".join(f"{k} {float(v):.4g}" for k, v in losses.items() if k != "loss")
                cause = ("the weights became NaN or inf in the previous step (a learning rate that is too "
                         "high?)" if non_finite_tensors(net.state_dict()) else "likely a loss weight such as "
                         "--pos-weight that is not finite, or non-finite synthesised inputs")
                raise CommandError(f"step {step + 1}: the training loss is {float(losses['loss'])} ({parts}); "
                                   f"stopped, no checkpoint written at this step: {cause}")
            opt.zero_grad(set_to_none=True)
            losses["loss"].backward()
            grad_norm = float(torch.nn.utils.clip_grad_norm_(net.parameters(), 1.0))
            if not math.isfinite(grad_norm):
                raise CommandError(f"step {step + 1}: the gradient norm is {grad_norm} (loss "
                                   f"{float(losses['loss']):.4g}); stopped before the weights changed "
                                   f"(likely extreme values in a training clip, or a learning rate that is too high)")
            opt.step()
            step += 1
            step_times.append(time.time() - t0)
            for k, v in losses.items():
                acc[k] = acc.get(k, 0.0) + float(v)
            acc_n += 1
            if total is None and step == 20:
                # fix the schedule length from the measured speed (excluding the first steps)
                per = float(np.median(step_times[5:]))
                total = max(cfg.warmup + 1, int((budget_s - (time.time() - t_start)) / (per * 1.04)) + step)
                print(f"train: {per * 1000:.0f} ms/step -> schedule of {total} steps "
                      f"({total / steps_per_epoch:.1f} epochs)")
                if pbar is not None:
                    pbar.total = total
                    pbar.refresh()
            if pbar is not None:
                pbar.update(1)
                pbar.set_postfix(loss=f"{float(losses['loss']):.3f}", refresh=False)
            if acc_n >= 50 or (total is not None and step >= total):
                rec = {k: v / acc_n for k, v in acc.items()}
                rec.update(step=step, epoch=step / steps_per_epoch, lr=opt.param_groups[0]["lr"],
                           s_per_step=(time.time() - t_log) / acc_n, elapsed_s=time.time() - t_start)
                history["train"].append(rec)
                acc, acc_n, t_log = {}, 0, time.time()
            now = time.time()
            done = ((total is not None and step >= total) or now - t_start > budget_s
                    or (cfg.stop_after is not None and step >= cfg.stop_after))
            if val and (now - last_eval > cfg.eval_every_s or done):
                vr = validate(net, val, cfg, device)
                vr["step"] = step
                if not math.isfinite(vr["val_loss"]):
                    raise CommandError(f"step {step}: the validation loss is {vr['val_loss']} with finite "
                                       f"weights (non-finite synthesised validation inputs?); best.pt not written")
                history["val"].append(vr)
                last_eval = time.time()
                msg = f"val step {step}: loss {vr['val_loss']:.4f} angle {vr['val_angle_err_deg']:.2f} deg " \
                      f"pos {vr['val_pos_err_cm']:.2f} cm contact {vr['val_contact_acc']:.3f}"
                (pbar.write if pbar is not None else print)(msg)
                if best is None or vr["val_loss"] < best["val_loss"]:
                    best = dict(vr)
                    _save(ckpt_dir / "best.pt", net, opt, step, total, cfg, history, best, rng, batcher, state)
            if now - last_ckpt > cfg.ckpt_every_s:
                _save(ckpt_dir / "last.pt", net, opt, step, total, cfg, history, best, rng, batcher, state)
                last_ckpt = time.time()
    finally:
        if in_main_thread:
            signal.signal(signal.SIGINT, previous_handler)
        if pbar is not None:
            pbar.close()
        batcher.close()
    _save(ckpt_dir / "last.pt", net, opt, step, total, cfg, history, best, rng, batcher, state)
    if not val:
        _save(ckpt_dir / "best.pt", net, opt, step, total, cfg, history, best, rng, batcher, state)
    st = np.array(step_times[5:] or step_times)
    dt = np.array(data_times[5:] or data_times)
    summary = {"steps": step, "total_steps": total, "epochs": step / steps_per_epoch,
               "s_per_step_median": float(np.median(st)) if st.size else None,
               # waiting for the batch and moving it to the device: the rest of a step is compute
               "data_s_per_step_median": float(np.median(dt)) if dt.size else None,
               "frames_per_s": float(cfg.batch * cfg.window / np.median(st)) if st.size else None,
               "parameters": count_parameters(net), "device": str(device), "blas": blas,
               "train_clips": len(batcher.motions), "train_frames": batcher.total_frames,
               "best": best, "elapsed_s": time.time() - t_start}
    results_dir.mkdir(parents=True, exist_ok=True)
    log = {"summary": summary, "train_config": _portable_paths(asdict(cfg)),
           "model_config": net.config.to_dict(), "history": history}
    (results_dir / "train_log.json").write_text(json.dumps(log, indent=1))
    plot_losses(history, results_dir / "loss.png")
    print("train: " + json.dumps({k: v for k, v in summary.items() if k != "best"}))
    if interrupted:
        # Not a finished run: a script going on to `export` must not take it for one.
        raise CommandError(f"interrupted (Ctrl-C) after step {step}: {ckpt_dir / 'last.pt'} saved; "
                           f"--resume continues the run")
    return summary


# Options a resumed run may change when its command line gives them: how long it runs, on what,
# and where it writes. Every other option comes from the checkpoint (its saved train_config; the
# network's size, anchoring and wrist placement from its model config).
RESUME_OVERRIDES = ("budget_minutes", "steps", "stop_after", "device", "ckpt_dir", "results_dir", "progress",
                    "resume", "eval_every_s", "ckpt_every_s", "data_workers")
ARCHITECTURE = ("size", "anchored", "wrist_sensor", "sensors", "optional", "masked")
_OPTIONS = {"w_pos": "--pos-weight", "arm_jitter_deg": "--arm-jitter",
            "spine_jitter_deg": "--spine-jitter", "anchored": "--no-anchor",
            "train_source": "--bvh", "val_source": "--val-bvh"}
_PATH_OPTIONS = ("train_source", "val_source", "init_from", "ckpt_dir", "results_dir")


def _option(key: str) -> str:
    return _OPTIONS.get(key, "--" + key.replace("_", "-"))


def _size_dims(cfg: ModelConfig) -> tuple:
    dims = (cfg.core, cfg.embed, cfg.hidden, cfg.layers, cfg.head)
    return dims + ((cfg.window, cfg.blocks, cfg.heads, cfg.ff) if cfg.core == "transformer" else ())


def saved_train_config(ck, path="the checkpoint") -> TrainConfig:
    """The options a checkpoint was trained with: its train_config (unknown keys dropped, keys
    older checkpoints lack at their defaults), with size, anchoring and wrist placement read from
    the network's own config."""
    known = TrainConfig.__dataclass_fields__
    cfg = TrainConfig(**{k: v for k, v in (ck.get("train_config") or {}).items() if k in known})
    mc = checkpoint_model_config(ck["config"], path)
    cfg.anchored, cfg.wrist_sensor = bool(mc.anchored), mc.wrist_anchor
    cfg.sensors, cfg.optional, cfg.masked = mc.sensors, mc.optional, mc.masked
    cfg.size = next((n for n, c in SIZES.items() if _size_dims(c) == _size_dims(mc)), cfg.size)
    return cfg


def _same(key: str, a, b) -> bool:
    """Whether option `key` asks for the same as the checkpoint's (a: asked, b: saved)."""
    if key in ("sensors", "optional"):   # None: not asked, the network's own
        return a is None or b is None or tuple(a) == tuple(b)
    if key == "masked":   # not asking for the mask is no contradiction of a masked network
        return not a or bool(b)
    if key in ("dropout_seconds", "body_scale"):
        return tuple(a) == tuple(b)
    if key == "size":
        return a in SIZES and b in SIZES and _size_dims(SIZES[a]) == _size_dims(SIZES[b])
    if key in _PATH_OPTIONS and isinstance(a, str) and isinstance(b, str):
        from .dataset import SPLITS
        if a not in SPLITS and b not in SPLITS:
            return os.path.realpath(a) == os.path.realpath(b)
    return a == b


def _contradiction(key: str, new, old, path) -> str:
    if key == "anchored":
        new, old = ("anchored" if new else "not anchored (--no-anchor)"), ("anchored" if old else "not anchored")
    if key in ("sensors", "optional", "dropout_seconds"):   # as typed: a,b,c
        new, old = (",".join(map(str, v)) or "none" for v in (new, old))
    what = "network" if key in ARCHITECTURE else "training options"
    return (f"--resume: {_option(key)} {new} contradicts {path} ({old}); a resumed run keeps its "
            f"{what} (only --budget-minutes, --steps, --stop-after, --device, --ckpt-dir, --results-dir may "
            f"change; start a new run with --init-from {path} to change the rest)")


def _nothing_to_resume(ckpt_dir) -> str:
    return (f"--resume: no checkpoint to resume in {ckpt_dir} (no last.pt); run without --resume "
            f"to start a new run, or give the run's --ckpt-dir")


def check_resume_config(cfg: TrainConfig, ck, path) -> None:
    """A UsageError when cfg asks for anything the checkpoint's run did not (outside
    RESUME_OVERRIDES): another network, other anchoring or wrist placement, other training
    options or data."""
    saved = saved_train_config(ck, path)
    for key in TrainConfig.__dataclass_fields__:
        if key not in RESUME_OVERRIDES and not _same(key, getattr(cfg, key), getattr(saved, key)):
            raise UsageError(_contradiction(key, getattr(cfg, key), getattr(saved, key), path))


def resume_config(cfg: TrainConfig, explicit) -> TrainConfig:
    """The TrainConfig of `--resume`: the checkpoint's own options, with those of `explicit` (the
    fields the command line gave) that may change (RESUME_OVERRIDES) taken from cfg. An explicit
    option that contradicts the checkpoint, or a missing last.pt, is a UsageError."""
    last = Path(cfg.ckpt_dir) / "last.pt"
    if not last.is_file():
        raise UsageError(_nothing_to_resume(cfg.ckpt_dir))
    saved = saved_train_config(load_checkpoint_file(last), last)
    # stop_after belongs to one sitting: the saved one would stop the resumed run at once.
    out = replace(saved, resume=True, ckpt_dir=cfg.ckpt_dir, progress=cfg.progress, stop_after=None)
    for key in sorted(explicit):
        if key in RESUME_OVERRIDES:
            setattr(out, key, getattr(cfg, key))
        elif not _same(key, getattr(cfg, key), getattr(saved, key)):
            raise UsageError(_contradiction(key, getattr(cfg, key), getattr(saved, key), last))
    return out


def config_from_args(args) -> TrainConfig:
    """The TrainConfig a parsed command line asks for (unset options keep the defaults). With
    --resume: the checkpoint's saved options (resume_config), the command line changing only what
    may change."""
    cfg = TrainConfig()
    explicit = set()
    for k in ("budget_minutes", "steps", "stop_after", "batch", "window", "lr", "seed", "device", "size",
              "max_clips", "resume", "smoke", "init_from", "dropout", "rot_loss", "arm_swap",
              "arm_jitter_deg", "spine_jitter_deg", "trunk_swap", "rare_boost", "w_pos", "ckpt_dir",
              "results_dir", "wrist_sensor", "data_workers", "eval_every_s", "sensors", "optional",
              "masked", "optional_absent", "sensor_dropout", "dropout_seconds", "body_scale"):
        v = getattr(args, k, None)
        if v is not None and v is not False:
            setattr(cfg, k, v)
            explicit.add(k)
    if getattr(args, "no_anchor", False):
        cfg.anchored = False
        explicit.add("anchored")
    if getattr(args, "bvh", None):
        cfg.train_source = args.bvh
        explicit.add("train_source")
        # without --val-bvh: a held-out share of the folder (holdout_validation), not its own clips
        cfg.val_source = getattr(args, "val_bvh", None) or None
    if getattr(args, "val_bvh", None):
        cfg.val_source = args.val_bvh
        explicit.add("val_source")
    if "init_from" in explicit and "size" in explicit:
        # The weights bring their own network; a --size beside them would be silently ignored.
        raise UsageError("--init-from starts from the network those weights belong to (its size and "
                         "core); --size cannot be combined with it")
    if cfg.smoke:
        # --smoke trains on procedural motions: a data option would be ignored, while the log
        # recorded it as the run's data.
        given = [o for o, a in (("--bvh", "bvh"), ("--val-bvh", "val_bvh"), ("--max-clips", "max_clips"))
                 if getattr(args, a, None) is not None]
        if given:
            raise UsageError(f"--smoke trains on procedural motions and cannot be combined with "
                             f"{' '.join(given)} (for a short run on a folder: --size tiny --steps 30)")
        if getattr(args, "size", None) is None:
            cfg.size = "tiny"
        cfg.batch, cfg.window = min(cfg.batch, 4), min(cfg.window, 60)
        cfg.warmup = 5
        cfg.eval_every_s = 1e9
        if cfg.steps is None:
            cfg.steps = 30
        if "ckpt_dir" not in explicit:
            cfg.ckpt_dir = str(REPO / "training" / "data" / "smoke" / "checkpoints")
        if "results_dir" not in explicit:
            cfg.results_dir = str(REPO / "training" / "data" / "smoke" / "results")
    if cfg.resume:
        cfg = resume_config(cfg, explicit)
    return cfg


def main(args) -> int:
    train(config_from_args(args))
    return 0


PROBABILITY = number_type(float, lambda v: 0 <= v <= 1, "a probability in [0, 1]")
DROPOUT = number_type(float, lambda v: 0 <= v < 1, "a dropout rate in [0, 1)")


def _sensor_names(text: str) -> tuple:
    """--sensors: a sensor list (sensors.sensor_list), checked as the command line is read."""
    import argparse
    from .sensors import sensor_list
    try:
        return sensor_list(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _optional_names(text: str) -> tuple:
    """--optional: comma-separated segment names ("" or "none": no optional sensor); checked
    against the network's list when it is known (network_sensors)."""
    import argparse
    from .sensors import segment
    names = tuple(n.strip() for n in text.split(",") if n.strip() and n.strip() != "none")
    try:
        for n in names:
            segment(n)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    return names


# --dropout-seconds A,B: 0 < A <= B
_seconds_range = number_pair_type(lambda a, b: 0 < a <= b, "{text} is not two numbers A,B (seconds)",
                                  "{text}: expected 0 < A <= B seconds")
# --body-scale A,B: 0.5 <= A <= B <= 2 (times each clip's own size)
_scale_range = number_pair_type(lambda a, b: 0.5 <= a <= b <= 2.0,
                                "{text} is not two numbers A,B (body scales)",
                                "{text} is not A,B with 0.5 <= A <= B <= 2")


def add_arguments(parser) -> None:
    parser.add_argument("--budget-minutes", dest="budget_minutes", type=POSITIVE, default=None,
                        help="wall-clock budget (default 60)")
    parser.add_argument("--steps", type=POSITIVE_INT, default=None, help="total steps (default: from budget)")
    parser.add_argument("--stop-after", dest="stop_after", type=POSITIVE_INT, default=None,
                        help="stop after this step of the schedule, with a checkpoint; --resume "
                             "continues exactly where it stopped (a run split over sittings)")
    parser.add_argument("--resume", action="store_true",
                        help="continue the run in --ckpt-dir (its last.pt, which must exist) with its "
                             "own options; only --budget-minutes, --steps, --stop-after, --device, --ckpt-dir and "
                             "--results-dir may change")
    parser.add_argument("--init-from", dest="init_from", default=None,
                        help="start from these weights (e.g. training/checkpoints/mocap_pose.pt)")
    parser.add_argument("--device", default=None, choices=["auto", "cpu", "cuda"])
    parser.add_argument("--smoke", action="store_true", help="tiny procedural run (seconds)")
    parser.add_argument("--size", default=None, choices=sorted(SIZES), help="model size (default medium; tip: a network of the seed system's TIP class, causal windowed attention + RNN, for comparison only)")
    parser.add_argument("--eval-every", dest="eval_every_s", type=POSITIVE, default=None,
                        help="seconds between validations, each a chance to write best.pt (default 180)")
    parser.add_argument("--data-workers", dest="data_workers", type=NON_NEGATIVE_INT, default=None,
                        help="processes that synthesise the training batches (default 0: the training "
                             "process; a GPU needs several: about 35 k frames/s each)")
    parser.add_argument("--batch", type=POSITIVE_INT, default=None, help="streams per step (default 32)")
    parser.add_argument("--window", type=POSITIVE_INT, default=None, help="frames per step (default 120)")
    parser.add_argument("--lr", type=POSITIVE, default=None)
    parser.add_argument("--seed", type=NON_NEGATIVE_INT, default=None)
    parser.add_argument("--dropout", type=DROPOUT, default=None, help="dropout in training (default 0.1)")
    parser.add_argument("--no-anchor", dest="no_anchor", action="store_true",
                        help="predict the sensor bones like every other joint (runs 1-2)")
    parser.add_argument("--rot-loss", dest="rot_loss", default=None, choices=["chordal", "squared"],
                        help="rotation loss (default chordal)")
    parser.add_argument("--arm-swap", dest="arm_swap", type=PROBABILITY, default=None,
                        help="probability that a clip's arms move as in another clip (default 0)")
    parser.add_argument("--arm-jitter", dest="arm_jitter_deg", type=NON_NEGATIVE, default=None,
                        help="slow random shoulder offsets, per-axis sigma in degrees (default 0)")
    parser.add_argument("--trunk-swap", dest="trunk_swap", type=PROBABILITY, default=None,
                        help="probability that a clip's whole upper body (spine, neck, head, arms) "
                             "moves as in another clip (default 0)")
    parser.add_argument("--spine-jitter", dest="spine_jitter_deg", type=NON_NEGATIVE, default=None,
                        help="slow random offsets of the three spine joints, per-axis sigma in "
                             "degrees (default 0)")
    parser.add_argument("--body-scale", dest="body_scale", type=_scale_range, default=None,
                        help="each training clip's body (skeleton and root path) U(A, B) times its size "
                             "(default 0.9,1.1; users are 1.5-2.0 m, the CMU clips ~1.72 m)")
    parser.add_argument("--rare-boost", dest="rare_boost", type=NON_NEGATIVE, default=None,
                        help="draw clips by length x rarity^A of their poses (training/rarity.py): "
                             "rare motion more often (default 0: by length)")
    parser.add_argument("--wrist-sensor", dest="wrist_sensor", default=None, choices=["hand", "forearm"],
                        help="where the synthesised wrist sensors are: hand (back of the hands, the "
                             "default and the shipped model's) or forearm (wrist straps; a hand-trained "
                             "--init-from is switched over)")
    parser.add_argument("--sensors", type=_sensor_names, default=None,
                        help="the network's sensors, segment names in input order, e.g. "
                             "pelvis,left_wrist,right_wrist,left_shin,right_shin,head,chest (default: the "
                             "six of model contract 1, or the --init-from network's; new sensors of an "
                             "--init-from network start with zero weights)")
    parser.add_argument("--optional", type=_optional_names, default=None,
                        help="which of --sensors the network can do without, e.g. chest (a masked "
                             "network, exported as model contract 2; the pelvis cannot be optional)")
    parser.add_argument("--masked", action="store_true",
                        help="give the network the sensor mask input of model contract 2 (implied by "
                             "--optional and --sensor-dropout)")
    parser.add_argument("--optional-absent", dest="optional_absent", type=PROBABILITY, default=None,
                        help="probability that a training clip lacks each optional sensor (default 0.5)")
    parser.add_argument("--sensor-dropout", dest="sensor_dropout", type=PROBABILITY, default=None,
                        help="probability that a training clip loses one non-pelvis sensor for a "
                             "window (--dropout-seconds), as a sensor that stops sending (default 0)")
    parser.add_argument("--dropout-seconds", dest="dropout_seconds", type=_seconds_range, default=None,
                        help="length range A,B of a --sensor-dropout window in seconds (default 0.5,5)")
    parser.add_argument("--pos-weight", dest="w_pos", type=NON_NEGATIVE, default=None,
                        help="weight of the joint-position loss (metres) against the rotation "
                             "loss (default 10)")
    parser.add_argument("--ckpt-dir", dest="ckpt_dir", default=None,
                        help="checkpoint folder (default training/data/checkpoints)")
    parser.add_argument("--results-dir", dest="results_dir", default=None,
                        help="loss curve and log folder (default training/results)")
    parser.add_argument("--max-clips", dest="max_clips", type=POSITIVE_INT, default=None,
                        help="train on N of the training clips, drawn with --seed (quick runs)")
    parser.add_argument("--bvh", default=None, help="train on a BVH folder or a motion pack (training "
                        "pack) instead of the CMU split "
                        "(without --val-bvh, about 10 %% of its clips are held out for validation: "
                        "by subject where the names carry CMU subject numbers, else by clip)")
    parser.add_argument("--val-bvh", dest="val_bvh", default=None,
                        help="validation BVH folder or motion pack (default: a held-out share of --bvh)")
