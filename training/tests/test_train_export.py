"""Training loop smoke test (one epoch on procedural data) and the ONNX export contract."""
import argparse
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch

from training import export, procedural, skeleton as sk, train as tr
from training.model import MirrorEnsemble, ModelConfig, PoseNet

CONTRACT_KEYS = ["mocap.contract_version", "mocap.frame_rate", "mocap.sensor_order", "mocap.joint_names",
                 "mocap.joint_parents", "mocap.rest_offsets", "mocap.state_layers", "mocap.state_size",
                 "mocap.precision", "mocap.model_name", "mocap.wrist_sensor_bone"]


def _motions(n, seed):
    return [procedural.make_motion(procedural.KINDS[i % 5], seconds=3.0, seed=seed + i) for i in range(n)]


def test_one_epoch_smoke_training_and_resume(tmp_path):
    train_m, val_m = _motions(4, 0), _motions(1, 50)
    cfg = tr.TrainConfig(size="tiny", batch=4, window=60, lr=3e-3, warmup=2, steps=None, budget_minutes=5,
                         ckpt_dir=str(tmp_path / "ck"), results_dir=str(tmp_path / "res"), progress=False,
                         smoke=True, eval_every_s=1e9)
    frames = sum(m.num_frames for m in train_m)
    cfg.steps = int(np.ceil(frames / (cfg.batch * cfg.window)))       # one epoch = 3 steps
    s1 = tr.train(cfg, train_m, val_m)
    assert s1["steps"] == cfg.steps and abs(s1["epochs"] - 1.0) < 1e-6
    log = json.loads((tmp_path / "res" / "train_log.json").read_text())
    assert log["history"]["val"] and np.isfinite(log["history"]["val"][-1]["val_loss"])
    assert (tmp_path / "res" / "loss.png").stat().st_size > 1000
    for name in ("last.pt", "best.pt"):
        assert (tmp_path / "ck" / name).is_file()
    # resume continues the schedule from the checkpoint; a few more steps lower the loss
    cfg.resume, cfg.steps = True, 40
    ck = torch.load(str(tmp_path / "ck" / "last.pt"))
    assert ck["step"] == s1["steps"]
    s2 = tr.train(cfg, train_m, val_m)
    assert s2["steps"] == 40
    # the data path's share of a step is measured on the same steps, so it cannot exceed the step
    assert 0 < s2["data_s_per_step_median"] <= s2["s_per_step_median"]
    hist = json.loads((tmp_path / "res" / "train_log.json").read_text())["history"]
    assert hist["val"][-1]["val_loss"] < hist["val"][0]["val_loss"]
    net, _ = export.load_checkpoint(tmp_path / "ck" / "best.pt")
    assert replace(net.config, dropout=0.0, anchored=False) == tr.SIZES["tiny"]
    assert net.config.dropout == cfg.dropout and net.config.anchored == cfg.anchored


def test_weights_only_checkpoint_warm_starts_a_new_run(tmp_path):
    train_m, val_m = _motions(2, 0), _motions(1, 50)
    cfg = tr.TrainConfig(size="tiny", batch=4, window=60, lr=3e-3, warmup=2, steps=3, budget_minutes=5,
                         ckpt_dir=str(tmp_path / "ck"), results_dir=str(tmp_path / "res"), progress=False,
                         smoke=True, eval_every_s=1e9)
    tr.train(cfg, train_m, val_m)
    tr.save_weights(tmp_path / "ck" / "last.pt", tmp_path / "weights.pt")
    small = torch.load(str(tmp_path / "weights.pt"))
    assert "optimizer" not in small and small["config"] == replace(tr.SIZES["tiny"], dropout=cfg.dropout,
                                                                anchored=True).to_dict()
    # the warm start begins exactly at those weights (a fresh run would start elsewhere)
    net = tr.load_weights(tmp_path / "weights.pt")
    for k, v in small["model"].items():
        assert torch.equal(net.state_dict()[k], v)
    fresh = tr.PoseNet(tr.SIZES["tiny"])
    assert any(not torch.equal(fresh.state_dict()[k], v) for k, v in small["model"].items())
    cfg2 = tr.TrainConfig(size="tiny", batch=4, window=60, lr=3e-3, warmup=2, steps=2, budget_minutes=5,
                          ckpt_dir=str(tmp_path / "ck2"), results_dir=str(tmp_path / "res2"), progress=False,
                          smoke=True, eval_every_s=1e9, init_from=str(tmp_path / "weights.pt"))
    s2 = tr.train(cfg2, train_m, val_m)
    assert s2["steps"] == 2   # its own schedule, not the source run's


def test_command_line_options_reach_the_training_config():
    import argparse
    parser = argparse.ArgumentParser()
    tr.add_arguments(parser)
    cfg = tr.config_from_args(parser.parse_args(
        ["--pos-weight", "30", "--arm-swap", "0.5", "--arm-jitter", "12", "--lr", "2.5e-4", "--seed", "3",
         "--rare-boost", "0.5", "--spine-jitter", "6", "--trunk-swap", "0.25", "--body-scale", "0.85,1.15"]))
    assert (cfg.w_pos, cfg.arm_swap, cfg.arm_jitter_deg, cfg.lr, cfg.seed, cfg.rare_boost) == \
        (30.0, 0.5, 12.0, 2.5e-4, 3, 0.5)
    assert (cfg.spine_jitter_deg, cfg.trunk_swap) == (6.0, 0.25)
    walk = procedural.make_motion("walk", seconds=4.0, seed=1)
    augment = tr.make_batcher([walk], cfg, np.random.default_rng(0)).augment
    assert augment.spine_jitter_deg == 6.0 and augment.scale == (0.85, 1.15)
    default = tr.config_from_args(parser.parse_args([]))
    assert tr.make_batcher([walk], default, np.random.default_rng(0)).augment.scale == (0.9, 1.1)
    assert default == tr.TrainConfig()
    assert tr.config_from_args(parser.parse_args(["--no-anchor"])).anchored is False


def test_rare_boost_draws_the_clip_with_rare_poses_more_often():
    from training import procedural
    walks = [procedural.make_motion("walk", 6.0, seed=i, name=f"walk{i}") for i in range(5)]
    squat = procedural.make_motion("squat", 6.0, seed=9, name="squat")
    motions = walks + [squat]
    plain = tr.StreamBatcher(motions, batch=2, window=30, rng=np.random.default_rng(0))
    boosted = tr.StreamBatcher(motions, batch=2, window=30, rng=np.random.default_rng(0), rare_boost=1.0)
    lengths = np.array([m.num_frames for m in motions], np.float64)
    np.testing.assert_allclose(plain.p, lengths / lengths.sum())
    np.testing.assert_allclose(boosted.p, lengths * boosted.rarity / (lengths * boosted.rarity).sum())
    assert boosted.p[-1] > 1.5 * plain.p[-1] and all(boosted.p[:-1] < plain.p[:-1])
    drawn = [boosted.motions[int(boosted.rng.choice(len(motions), p=boosted.p))].name for _ in range(400)]
    assert drawn.count("squat") > 1.3 * 400 * plain.p[-1]
    assert "rarest" in tr.rarity_summary(boosted)


def test_stream_batcher_carries_state_and_resets_on_new_clips():
    rng = np.random.default_rng(0)
    b = tr.StreamBatcher(_motions(2, 0), batch=3, window=30, rng=rng)
    first, reset = b.next()
    assert reset.all()
    assert first["imu_orientation"].shape == (3, 30, 6, 3, 3)
    assert first["local_rot"].shape == (3, 30, 24, 3, 3) and first["offsets"].shape == (3, 24, 3)
    pos = list(b.pos)
    _, reset2 = b.next()
    for i in range(3):   # a stream either continues its clip right after the last window or restarts
        assert (not reset2[i] and b.pos[i] == pos[i] + 30) or reset2[i]


def test_rotation_losses_chordal_and_squared():
    T = 5
    tgt = torch.eye(3).expand(1, T, 24, 3, 3).clone()
    pred = tgt.clone()
    theta = math.radians(90.0)
    c, s = math.cos(theta), math.sin(theta)
    pred[:, :, 5] = torch.tensor([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])   # one joint 90 deg off
    batch = {"local_rot": tgt, "offsets": torch.from_numpy(sk.DEFAULT_OFFSETS[None].astype(np.float32)),
             "root_velocity": torch.zeros(1, T, 3), "foot_contact": torch.ones(1, T, 2)}
    out = (pred, torch.zeros(1, T, 3), torch.full((1, T, 2), 10.0))
    chordal = tr.compute_losses(out, batch, tr.TrainConfig(rot_loss="chordal"))["rot"]
    squared = tr.compute_losses(out, batch, tr.TrainConfig(rot_loss="squared"))["rot"]
    # Frobenius distance of a rotation by theta: 2 sqrt(2) sin(theta / 2) = 2 at 90 deg
    assert abs(float(chordal) - 2.0 / 24) < 2e-3
    assert abs(float(squared) - 4.0 / 24) < 1e-4


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    d = tmp_path_factory.mktemp("onnx")
    net = export.untrained_model(seed=0)
    net.enable_anchoring()      # as trained since run 5: the anchored output path is exported
    with torch.no_grad():       # make the outputs depend visibly on the input
        net.head[-1].weight.normal_(0, 0.05)
    net.set_dropout(0.2)        # as trained: the export must leave no dropout in the graph
    model = MirrorEnsemble(net).eval()   # as shipped: the mirror-averaged pair
    info = export.export(model, d, model_name="test", check=False)
    return model, d, info


def test_export_follows_the_contract(exported):
    import onnx
    net, d, info = exported
    for name, prec in ((export.FP32_NAME, "fp32"), (export.FP16_NAME, "fp16")):
        m = onnx.load(str(d / name))
        onnx.checker.check_model(m)
        assert max(o.version for o in m.opset_import if o.domain in ("", "ai.onnx")) >= 14
        meta = {p.key: p.value for p in m.metadata_props}
        assert sorted(meta) == sorted(CONTRACT_KEYS)
        assert meta["mocap.contract_version"] == "1" and meta["mocap.precision"] == prec
        assert meta["mocap.frame_rate"] == "60"
        assert meta["mocap.wrist_sensor_bone"] == net.config.wrist_anchor == "hand"
        assert meta["mocap.sensor_order"] == "pelvis,left_wrist,right_wrist,left_shin,right_shin,head"
        assert meta["mocap.joint_names"].split(",") == sk.JOINT_NAMES
        assert [int(x) for x in meta["mocap.joint_parents"].split(",")] == sk.PARENTS
        offs = np.array([float(x) for x in meta["mocap.rest_offsets"].split(",")]).reshape(24, 3)
        assert np.allclose(offs, sk.DEFAULT_OFFSETS, atol=1e-6)
        L, H = int(meta["mocap.state_layers"]), int(meta["mocap.state_size"])
        assert (L, H) == (net.state_layers, net.state_size) == (net.net.state_layers, 2 * net.net.state_size)

        def dims(vi):
            return [dd.dim_param or dd.dim_value for dd in vi.type.tensor_type.shape.dim]
        ins = {i.name: i for i in m.graph.input}
        outs = {o.name: o for o in m.graph.output}
        assert list(ins) == export.INPUT_NAMES and list(outs) == export.OUTPUT_NAMES
        for vi in list(ins.values()) + list(outs.values()):
            assert vi.type.tensor_type.elem_type == onnx.TensorProto.FLOAT, vi.name
        assert dims(ins["imu_orientation"]) == ["B", "T", 6, 3, 3]
        assert dims(ins["imu_acceleration"]) == ["B", "T", 6, 3]
        assert dims(ins["state_in_h"]) == [L, "B", H] and dims(outs["state_out_c"]) == [L, "B", H]
        assert dims(outs["joint_rotations"]) == ["B", "T", 24, 3, 3]
        assert dims(outs["root_velocity"]) == ["B", "T", 3] and dims(outs["foot_contact"]) == ["B", "T", 2]
        assert not any(n.op_type in ("Dropout", "RandomUniformLike", "RandomUniform", "Bernoulli")
                       for n in m.graph.node)
        types = {i.data_type for i in m.graph.initializer if i.dims and np.prod(i.dims) > 16}
        assert types == ({onnx.TensorProto.FLOAT16} if prec == "fp16" else {onnx.TensorProto.FLOAT})
    assert info["fp32_bytes"] <= 16 * 2 ** 20
    assert info["fp16_bytes"] < 0.6 * info["fp32_bytes"]


def test_the_exported_geometry_stays_a_few_hundred_operators(exported):
    """ONNX Runtime pays per operator, and at one frame per call the mirror, the heading frame,
    Gram-Schmidt and the anchoring's kinematics cost more than the weights. Bone-by-bone code
    exported ~530 operators (0.21 ms a frame in int8); batched ~200 (0.14 ms); with every
    normalisation one LpNormalization and one Gram-Schmidt for the mirror average ~150 (0.12 ms).
    No Shape operator: every reshape copies its leading dimensions instead of computing them."""
    import collections
    import onnx
    _, d, _ = exported
    ops = collections.Counter(n.op_type for n in onnx.load(str(d / export.FP32_NAME)).graph.node
                              if n.op_type != "Constant")
    assert sum(ops.values()) <= 170, ops
    assert ops["Shape"] == 0 and ops["Split"] >= 5, ops
    assert ops["LSTM"] == 2 and ops["MatMul"] <= 20, ops    # six tree levels, not a product per bone
    # a unit vector is one LpNormalization, never Mul-ReduceSum-Add-Sqrt-Div; the two ReduceSums
    # are the Gram-Schmidt projections: one for the anchoring's kinematics, one for the output
    assert ops["Sqrt"] == 0 and ops["LpNormalization"] == 6 and ops["ReduceSum"] == 2, ops


def test_onnx_runtime_matches_pytorch_and_streams(exported):
    from training import ort
    if not ort.onnx_runtime_available():
        pytest.skip("ONNX Runtime not available (scripts/fetch_onnxruntime.sh)")
    net, d, _ = exported
    ori, acc = export.fixture_inputs(seconds=1.0)
    rep = export.check_against_torch(net, {"fp32": d / export.FP32_NAME, "fp16": d / export.FP16_NAME},
                                     ori, acc, stream_frames=30)
    assert max(rep["fp32"].values()) < 1e-4, rep
    assert max(rep["fp16"].values()) < 2e-2, rep
    assert max(rep["stream_vs_whole_fp32"].values()) < 1e-5, rep
    # the test model is not trivial: outputs move with the input
    ref = export.torch_outputs(net, ori, acc)
    assert np.ptp(ref["root_velocity"]) > 1e-3


def test_export_cli_ships_the_mirror_averaged_pair_unless_told_not_to(tmp_path):
    import argparse
    import onnx
    torch.manual_seed(0)
    cfg = ModelConfig(embed=16, hidden=8, layers=1, head=16)
    ckpt = tmp_path / "tiny.pt"
    torch.save({"model": PoseNet(cfg).state_dict(), "config": cfg.to_dict(), "step": 7}, ckpt)
    parser = argparse.ArgumentParser()
    export.add_arguments(parser)
    for extra, size, named in (([], 16, True), (["--no-mirror"], 8, False)):
        out = tmp_path / ("plain" if extra else "pair")
        assert export.main(parser.parse_args(["--checkpoint", str(ckpt), "--out", str(out), "--no-check"]
                                             + extra)) == 0
        meta = {p.key: p.value for p in onnx.load(str(out / export.FP32_NAME)).metadata_props}
        assert int(meta["mocap.state_size"]) == size
        assert ("mirror-averaged" in meta["mocap.model_name"]) == named
        assert meta["mocap.model_name"].endswith("step 7")


def test_an_averaged_checkpoint_is_named_as_an_average_never_step_none(tmp_path):
    import onnx
    torch.manual_seed(0)
    cfg = ModelConfig(embed=16, hidden=8, layers=1, head=16)
    ckpt = tmp_path / "avg.pt"
    torch.save({"model": PoseNet(cfg).state_dict(), "config": cfg.to_dict(), "step": None, "best": None,
                "averaged_from": ["a.pt", "b.pt", "c.pt"]}, ckpt)
    parser = argparse.ArgumentParser()
    export.add_arguments(parser)
    out = tmp_path / "avg"
    assert export.main(parser.parse_args(["--checkpoint", str(ckpt), "--out", str(out), "--no-check"])) == 0
    name = {p.key: p.value for p in onnx.load(str(out / export.FP32_NAME)).metadata_props}["mocap.model_name"]
    assert "None" not in name and "?" not in name
    assert name.endswith("mirror-averaged average of 3 checkpoints")
    assert export.checkpoint_label({}) == ""


def test_wrist_sensor_option_reaches_training_and_moves_a_hand_model_to_the_forearm(tmp_path):
    args = argparse.Namespace(wrist_sensor="forearm", smoke=True)
    cfg = tr.config_from_args(args)
    assert cfg.wrist_sensor == "forearm" and tr.TrainConfig().wrist_sensor == "hand"
    hand = tmp_path / "hand.pt"
    net = PoseNet(ModelConfig(16, 16, 1, 16, anchored=True))
    torch.save({"model": net.state_dict(), "config": {k: v for k, v in net.config.to_dict().items()
                                                      if k != "wrist_anchor"}}, hand)
    cfg.init_from, cfg.steps = str(hand), 2
    cfg.ckpt_dir, cfg.results_dir = str(tmp_path / "ck"), str(tmp_path / "res")
    motions = _motions(3, 0)
    tr.train(cfg, motions, motions[:1])
    assert tr.load_weights(tmp_path / "ck" / "last.pt").config.wrist_anchor == "forearm"
    # a forearm-trained network is not silently trained for the hands again
    back = tr.config_from_args(argparse.Namespace(smoke=True))
    back.init_from, back.steps = str(tmp_path / "ck" / "last.pt"), 2
    back.ckpt_dir, back.results_dir = str(tmp_path / "ck2"), str(tmp_path / "res2")
    with pytest.raises(ValueError, match="wrist sensors as the forearm"):
        tr.train(back, motions, motions[:1])


# ------------------------------------------------------------------ resume, held-out validation
def _cli(argv):
    parser = argparse.ArgumentParser()
    tr.add_arguments(parser)
    return tr.config_from_args(parser.parse_args([str(a) for a in argv]))


def _dirs(tmp_path):
    return ["--ckpt-dir", tmp_path / "ck", "--results-dir", tmp_path / "res"]


TINY_RUN = ["--size", "tiny", "--batch", "4", "--window", "60", "--steps", "2"]


def test_resume_continues_with_the_checkpoints_own_options(tmp_path, monkeypatch):
    motions = _motions(3, 0)
    first = _cli(TINY_RUN + ["--no-anchor", "--wrist-sensor", "forearm", "--pos-weight", "30",
                             "--dropout", "0.2", "--arm-swap", "0.5"] + _dirs(tmp_path))
    tr.train(first, motions, motions[:1])
    again = _cli(["--resume", "--steps", "4"] + _dirs(tmp_path))   # the flags are not repeated
    assert (again.anchored, again.wrist_sensor, again.w_pos, again.dropout, again.arm_swap, again.size,
            again.batch, again.window, again.steps) == (False, "forearm", 30.0, 0.2, 0.5, "tiny", 4, 60, 4)

    def switched(*_):
        raise AssertionError("a resumed network is switched over again")
    monkeypatch.setattr(PoseNet, "enable_anchoring", switched)
    monkeypatch.setattr(PoseNet, "anchor_wrists_on_forearm", switched)
    assert tr.train(again, motions, motions[:1])["steps"] == 4
    ck = torch.load(str(tmp_path / "ck" / "last.pt"), weights_only=False)
    assert (ck["config"]["anchored"], ck["config"]["wrist_anchor"], ck["config"]["dropout"]) == (False, "forearm", 0.2)


def _nine_step_run(tmp_path, name, **kw):
    """A tiny 9-step run in tmp_path/name whose weights depend on its steps alone: no wall-clock
    budget, validation or periodic checkpoint in the way."""
    return tr.TrainConfig(size="tiny", batch=3, window=40, lr=3e-3, warmup=2, steps=9,
                          budget_minutes=1e6, ckpt_dir=str(tmp_path / name / "ck"),
                          results_dir=str(tmp_path / name / "res"), progress=False,
                          smoke=True, eval_every_s=1e9, ckpt_every_s=1e9, **kw)


def test_a_run_stopped_and_resumed_ends_with_the_weights_of_an_uninterrupted_one(tmp_path):
    """--stop-after then --resume (a run split over sittings, e.g. short GPU leases) takes exactly
    the steps of an uninterrupted run: same batches, same LSTM state carried, same random draws."""
    train_m = _motions(4, 0)

    whole = _nine_step_run(tmp_path, "whole")
    assert tr.train(whole, train_m, [])["steps"] == 9
    split = _nine_step_run(tmp_path, "split", stop_after=4)
    assert tr.train(split, train_m, [])["steps"] == 4
    resumed = replace(split, resume=True, stop_after=None)
    assert tr.train(resumed, train_m, [])["steps"] == 9
    a = torch.load(str(tmp_path / "whole" / "ck" / "last.pt"), weights_only=False)
    b = torch.load(str(tmp_path / "split" / "ck" / "last.pt"), weights_only=False)
    for name, value in a["model"].items():
        assert torch.equal(value, b["model"][name]), name
    for x, y in zip(a["lstm_state"], b["lstm_state"]):
        assert torch.equal(x, y)
    assert a["batcher"]["pos"] == b["batcher"]["pos"]


def test_ctrl_c_finishes_the_step_saves_and_resumes_exactly(tmp_path, monkeypatch):
    """Ctrl-C during step 4 (a real SIGINT to this process): the step completes, last.pt holds
    its end, the run reports the interruption as an error, and --resume ends with the weights of
    a run that was never interrupted."""
    import os
    import signal
    from training.errors import CommandError
    train_m = _motions(4, 0)

    tr.train(_nine_step_run(tmp_path, "whole"), train_m, [])
    # the handler the run found (a shell's background job starts with SIGINT ignored)
    handler_before = signal.getsignal(signal.SIGINT)
    calls = []
    real_next = tr.StreamBatcher.next

    def next_with_ctrl_c(self):
        calls.append(1)
        if len(calls) == 4:
            os.kill(os.getpid(), signal.SIGINT)
        return real_next(self)

    monkeypatch.setattr(tr.StreamBatcher, "next", next_with_ctrl_c)
    cut = _nine_step_run(tmp_path, "cut")
    with pytest.raises(CommandError, match="interrupted .* after step 4: .*last.pt saved"):
        tr.train(cut, train_m, [])
    monkeypatch.setattr(tr.StreamBatcher, "next", real_next)
    assert signal.getsignal(signal.SIGINT) is handler_before   # handler given back
    ck = torch.load(str(tmp_path / "cut" / "ck" / "last.pt"), weights_only=False)
    assert ck["step"] == 4
    assert tr.train(replace(cut, resume=True), train_m, [])["steps"] == 9
    a = torch.load(str(tmp_path / "whole" / "ck" / "last.pt"), weights_only=False)
    b = torch.load(str(tmp_path / "cut" / "ck" / "last.pt"), weights_only=False)
    for name, value in a["model"].items():
        assert torch.equal(value, b["model"][name]), name


def test_stop_after_belongs_to_one_sitting(tmp_path, monkeypatch):
    motions = _motions(3, 0)
    monkeypatch.setattr(tr, "load_data", lambda cfg: (motions, []))
    cfg = _cli(TINY_RUN + ["--steps", "5", "--stop-after", "2"] + _dirs(tmp_path))
    assert cfg.stop_after == 2
    assert tr.train(replace(cfg, progress=False))["steps"] == 2
    again = _cli(["--resume"] + _dirs(tmp_path))
    assert again.stop_after is None and again.steps == 5     # not stopped at once by the saved 2
    assert _cli(["--resume", "--stop-after", "4"] + _dirs(tmp_path)).stop_after == 4


def test_resume_refuses_options_that_contradict_the_checkpoint(tmp_path, capsys):
    from training.__main__ import main
    from training.errors import UsageError
    motions = _motions(3, 0)
    tr.train(_cli(TINY_RUN + _dirs(tmp_path)), motions, motions[:1])      # anchored, hand, tiny
    for extra in (["--no-anchor"], ["--wrist-sensor", "forearm"], ["--size", "small"], ["--lr", "0.5"]):
        with pytest.raises(UsageError, match="--resume: " + extra[0]):
            _cli(["--resume"] + extra + _dirs(tmp_path))
    # the run's own values, and budget / steps / device / output folders, may be given
    ok = _cli(["--resume", "--size", "tiny", "--lr", "0.001", "--budget-minutes", "7", "--device", "cpu",
               "--results-dir", tmp_path / "res2", "--ckpt-dir", tmp_path / "ck"])
    assert (ok.budget_minutes, ok.device, ok.results_dir, ok.resume) == (7.0, "cpu", str(tmp_path / "res2"), True)
    # the library entry point refuses the same contradiction
    with pytest.raises(UsageError, match="--no-anchor"):
        tr.train(replace(ok, anchored=False), motions, motions[:1])
    capsys.readouterr()
    assert main(["train", "--resume", "--wrist-sensor", "forearm"] + [str(a) for a in _dirs(tmp_path)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("training train: --resume: --wrist-sensor forearm contradicts") and "\n" not in err


def test_resume_without_a_last_checkpoint_is_an_error(tmp_path, capsys):
    from training.__main__ import main
    from training.errors import UsageError
    ck = tmp_path / "ck"
    ck.mkdir()
    (ck / "best.pt").write_bytes(b"the earlier run's best")
    with pytest.raises(UsageError, match="no checkpoint to resume"):
        _cli(["--resume"] + _dirs(tmp_path))
    cfg = tr.TrainConfig(size="tiny", batch=4, window=60, steps=2, resume=True, ckpt_dir=str(ck),
                         results_dir=str(tmp_path / "res"), progress=False)
    with pytest.raises(UsageError, match="no checkpoint to resume"):
        tr.train(cfg, _motions(2, 0), _motions(1, 9))
    assert (ck / "best.pt").read_bytes() == b"the earlier run's best" and not (ck / "last.pt").exists()
    assert main(["train", "--resume"] + [str(a) for a in _dirs(tmp_path)]) == 1
    assert "training train: --resume: no checkpoint to resume in" in capsys.readouterr().err


def test_bvh_folder_without_val_folder_holds_out_validation_clips(fixture_dir, tmp_path, monkeypatch, capsys):
    from training import dataset
    monkeypatch.setattr(dataset, "CACHE_DIR", tmp_path / "cache")
    d, truth = fixture_dir
    cfg = _cli(["--bvh", d])
    assert cfg.train_source == str(d) and cfg.val_source is None
    cfg.progress = False
    train_m, val_m = tr.load_data(cfg)
    # CMU subject numbers in the names: subject 1 is a CMU validation subject (1 % 10 == 1)
    assert [m.name for m in val_m] == ["01_01"]
    assert sorted(m.name for m in train_m) == sorted(n for n in truth if n != "01_01")
    assert "subjects 1 (CMU validation subjects)" in capsys.readouterr().out
    assert _cli(["--bvh", d, "--val-bvh", d]).val_source == str(d)       # an explicit folder is kept


def test_holdout_validation_by_subject_or_by_clip():
    def named(n, subjects):
        return [replace(m, name=f"c{i}", subject=s) for i, (m, s) in enumerate(zip(_motions(n, 0), subjects))]
    # no CMU validation subject among them: every 10th subject
    tr_m, va_m, how = tr.holdout_validation(named(4, [2, 3, 4, 5]))
    assert {m.subject for m in va_m} == {4} and len(tr_m) == 3 and "every 10th subject" in how
    # no subject numbers: by clip, about 10 %, spread over the folder, deterministic
    clips = named(12, [0] * 12)
    tr_m, va_m, how = tr.holdout_validation(clips)
    assert [m.name for m in va_m] == ["c6"] and len(tr_m) == 11 and "every 10th clip" in how
    assert [m.name for m in tr.holdout_validation(named(30, [0] * 30))[1]] == ["c5", "c15", "c25"]
    assert tr.holdout_validation(clips[:1])[1] == []                       # one clip: no validation


# ------------------------------------------------------------------ atomic export and its check
def _tiny_checkpoint(path):
    torch.manual_seed(0)
    cfg = ModelConfig(embed=16, hidden=8, layers=1, head=16)
    torch.save({"model": PoseNet(cfg).state_dict(), "config": cfg.to_dict(), "step": 7}, path)
    return path


def _report(fp32=0.0, fp16=0.0, stream=0.0):
    def row(x):
        return {k: (x if k == "joint_rotations" else 0.0) for k in export.OUTPUT_NAMES}
    return {"fp32": row(fp32), "fp16": row(fp16), "stream_vs_whole_fp32": row(stream)}


def test_export_check_thresholds():
    assert export.check_failures(_report(5e-5, 1.5e-3, 0.0)) == []
    assert export.check_failures(_report(2e-4))[0].startswith("fp32 joint_rotations differ by 0.0002 > 0.0001")
    assert export.check_failures(_report(fp16=3e-3))[0].startswith("fp16 joint_rotations")
    assert export.check_failures(_report(stream=float("nan")))[0].startswith("stream_vs_whole_fp32")


def test_export_installs_the_files_only_after_a_passing_check(tmp_path, monkeypatch, capsys):
    import onnx
    from training import ort
    from training.__main__ import main
    ckpt = _tiny_checkpoint(tmp_path / "tiny.pt")
    out = tmp_path / "models"
    out.mkdir()
    previous = {n: f"previous {n}".encode() for n in (export.FP32_NAME, export.FP16_NAME)}
    for n, b in previous.items():
        (out / n).write_bytes(b)
    seen = {}

    def fake_check(net, paths, *a, **k):   # ONNX Runtime disagrees beyond the fp16 threshold
        for tag, p in paths.items():
            meta = {q.key: q.value for q in onnx.load(str(p)).metadata_props}
            seen[tag] = (p.parent == out, p.name not in previous, meta["mocap.precision"])
        return _report(fp16=0.05)
    monkeypatch.setattr(ort, "onnx_runtime_available", lambda: True)
    monkeypatch.setattr(export, "check_against_torch", fake_check)
    argv = ["export", "--checkpoint", str(ckpt), "--out", str(out)]
    capsys.readouterr()
    assert main(argv) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("training export: ONNX Runtime does not reproduce PyTorch: fp16 joint_rotations "
                          "differ by 0.05 > 0.002") and "\n" not in err
    assert seen == {"fp32": (True, True, "fp32"), "fp16": (True, True, "fp16")}   # temporaries, checked
    assert {p.name: p.read_bytes() for p in out.iterdir()} == previous       # untouched, no leftovers
    # an interrupted export (the fp16 conversion fails) leaves them too
    real_convert = export.convert_fp16

    def broken(src, dst):
        Path(dst).write_bytes(b"half")
        raise KeyboardInterrupt
    monkeypatch.setattr(export, "convert_fp16", broken)
    with pytest.raises(KeyboardInterrupt):
        main(argv)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == previous
    # a passing check installs both, complete with the contract's metadata
    monkeypatch.setattr(export, "convert_fp16", real_convert)
    monkeypatch.setattr(export, "check_against_torch", lambda *a, **k: _report(1e-7, 1e-4))
    assert main(argv) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(previous)
    for n, prec in ((export.FP32_NAME, "fp32"), (export.FP16_NAME, "fp16")):
        meta = {q.key: q.value for q in onnx.load(str(out / n)).metadata_props}
        assert sorted(meta) == sorted(CONTRACT_KEYS) and meta["mocap.precision"] == prec


def test_export_check_on_the_real_onnx_runtime_passes_and_fails(tmp_path, monkeypatch):
    from training import ort
    if not ort.onnx_runtime_available():
        pytest.skip("ONNX Runtime not available (scripts/fetch_onnxruntime.sh)")
    net, _ = export.load_checkpoint(_tiny_checkpoint(tmp_path / "tiny.pt"))
    info = export.export(net, tmp_path / "ok", model_name="t", check=True)
    assert export.check_failures(info["check"]) == [] and (tmp_path / "ok" / export.FP16_NAME).is_file()
    monkeypatch.setitem(export.CHECK_TOLERANCE, "fp32", -1.0)   # any difference is too much
    with pytest.raises(export.ExportCheckError, match="fp32 joint_rotations"):
        export.export(net, tmp_path / "bad", model_name="t", check=True)
    assert list((tmp_path / "bad").iterdir()) == []


def test_weights_only_save_is_atomic(tmp_path, monkeypatch):
    import os
    from training.errors import CommandError
    src = _tiny_checkpoint(tmp_path / "tiny.pt")
    dst = tmp_path / "w" / "weights.pt"
    tr.save_weights(src, dst)
    before = dst.read_bytes()

    def disk_full(fd):   # the temporary is written, then the disk turns out to be full
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "fsync", disk_full)
    with pytest.raises(CommandError, match=f"{dst}: cannot write the checkpoint"):
        tr.save_weights(src, dst)
    assert dst.read_bytes() == before and [p.name for p in dst.parent.iterdir()] == ["weights.pt"]


# ------------------------------------------------------------------ non-finite values, bad options
def _tiny_config(tmp_path, **kw):
    return tr.TrainConfig(**{**dict(size="tiny", batch=2, window=30, lr=3e-3, warmup=2, steps=3, budget_minutes=5,
                                    ckpt_dir=str(tmp_path / "ck"), results_dir=str(tmp_path / "res"),
                                    progress=False, smoke=True, eval_every_s=1e9), **kw})


def test_training_stops_at_a_non_finite_loss_and_saves_no_nan_weights(tmp_path, monkeypatch):
    from training.errors import CommandError, UsageError
    motions = _motions(2, 0)
    with pytest.raises(CommandError, match=r"step 1: the training loss is nan .*--pos-weight"):
        tr.train(_tiny_config(tmp_path, w_pos=float("nan")), motions, motions[:1])
    assert not (tmp_path / "ck").exists()
    # a clip with NaN values is named before any step
    broken = replace(motions[1], name="broken_clip", root_pos=motions[1].root_pos.copy())
    broken.root_pos[7, 1] = np.nan
    with pytest.raises(UsageError, match="training clip broken_clip: its root_pos holds NaN or inf"):
        tr.train(_tiny_config(tmp_path), [motions[0], broken], motions[:1])
    with pytest.raises(UsageError, match="validation clip broken_clip"):
        tr.train(_tiny_config(tmp_path), motions, [broken])
    assert not (tmp_path / "ck").exists()
    # a finite loss whose gradient is not (d sqrt(x) / dx at 0), after a good checkpoint: kept
    tr.train(_tiny_config(tmp_path, steps=2), motions, motions[:1])
    good = (tmp_path / "ck" / "last.pt").read_bytes()
    real = tr.compute_losses

    def infinite_gradient(out, batch, cfg):
        losses = real(out, batch, cfg)
        losses["loss"] = losses["loss"] + torch.sqrt((out[0] - out[0].detach()).abs().sum())
        return losses
    monkeypatch.setattr(tr, "compute_losses", infinite_gradient)
    with pytest.raises(CommandError, match=r"step 3: the gradient norm is (nan|inf)"):
        tr.train(_tiny_config(tmp_path, resume=True, steps=4), motions, motions[:1])
    assert (tmp_path / "ck" / "last.pt").read_bytes() == good
    # weights that became non-finite (an overflowing learning rate) are never saved
    monkeypatch.setattr(tr, "compute_losses", real)
    with pytest.raises(CommandError, match="step 2: .*: the weights became NaN or inf in the previous step"):
        tr.train(_tiny_config(tmp_path / "huge", lr=float("inf"), steps=2), motions, motions[:1])
    assert not list((tmp_path / "huge").glob("ck/*.pt"))


@pytest.mark.parametrize("option", [
    "--batch 0", "--batch -1", "--window 0", "--window -5", "--lr nan", "--lr -1", "--lr 0", "--dropout 2",
    "--dropout 1", "--dropout -0.1", "--seed -1", "--steps 0", "--steps -1", "--budget-minutes -1",
    "--budget-minutes inf", "--stop-after -3", "--stop-after 0", "--arm-swap 5", "--arm-jitter -1",
    "--max-clips -1", "--max-clips 0", "--pos-weight nan", "--pos-weight -2", "--steps 2.5",
    "--rare-boost -1", "--rare-boost nan", "--body-scale 1.2,1.1", "--body-scale 0.3,1",
    "--body-scale 1,2.5", "--body-scale nan,1", "--body-scale 1"])
def test_bad_numeric_training_options_are_usage_errors(option, capsys):
    with pytest.raises(SystemExit) as e:
        _cli(option.split())
    assert e.value.code == 2
    name, value = option.split()
    assert f"argument {name}: '{value}' is not " in capsys.readouterr().err


def test_good_numeric_training_options_pass():
    cfg = _cli(["--batch", "1", "--window", "1", "--dropout", "0", "--seed", "0", "--arm-swap", "1",
                "--pos-weight", "0", "--budget-minutes", "0.5", "--steps", "1", "--max-clips", "1"])
    assert (cfg.batch, cfg.window, cfg.dropout, cfg.seed, cfg.arm_swap, cfg.w_pos, cfg.budget_minutes,
            cfg.steps, cfg.max_clips) == (1, 1, 0.0, 0, 1.0, 0.0, 0.5, 1, 1)


def test_smoke_refuses_options_that_choose_the_data(fixture_dir):
    from training.errors import UsageError
    d, _ = fixture_dir
    for extra in (["--bvh", d], ["--val-bvh", d], ["--max-clips", "3"]):
        with pytest.raises(UsageError, match=f"--smoke trains on procedural motions .* {extra[0]}"):
            _cli(["--smoke"] + extra)


def test_export_refuses_non_finite_weights_before_writing_anything(tmp_path):
    from training.errors import UsageError
    net = export.untrained_model(seed=0, config=ModelConfig(16, 8, 1, 16))
    with torch.no_grad():
        net.lstm.bias_ih_l0[2] = float("nan")
    for model in (net, MirrorEnsemble(net)):
        with pytest.raises(export.ExportCheckError, match=r"weights hold NaN or inf .*lstm.bias_ih_l0.*nothing written"):
            export.export(model, tmp_path / "m", model_name="t", check=False)
    assert not (tmp_path / "m").exists()
    bad = dict(ModelConfig(16, 8, 1, 16).to_dict(), hidden=-5)
    torch.save({"model": net.state_dict(), "config": bad}, tmp_path / "bad.pt")
    with pytest.raises(UsageError, match=f"{tmp_path / 'bad.pt'}: invalid network config .hidden -5"):
        export.load_checkpoint(tmp_path / "bad.pt")
    for key, value in (("layers", 0), ("embed", "16"), ("dropout", 1.5), ("head", 2.5)):
        with pytest.raises(ValueError, match=key):
            ModelConfig.from_dict(dict(ModelConfig().to_dict(), **{key: value}))


def _with_root_jump(motion, at, jump_m):
    """The motion with its root moved by jump_m metres between frames at-1 and at (a glitch)."""
    root = motion.root_pos.copy()
    root[at:, 0] += jump_m
    return sk.Motion(motion.name + "_jump", motion.subject, motion.fps, motion.local_rot, root, motion.offsets)


def test_clips_whose_root_jumps_are_left_out_of_training_only(tmp_path, capsys):
    clean = _motions(3, 0)
    # 0.3 m in one frame at 60 Hz is 18 m/s; a walk's own speed (~1.4 m/s) stays in
    glitch = _with_root_jump(clean[0], 40, 0.3)
    kept, dropped = tr.without_root_jumps(clean + [glitch])
    assert [m.name for m in kept] == [m.name for m in clean] and dropped == [glitch.name]
    assert tr.without_root_jumps([_with_root_jump(clean[0], 40, 0.19)])[1] == []   # 11.4 m/s
    s = tr.train(_tiny_config(tmp_path), clean + [glitch], [glitch])
    out = capsys.readouterr().out
    assert f"1 clips left out, their root jumps faster than 12 m/s (capture glitches): {glitch.name}" in out
    assert s["train_clips"] == len(clean)
    from training.errors import UsageError
    with pytest.raises(UsageError, match="every training clip has root jumps"):
        tr.train(_tiny_config(tmp_path / "b"), [glitch], clean[:1])


def test_parallel_batches_are_the_workers_streams_joined_whatever_the_timing():
    motions = _motions(4, 0)
    cfg = tr.TrainConfig(batch=5, window=30, seed=3, data_workers=2)

    def parallel():
        return tr.make_batcher(motions, cfg, np.random.default_rng(cfg.seed))

    a, b = parallel(), parallel()
    try:
        assert isinstance(a, tr.ParallelBatcher) and a.total_frames == sum(m.num_frames for m in motions)
        # worker k plays streams of its own generator (seed, k): 3 + 2 streams here
        shares = [tr.StreamBatcher(motions, n, 30, np.random.default_rng([3, k])) for k, n in enumerate((3, 2))]
        for _ in range(4):
            (ba, ra), (bb, rb) = a.next(), b.next()
            parts = [s.next() for s in shares]
            assert ba["imu_orientation"].shape == (5, 30, 6, 3, 3) and ra.shape == (5,)
            for key in ba:
                torch.testing.assert_close(ba[key], bb[key], rtol=0, atol=0)
                torch.testing.assert_close(ba[key], torch.cat([p[0][key] for p in parts]), rtol=0, atol=0)
            assert torch.equal(ra, rb) and torch.equal(ra, torch.cat([p[1] for p in parts]))
        # a worker that dies is an error, not a hang
        a.procs[1].kill()
        a.procs[1].join()
        with pytest.raises(tr.CommandError, match="worker 1 stopped"):
            for _ in range(10):
                a.next()
    finally:
        a.close()
        b.close()
    assert not any(p.is_alive() for p in a.procs + b.procs)
    assert isinstance(tr.make_batcher(motions, replace(cfg, data_workers=0), np.random.default_rng(0)),
                       tr.StreamBatcher)


def test_a_run_with_data_workers_trains_and_shuts_its_workers_down(tmp_path):
    import multiprocessing
    cfg = tr.TrainConfig(steps=6, batch=4, window=30, size="tiny", warmup=2, device="cpu", data_workers=2,
                         ckpt_dir=str(tmp_path / "ck"), results_dir=str(tmp_path / "res"), progress=False,
                         eval_every_s=1e9)
    summary = tr.train(cfg, _motions(4, 0), _motions(1, 50))
    assert summary["steps"] == 6 and (tmp_path / "ck" / "last.pt").is_file()
    assert not [p for p in multiprocessing.active_children() if p.name.startswith("train-data")]
    assert tr.load_checkpoint_file(tmp_path / "ck" / "last.pt")["batcher"] is None   # resumed: fresh streams
    cfg = _cli(["--data-workers", 3, "--eval-every", 30])
    assert (cfg.data_workers, cfg.eval_every_s) == (3, 30)


def test_data_workers_refuse_a_shared_memory_too_small_for_their_buffers(tmp_path, monkeypatch):
    import os
    stat = os.statvfs_result((4096, 4096, 1000, 1000, 10, 0, 0, 0, 0, 255))   # 40 kB free
    monkeypatch.setattr(tr.os, "statvfs", lambda path: stat)
    cfg = tr.TrainConfig(batch=4, window=30, data_workers=2)
    with pytest.raises(tr.UsageError, match=r"needs \d+ MB of shared memory for its batch buffers, /dev/shm has 0 MB free"):
        tr.make_batcher(_motions(2, 0), cfg, np.random.default_rng(0))
    tr._require_shared_memory(10_000)   # fits in 40 kB


def test_the_shipped_models_say_where_their_weights_come_from():
    import onnx
    for name in (export.FP32_NAME, export.FP16_NAME):
        path = export.DEFAULT_OUT / name
        meta = {p.key: p.value for p in onnx.load(str(path), load_external_data=False).metadata_props}
        label = meta["mocap.model_name"]
        assert label.startswith("mocap-pose lstm"), label
        assert "None" not in label and not label.endswith("?"), f"{path}: {label}"


def _with_joint_jump(motion, at):
    """The motion with the left hip turned 90 deg for the one frame `at` (a swapped marker: the
    left leg jumps out and back)."""
    rot = motion.local_rot.copy()
    c, s = 0.0, 1.0
    rot[at, 1] = rot[at, 1] @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]], np.float32)
    return sk.Motion(motion.name + "_glitch", motion.subject, motion.fps, rot, motion.root_pos, motion.offsets)


def test_clips_are_cut_where_a_joint_jumps_and_short_pieces_left_out(capsys, tmp_path):
    clean = [procedural.make_motion(procedural.KINDS[i], seconds=6.0, seed=i) for i in range(2)]
    T = clean[0].num_frames
    assert all(len(tr.joint_jumps(m)) == 0 for m in clean)     # a walk's feet never move 30 cm a frame
    glitch = _with_joint_jump(clean[0], 200)
    assert tr.joint_jumps(glitch).tolist() == [199, 200]
    out, cut, lost = tr.cut_at_joint_jumps(clean + [glitch])
    assert cut == [glitch.name] and lost == 1                  # the glitch frame itself
    pieces = [m for m in out if m.name.startswith(glitch.name)]
    assert [m.name for m in pieces] == [glitch.name + "#0", glitch.name + "#2"]
    assert np.array_equal(pieces[0].local_rot, glitch.local_rot[:200])
    assert np.array_equal(pieces[1].root_pos, glitch.root_pos[201:]) and pieces[1].num_frames == T - 201
    # a glitch 1 s from the start leaves a piece under MIN_PIECE_S, which is left out
    early = _with_joint_jump(clean[1], 60)
    out, cut, lost = tr.cut_at_joint_jumps([early])
    assert [m.name for m in out] == [early.name + "#2"] and lost == 61
    s = tr.train(_tiny_config(tmp_path), clean + [glitch], clean[:1])
    assert "1 clips cut where a joint jumps more than 30 cm in one 60 Hz frame (capture glitches; 1 " \
           f"frames left out): {glitch.name}" in capsys.readouterr().out
    assert s["train_clips"] == len(clean) + 2          # the glitched clip trains as its two pieces
