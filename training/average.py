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

from pathlib import Path

import torch

from .model import ModelConfig
from .train import atomic_torch_save, load_checkpoint_file


def average_state_dicts(states: list, weights: list | None = None) -> dict:
    """The weighted mean of state dicts with the same keys and shapes. Integer tensors (counters)
    are taken from the first."""
    if not states:
        raise ValueError("average: no checkpoints given")
    weights = [1.0] * len(states) if weights is None else [float(w) for w in weights]
    if len(weights) != len(states):
        raise ValueError(f"average: {len(weights)} weights for {len(states)} checkpoints")
    if any(not w >= 0 for w in weights) or sum(weights) <= 0:
        raise ValueError("average: weights must be >= 0 with a positive sum")
    total = sum(weights)
    keys = list(states[0])
    for i, s in enumerate(states[1:], 1):
        if list(s) != keys:
            missing = sorted(set(keys) ^ set(s))
            raise ValueError(f"average: checkpoint {i} has different parameters ({missing[:3]}...)")
    out = {}
    for k in keys:
        first = states[0][k]
        for i, s in enumerate(states[1:], 1):
            if s[k].shape != first.shape:
                raise ValueError(f"average: {k} has shape {tuple(s[k].shape)} in checkpoint {i}, "
                                 f"{tuple(first.shape)} in checkpoint 0")
        if not first.is_floating_point():
            out[k] = first.clone()
            continue
        acc = torch.zeros_like(first, dtype=torch.float64)
        for w, s in zip(weights, states):
            acc += (w / total) * s[k].to(torch.float64)
        out[k] = acc.to(first.dtype)
    return out


def average_checkpoints(paths: list, out, weights: list | None = None) -> dict:
    """Average checkpoint files (training or weights-only) into a weights-only checkpoint."""
    cks = [load_checkpoint_file(p) for p in paths]
    config = cks[0]["config"]
    for p, ck in zip(paths[1:], cks[1:]):
        if _architecture(ck["config"]) != _architecture(config):
            raise ValueError(f"average: {p} is a different architecture from {paths[0]}")
    state = average_state_dicts([ck["model"] for ck in cks], weights)
    result = {"model": state, "config": config, "step": None, "best": None,
              "averaged_from": [str(p) for p in paths],
              "average_weights": list(weights) if weights else [1.0] * len(paths)}
    atomic_torch_save(result, Path(out))
    return result


def _architecture(config: dict) -> ModelConfig:
    """What must agree between averaged networks: the model config without dropout (training
    only; older configs without wrist_anchor read as "hand", as ModelConfig.from_dict does)."""
    cfg = ModelConfig.from_dict(config)
    cfg.dropout = 0.0
    return cfg


def main(args) -> int:
    try:
        average_checkpoints(args.checkpoints, args.out, args.weights)
    except (ValueError, KeyError, OSError) as e:
        print(f"average: {e}")
        return 1
    print(f"average: {len(args.checkpoints)} checkpoints -> {args.out}")
    return 0


def add_arguments(parser) -> None:
    parser.add_argument("checkpoints", nargs="+", help="checkpoints of one architecture")
    parser.add_argument("--out", required=True, help="weights-only checkpoint to write")
    parser.add_argument("--weights", nargs="+", type=float, default=None,
                        help="relative weight of each checkpoint (default: equal)")
