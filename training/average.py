"""Weight averaging of checkpoints of one network ("model soup", Wortsman et al. 2022).

    python3 -m training average A.pt B.pt [C.pt ...] --out SOUP.pt [--weights 1 1 ...]

Checkpoints fine-tuned from the same starting weights sit in one basin of the loss, so the mean
of their weights is itself a good network, often better than each: the averaging cancels part of
the noise that each run's last steps leave in the weights. The result is one network of the same
size and cost, written as a weights-only checkpoint (the form `export` and `evaluate` read).
Only checkpoints of the same architecture (identical model config apart from the training-only
dropout) can be averaged; the result keeps the first checkpoint's config.
"""
from __future__ import annotations

import math
from pathlib import Path

import torch

from .errors import UsageError
from .files import atomic_torch_save, same_file
from .model import ModelConfig
from .train import checkpoint_model_config, load_checkpoint_file, require_finite_weights, require_pose_checkpoint


def average_state_dicts(states: list, weights: list | None = None) -> dict:
    """The weighted mean of state dicts with the same keys and shapes. Integer tensors (counters)
    are taken from the first. Bad input is a UsageError (a ValueError)."""
    if not states:
        raise UsageError("no checkpoints given")
    weights = check_weights(weights, len(states))
    total = sum(weights)
    keys = list(states[0])
    for i, s in enumerate(states[1:], 1):
        if list(s) != keys:
            missing = sorted(set(keys) ^ set(s))
            raise UsageError(f"checkpoint {i} has different parameters ({missing[:3]}...)")
    out = {}
    for k in keys:
        first = states[0][k]
        for i, s in enumerate(states[1:], 1):
            if s[k].shape != first.shape:
                raise UsageError(f"{k} has shape {tuple(s[k].shape)} in checkpoint {i}, "
                                 f"{tuple(first.shape)} in checkpoint 0")
        if not first.is_floating_point():
            out[k] = first.clone()
            continue
        acc = torch.zeros_like(first, dtype=torch.float64)
        for w, s in zip(weights, states):
            acc += (w / total) * s[k].to(torch.float64)
        out[k] = acc.to(first.dtype)
    return out


def check_weights(weights, n: int) -> list:
    """The averaging weights as floats (default: equal), or a UsageError: one per checkpoint,
    each finite and >= 0, with a positive sum (an inf or NaN weight makes the soup NaN)."""
    weights = [1.0] * n if weights is None else [float(w) for w in weights]
    if len(weights) != n:
        raise UsageError(f"--weights: {len(weights)} weights for {n} checkpoints")
    if any(not (math.isfinite(w) and w >= 0) for w in weights) or sum(weights) <= 0:
        raise UsageError(f"--weights {' '.join(f'{w:g}' for w in weights)}: weights must be finite "
                         f"and >= 0 with a positive sum")
    return weights


def average_checkpoints(paths: list, out, weights: list | None = None) -> dict:
    """Average checkpoint files (training or weights-only) into a weights-only checkpoint. Bad
    input (files that do not fit together, non-finite weights, --out naming an input) is a
    UsageError naming the file."""
    weights = check_weights(weights, len(paths))
    for p in paths:
        # The soup is written over --out: an input there would be lost, replaced by the mean.
        if Path(out).exists() and Path(p).exists() and same_file(p, out):
            raise UsageError(f"--out {out} is one of the checkpoints to average ({p}); write the "
                             f"average to another file")
    cks = [load_checkpoint_file(p) for p in paths]
    for p, ck in zip(paths, cks):
        require_pose_checkpoint(ck, p)
        require_finite_weights(ck["model"], p, "the average would be NaN")
    config = cks[0]["config"]
    for p, ck in zip(paths[1:], cks[1:]):
        if _architecture(ck, p) != _architecture(cks[0], paths[0]):
            raise UsageError(f"{p} is a different architecture from {paths[0]}")
    state = average_state_dicts([ck["model"] for ck in cks], weights)
    result = {"model": state, "config": config, "step": None, "best": None,
              "averaged_from": [str(p) for p in paths],
              "average_weights": weights}
    atomic_torch_save(result, Path(out))
    return result


def _architecture(ck: dict, path) -> ModelConfig:
    """What must agree between averaged networks: the model config without dropout (training
    only; older configs without wrist_anchor read as "hand", as ModelConfig.from_dict does)."""
    cfg = checkpoint_model_config(ck["config"], path)
    cfg.dropout = 0.0
    return cfg


def main(args) -> int:
    # Bad input raises UsageError, a failed write CommandError: python3 -m training prints them as
    # one line on stderr with exit status 1.
    average_checkpoints(args.checkpoints, args.out, args.weights)
    print(f"average: {len(args.checkpoints)} checkpoints -> {args.out}")
    return 0


def add_arguments(parser) -> None:
    parser.add_argument("checkpoints", nargs="+", help="checkpoints of one architecture")
    parser.add_argument("--out", required=True, help="weights-only checkpoint to write")
    parser.add_argument("--weights", nargs="+", type=float, default=None,
                        help="relative weight of each checkpoint (default: equal)")
