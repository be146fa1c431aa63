"""The TIP-class core (model.WindowedTransformerCore, `train --size tip`): windowed causal
attention that streams, matches a plain per-frame computation, and stays out of the export."""
import argparse

import numpy as np
import pytest
import torch

from training import export, skeleton as sk, train as tr
from training.errors import UsageError
from training.model import (MirrorEnsemble, ModelConfig, PoseNet, WindowedTransformerCore,
                            _WindowedAttentionBlock)

from test_model import _assert_causal, _assert_streaming_equals_whole, _inputs, _mirrored, _streamed   # pytest puts this folder on sys.path

TIP_SMALL = ModelConfig(32, 24, 1, 32, core="transformer", window=5, blocks=2, heads=4, ff=48)


def _tip_like(cfg=TIP_SMALL, seed=0):
    torch.manual_seed(seed)
    net = PoseNet(cfg).eval()
    with torch.no_grad():
        net.head[-1].weight.normal_(0, 0.3)
        for block in net.core.blocks:
            block.distance_bias.normal_(0, 1.0)   # trained biases differ by distance; zeros would not
    return net


def _reference_block(block, x, memory):
    """The block computed frame by frame: each frame's query against exactly the window of
    frames ending at it (memory first), softmax of scaled dot products plus the distance bias."""
    w, heads = block.window, block.heads
    full = torch.cat([memory, x], dim=1)
    b, n, d = full.shape
    dh = d // heads
    q, k, v = block.qkv(block.norm1(full)).chunk(3, dim=-1)
    out = []
    for t in range(w - 1, n):
        seen = slice(t - w + 1, t + 1)
        qt = q[:, t].reshape(b, heads, 1, dh)
        kt = k[:, seen].reshape(b, w, heads, dh).permute(0, 2, 3, 1)      # (B,h,dh,w)
        vt = v[:, seen].reshape(b, w, heads, dh).permute(0, 2, 1, 3)      # (B,h,w,dh)
        distance = torch.arange(w - 1, -1, -1)                            # oldest frame first
        scores = (qt @ kt) / dh ** 0.5 + block.distance_bias[:, distance].unsqueeze(1)
        out.append((torch.softmax(scores, dim=-1) @ vt).reshape(b, d))
    y = x + block.proj(torch.stack(out, dim=1))
    return y + block.ff(block.norm2(y))


@pytest.mark.parametrize("frames", [1, 3, 5, 12, 23])
def test_blocked_attention_equals_the_window_of_each_frame(frames):
    torch.manual_seed(1)
    block = _WindowedAttentionBlock(width=16, heads=4, ff=24, window=5).eval()
    with torch.no_grad():
        block.distance_bias.normal_(0, 1.0)
        x, memory = torch.randn(2, frames, 16), torch.randn(2, 4, 16)
        y, new_memory = block(x, memory, 0.0)
        assert torch.allclose(y, _reference_block(block, x, memory), atol=1e-5)
        assert torch.equal(new_memory, torch.cat([memory, x], dim=1)[:, -4:])


def test_a_frame_reaches_only_the_window_after_it():
    """One block: changing frame 10 changes its own output and the next window - 1 frames', no
    earlier one and none later (the window is the attention's whole reach)."""
    torch.manual_seed(2)
    block = _WindowedAttentionBlock(width=16, heads=4, ff=24, window=5).eval()
    x = torch.randn(1, 30, 16)
    x2 = x.clone()
    x2[:, 10] += torch.randn(16)       # not a constant shift, which the layer norm would remove
    with torch.no_grad():
        changed = (block(x2, torch.zeros(1, 4, 16), 0.0)[0] - block(x, torch.zeros(1, 4, 16), 0.0)[0])
    moved = changed.abs().amax(dim=-1)[0] > 1e-6
    assert moved[10:15].all() and not moved[:10].any() and not moved[15:].any()


def test_streaming_equals_whole_clip_across_chunks(monkeypatch):
    monkeypatch.setattr(WindowedTransformerCore, "CHUNK", 7)     # the clip spans several chunks
    o, a = _inputs(seconds=0.5)
    whole, (memory, rnn) = _assert_streaming_equals_whole(_tip_like(), o, a)
    assert memory.shape == (TIP_SMALL.blocks * (TIP_SMALL.window - 1), o.shape[0], TIP_SMALL.embed)
    assert rnn.shape == (TIP_SMALL.layers, o.shape[0], TIP_SMALL.hidden)
    assert torch.allclose(memory, whole[3][0], atol=1e-5) and torch.allclose(rnn, whole[3][1], atol=1e-5)


def test_causal_and_the_state_carries_the_past():
    net = _tip_like()
    o, a = _inputs(seconds=0.5)
    r1 = _assert_causal(net, o, a, at=20)
    with torch.no_grad():
        # the second half alone, from a zero state, is not what it is after the first half
        cold = net(o[:, 15:], a[:, 15:])[0]
    assert (cold[:, :5] - r1[:, 15:20]).abs().max() > 1e-3


def test_heading_and_mirror_symmetry_hold_for_the_tip_core():
    net = _tip_like()
    net.enable_anchoring()
    ens = MirrorEnsemble(net).eval()
    o, a = _inputs(seconds=0.5)
    yaw = torch.from_numpy(sk.rot_axis("y", -1.3).astype(np.float32))
    m, om, am = _mirrored(o, a)
    with torch.no_grad():
        r, v, c, _ = ens(o, a)
        turned = ens(yaw @ o, (yaw @ a.unsqueeze(-1)).squeeze(-1))[0]
        rm, vm, cm, _ = ens(om, am)
    assert torch.allclose(turned[:, :, 1:], r[:, :, 1:], atol=1e-4)
    assert torch.allclose(turned[:, :, 0], yaw @ r[:, :, 0], atol=1e-4)
    assert torch.allclose(m @ rm[:, :, sk.MIRROR_JOINTS] @ m, r, atol=1e-5)
    assert torch.allclose(vm @ m, v, atol=1e-5) and torch.allclose(cm.flip(-1), c, atol=1e-6)
    # the pair streams with each state tensor doubled along its last axis
    streamed, state = _streamed(ens, o, a)
    assert torch.allclose(streamed[0], r, atol=1e-5)
    assert [s.shape[-1] for s in state] == [2 * TIP_SMALL.embed, 2 * TIP_SMALL.hidden]


def test_tip_size_is_tip_shaped():
    net = PoseNet(tr.SIZES["tip"])
    c = net.config
    assert (c.core, c.window, c.blocks, c.heads, c.ff, c.hidden, c.layers) == ("transformer", 40, 4, 16, 1024, 512, 1)
    # TIP has about 3.7 M parameters; the same core here stays under the 4 M
    assert 3_500_000 < sum(p.numel() for p in net.parameters()) < 4_000_000


@pytest.mark.parametrize("key, value, message", [("core", "gru", "core 'gru'"), ("heads", 5, "not a multiple"),
                                                 ("window", 1, "window 1"), ("blocks", 0, "blocks 0")])
def test_bad_core_configs_are_refused(key, value, message):
    with pytest.raises(ValueError, match=message):
        ModelConfig.from_dict(dict(TIP_SMALL.to_dict(), **{key: value}))


def test_a_tip_checkpoint_trains_resumes_and_is_never_exported(tmp_path):
    motions = [tr._procedural_motions(3, 3.0, 0), tr._procedural_motions(1, 3.0, 9)]
    cfg = tr.TrainConfig(size="tip", batch=2, window=30, lr=1e-3, warmup=2, steps=2, budget_minutes=5,
                         ckpt_dir=str(tmp_path / "ck"), results_dir=str(tmp_path / "res"), progress=False,
                         smoke=True, eval_every_s=1e9)
    tr.train(cfg, *motions)
    ck = torch.load(str(tmp_path / "ck" / "last.pt"))
    assert [tuple(t.shape) for t in ck["lstm_state"]] == [(4 * 39, 2, 256), (1, 2, 512)]
    assert tr.saved_train_config(ck).size == "tip"
    cfg.resume, cfg.steps = True, 3
    assert tr.train(cfg, *motions)["steps"] == 3
    net, _ = export.load_checkpoint(tmp_path / "ck" / "last.pt")
    assert net.config.core == "transformer"
    with pytest.raises(UsageError, match="transformer network .* cannot be exported; nothing written"):
        export.main(argparse.Namespace(checkpoint=str(tmp_path / "ck" / "last.pt"), out=str(tmp_path / "onnx")))
    with pytest.raises(UsageError, match="cannot be exported"):
        export.export(MirrorEnsemble(net), tmp_path / "onnx", check=False)
    assert not (tmp_path / "onnx").exists()


def test_size_and_init_from_are_not_combined():
    parser = argparse.ArgumentParser()
    tr.add_arguments(parser)
    args = parser.parse_args(["--size", "tip", "--init-from", "training/checkpoints/mocap_pose.pt"])
    with pytest.raises(UsageError, match="--size cannot be combined"):
        tr.config_from_args(args)
