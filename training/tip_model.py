"""tip-model: an ONNX network with the shape of TIP (the seed system's model), random weights, for
the speed comparison of `mocapctl bench tip`.

    python3 -m training tip-model --out FILE.onnx [--window 40] [--seed 0]

Shape (field-notes.md, "TIP's exact interface"): per frame 221 input values -> linear 221->256 ->
causal TransformerEncoder (4 layers, 16 heads, feed-forward 1024, d_model 256) -> 1-layer tanh RNN
512 -> linear 512->131. About 3.7 M parameters. The exported graph takes one fixed window
`input` [1, W, 221] and returns `output` [1, W, 131] (W = 40 by default): TIP re-runs the whole
window for every output frame, and the benchmark does the same. The weights are random: this
file measures cost only and is not TIP (TIP's weights are CC-BY-NC and never used here).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

IN_FEATURES = 221
OUT_FEATURES = 131
D_MODEL = 256
HEADS = 16
LAYERS = 4
FEED_FORWARD = 1024
RNN_SIZE = 512


def build(window: int = 40, seed: int = 0):
    import torch
    from torch import nn

    class TipShaped(nn.Module):
        def __init__(self):
            super().__init__()
            self.embed = nn.Linear(IN_FEATURES, D_MODEL)
            layer = nn.TransformerEncoderLayer(D_MODEL, HEADS, FEED_FORWARD, dropout=0.0,
                                               batch_first=True)
            self.encoder = nn.TransformerEncoder(layer, LAYERS)
            self.rnn = nn.RNN(D_MODEL, RNN_SIZE, num_layers=1, nonlinearity="tanh", batch_first=True)
            self.head = nn.Linear(RNN_SIZE, OUT_FEATURES)
            mask = torch.triu(torch.full((window, window), float("-inf")), diagonal=1)
            self.register_buffer("causal_mask", mask)

        def forward(self, x):
            h = self.encoder(self.embed(x), mask=self.causal_mask)
            h, _ = self.rnn(h)
            return self.head(h)

    torch.manual_seed(seed)
    net = TipShaped().eval()
    return net


def export(out, window: int = 40, seed: int = 0) -> dict:
    import torch
    net = build(window, seed)
    params = sum(p.numel() for p in net.parameters())
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    x = torch.randn(1, window, IN_FEATURES)
    import warnings
    with torch.no_grad(), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # torch's notes about RNN batch sizes / constant shapes
        torch.onnx.export(net, (x,), str(out), input_names=["input"], output_names=["output"],
                          opset_version=14, do_constant_folding=True)
    return {"path": out, "parameters": params, "window": window}


def add_arguments(p=None):
    p = p or argparse.ArgumentParser(prog="python3 -m training tip-model",
                                     description=__doc__.split("\n")[0])
    p.add_argument("--out", required=True, help="ONNX file to write")
    p.add_argument("--window", type=int, default=40, help="frames per window (TIP: 40)")
    p.add_argument("--seed", type=int, default=0)
    return p


def main(args=None):
    if args is None or isinstance(args, list):
        args = add_arguments().parse_args(args)
    info = export(args.out, args.window, args.seed)
    print(f"tip-model: {info['path']} ({info['parameters']:,} parameters, input [1,{info['window']},"
          f"{IN_FEATURES}] -> output [1,{info['window']},{OUT_FEATURES}], random weights)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
