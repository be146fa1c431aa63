"""Networks for sensors that may be missing (ModelConfig.masked, model contract 2): the mask in the
network, the mirror ensemble and streaming; SensorMasking in training; widening a contract-1
network; a tiny run with an optional chest exported as contract 2 and run by the engine."""
import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch

from training import export, ort, procedural, sensors as se, skeleton as sk, synthesis as sy, train as tr
from training.errors import UsageError
from training.stride_scaling import MEASURED_KEYS
from training.model import (MirrorEnsemble, ModelConfig, PoseNet, feature_labels, feature_size,
                            with_sensors)

REPO = Path(__file__).resolve().parents[2]
SHIPPED = REPO / "training" / "checkpoints" / "mocap_pose.pt"
SEVEN = se.DEFAULT_SENSORS + ("chest",)
CHEST = SEVEN.index("chest")
MASKED = ModelConfig(48, 48, 2, 48, anchored=True, sensors=SEVEN, optional=("chest",), masked=True)

needs_ort = pytest.mark.skipif(not ort.onnx_runtime_available(),
                               reason="ONNX Runtime not fetched (scripts/fetch_onnxruntime.sh)")


def _visible(net, seed=0):
    """Random weights whose outputs move visibly with the inputs (the real init is near rest)."""
    torch.manual_seed(seed)
    with torch.no_grad():
        net.head[-1].weight.normal_(0, 0.3)
    return net.eval()


def _net(config=MASKED, seed=0):
    torch.manual_seed(seed)
    return _visible(PoseNet(config), seed)


def _inputs(sensors=SEVEN, seconds=1.0):
    ori, acc = export.fixture_inputs(seconds=seconds, sensors=sensors)
    return torch.from_numpy(ori), torch.from_numpy(acc)


def _as_fed(o, a, mask):
    """The inputs as the engine feeds them with this mask: a missing sensor's values zero."""
    return o * mask[..., None, None], a * mask[..., None]


def _mask(o, missing=(), window=None):
    """Ones, with the sensors `missing` absent from every frame and window = (sensor, start, stop)
    absent for those frames."""
    mask = torch.ones(o.shape[:3])
    for k in missing:
        mask[:, :, k] = 0
    if window is not None:
        k, a, b = window
        mask[:, a:b, k] = 0
    return mask


def _assert_valid_rotations(r):
    eye = torch.eye(3).expand_as(r)
    assert torch.isfinite(r).all()
    assert torch.allclose(r.transpose(-1, -2) @ r, eye, atol=1e-5)
    assert torch.allclose(torch.linalg.det(r), torch.ones(r.shape[:-2]), atol=1e-5)


# ------------------------------------------------------------------------------ configuration
def test_the_pelvis_cannot_be_optional_and_optional_sensors_need_the_mask():
    with pytest.raises(ValueError, match="pelvis cannot be optional"):
        PoseNet(replace(MASKED, optional=("pelvis", "chest")))
    with pytest.raises(ValueError, match="optional sensor 'chest' is not one of the network's sensors"):
        PoseNet(replace(MASKED, sensors=se.DEFAULT_SENSORS))
    with pytest.raises(ValueError, match="need a masked network"):
        PoseNet(replace(MASKED, masked=False))
    with pytest.raises(ValueError, match="masked 'yes'"):
        ModelConfig.from_dict({**MASKED.to_dict(), "masked": "yes"})
    # a checkpoint config from before the mask existed is today's unmasked network
    legacy = {k: v for k, v in MASKED.to_dict().items() if k not in ("optional", "masked")}
    old = ModelConfig.from_dict({**legacy, "sensors": list(se.DEFAULT_SENSORS)})
    assert (old.masked, old.optional) == (False, ())
    # the optional sensors come back in the network's order, from a list or a string
    assert ModelConfig.from_dict({**MASKED.to_dict(), "optional": "chest, head"}).optional == ("head", "chest")
    assert feature_size(7, masked=True) == feature_size(7) + 7 == len(feature_labels(SEVEN, True))


def test_a_mask_is_refused_by_a_network_without_one_and_checked_for_shape():
    plain = PoseNet(ModelConfig(32, 32, 1, 32)).eval()
    o, a = _inputs(se.DEFAULT_SENSORS, 0.2)
    with pytest.raises(ValueError, match="has no mask input"):
        plain(o, a, None, torch.ones(o.shape[:3]))
    with pytest.raises(ValueError, match=r"imu_mask must be \(B,T,N\)"):
        _net()(*_inputs(seconds=0.2), None, torch.ones(2, 3, 7))


# ------------------------------------------------------------------------------ the network
def test_whatever_a_missing_sensor_holds_the_answer_is_the_one_for_zero_inputs():
    """The mask, not the values, says a sensor is absent: garbage in a masked-out slot (a random
    matrix, huge accelerations) changes nothing, for the plain network and the mirror pair."""
    for net in (_net(), MirrorEnsemble(_net()).eval()):
        o, a = _inputs()
        mask = _mask(o, missing=[CHEST], window=(1, 10, 40))
        zo, za = _as_fed(o, a, mask)
        junk_o = zo + (1 - mask)[..., None, None] * torch.randn_like(o) * 5
        junk_a = za + (1 - mask)[..., None] * 1e3
        with torch.no_grad():
            ref = net(zo, za, None, mask)
            got = net(junk_o, junk_a, None, mask)
        for x, y in zip(ref[:3], got[:3]):
            assert torch.equal(x, y)


def test_zero_inputs_with_mask_zero_give_finite_rotations_even_without_the_pelvis():
    for net in (_net(), MirrorEnsemble(_net()).eval()):
        o, a = _inputs(seconds=0.5)
        for missing in ([CHEST], list(range(1, 7)), list(range(7))):   # the chest, all but pelvis, all
            mask = _mask(o, missing=missing)
            with torch.no_grad():
                r, v, c, (h, cc) = net(*_as_fed(o, a, mask), None, mask)
            _assert_valid_rotations(r)
            for t in (v, c, h, cc):
                assert torch.isfinite(t).all()


def test_the_network_reads_the_mask():
    """A missing sensor is not the same as a present one at rest: the mask is a feature, and an
    anchored bone of a missing sensor falls back to the rest pose instead of following zeros."""
    net = _net()
    o, a = _inputs(seconds=0.5)
    still_o, still_a = o.clone(), a.clone()
    still_o[:, :, CHEST] = torch.eye(3)          # a chest sensor present, at rest and still
    still_a[:, :, CHEST] = 0
    present, absent = _mask(o), _mask(o, missing=[CHEST])
    with torch.no_grad():
        r_present = net(still_o, still_a, None, present)[0]
        r_absent = net(*_as_fed(o, a, absent), None, absent)[0]
    assert (r_present - r_absent).abs().max() > 1e-3
    # zero residual: the spine3 bone (the chest's) follows a present chest sensor, rest when absent
    torch.manual_seed(0)
    calm = PoseNet(MASKED).eval()
    calm._zero_output_rows([9])
    with torch.no_grad():
        rot = calm(o, a, None, present)[0][0].double().numpy()
        rest = calm(*_as_fed(o, a, absent), None, absent)[0][0].double().numpy()
    g, _ = sk.forward_kinematics(rot, np.zeros((rot.shape[0], 3)), sk.DEFAULT_OFFSETS)
    err = np.degrees(sk.angle_between_rots(g[:, 9], o[0, :, CHEST].double().numpy()))
    assert err.max() < 1e-3
    assert np.degrees(sk.angle_between_rots(rest[:, 9], np.eye(3)[None])).max() < 5.0


def test_an_all_ones_mask_is_the_default_and_streaming_equals_the_whole_clip_with_masks():
    net = _net()
    o, a = _inputs(seconds=0.5)
    with torch.no_grad():
        default = net(o, a)
        ones = net(o, a, None, _mask(o))
    for x, y in zip(default[:3], ones[:3]):
        assert torch.equal(x, y)
    mask = _mask(o, missing=[CHEST], window=(2, 5, 20))
    fo, fa = _as_fed(o, a, mask)
    ens = MirrorEnsemble(net).eval()
    with torch.no_grad():
        whole = ens(fo, fa, None, mask)
        state, parts = None, []
        for t in range(o.shape[1]):
            r, v, c, state = ens(fo[:, t:t + 1], fa[:, t:t + 1], state, mask[:, t:t + 1])
            parts.append((r, v, c))
    for i in range(3):
        assert torch.allclose(torch.cat([p[i] for p in parts], dim=1), whole[i], atol=1e-5)
    # causal: a sensor lost later changes nothing before it
    later = _mask(o, window=(1, 20, 30))
    with torch.no_grad():
        r_later = net(*_as_fed(o, a, later), None, later)[0]
    assert torch.equal(r_later[:, :20], default[0][:, :20])
    assert (r_later[:, 20:] - default[0][:, 20:]).abs().max() > 1e-4


def test_the_mirror_pair_stays_exactly_symmetric_with_masks():
    """The mirror image of a session missing its left wrist for a while is one missing its right
    wrist: the ensemble must mirror the masks with the sensors."""
    net = _net()
    ens = MirrorEnsemble(net).eval()
    o, a = _inputs(seconds=0.5)
    mask = _mask(o, missing=[CHEST], window=(SEVEN.index("left_wrist"), 5, 25))
    fo, fa = _as_fed(o, a, mask)
    m = torch.diag(torch.tensor([-1.0, 1.0, 1.0]))
    swap = se.mirror_indices(SEVEN)
    mo, ma, mm = m @ fo[:, :, swap] @ m, fa[:, :, swap] @ m, mask[:, :, swap]
    with torch.no_grad():
        r, v, c, _ = ens(fo, fa, None, mask)
        rm, vm, cm, _ = ens(mo, ma, None, mm)
        single, single_m = net(fo, fa, None, mask)[0], net(mo, ma, None, mm)[0]
        unswapped = ens(mo, ma, None, mask)[0]   # the mask left as it was: no longer symmetric
    assert torch.allclose(m @ rm[:, :, sk.MIRROR_JOINTS] @ m, r, atol=1e-5)
    assert torch.allclose(vm @ m, v, atol=1e-5)
    assert torch.allclose(cm.flip(-1), c, atol=1e-6)
    assert (m @ single_m[:, :, sk.MIRROR_JOINTS] @ m - single).abs().max() > 1e-2
    assert (unswapped - rm).abs().max() > 1e-3


def test_a_missing_sensor_keeps_the_network_heading_equivariant():
    net = _net()
    o, a = _inputs(seconds=0.5)
    mask = _mask(o, missing=[CHEST], window=(5, 0, 15))
    yaw = torch.from_numpy(sk.rot_axis("y", 1.1).astype(np.float32))
    with torch.no_grad():
        r1, v1, c1, _ = net(*_as_fed(o, a, mask), None, mask)
        r2, v2, c2, _ = net(*_as_fed(yaw @ o, (yaw @ a.unsqueeze(-1)).squeeze(-1), mask), None, mask)
    assert torch.allclose(r2[:, :, 1:], r1[:, :, 1:], atol=1e-4)
    assert torch.allclose(r2[:, :, 0], yaw @ r1[:, :, 0], atol=1e-4)
    assert torch.allclose(v2, (yaw @ v1.unsqueeze(-1)).squeeze(-1), atol=1e-4)


# ------------------------------------------------------------------------------ widening
def test_a_widened_contract_one_network_answers_as_before_while_the_new_sensor_is_missing():
    six = _net(ModelConfig(48, 48, 2, 48, anchored=True))
    seven = with_sensors(six, SEVEN, ("chest",), masked=True).eval()
    assert seven.config.masked and seven.config.optional == ("chest",)
    labels = feature_labels(SEVEN, True)
    first = seven.embed[0].weight
    new_cols = [i for i, (block, name, _) in enumerate(labels) if name == "chest" or block == "mask"]
    assert len(new_cols) == 24 + 7 and float(first[:, new_cols].abs().max()) == 0.0
    o, a = _inputs()
    mask = _mask(o, missing=[CHEST])
    for wrap in (lambda n: n, lambda n: MirrorEnsemble(n).eval()):
        with torch.no_grad():
            before = wrap(six)(o[:, :, :6], a[:, :, :6])
            after = wrap(seven)(*_as_fed(o, a, mask), None, mask)
            with_chest = wrap(seven)(o, a)
        for x, y in zip(before[:3], after[:3]):
            assert torch.allclose(x, y, atol=1e-5)
        # the chest, once present, anchors its bone (spine3): the new sensor is live from the start
        assert (with_chest[0][:, :, 9] - before[0][:, :, 9]).abs().max() > 1e-2
    # the other way round, a sensor left out drops its columns
    back = with_sensors(seven, se.DEFAULT_SENSORS, (), masked=False).eval()
    with torch.no_grad():
        assert torch.allclose(back(o[:, :, :6], a[:, :, :6])[0], six(o[:, :, :6], a[:, :, :6])[0], atol=1e-5)
    with pytest.raises(ValueError, match="needs a pelvis"):
        with_sensors(six, ("head", "chest"))


def test_the_shipped_model_widened_with_an_optional_chest_answers_as_shipped_without_it():
    net = tr.load_weights(SHIPPED).eval()
    seven = with_sensors(net, SEVEN, ("chest",), masked=True).eval()
    o, a = _inputs(seconds=0.5)
    mask = _mask(o, missing=[CHEST])
    with torch.no_grad():
        shipped = MirrorEnsemble(net).eval()(o[:, :, :6], a[:, :, :6])
        widened = MirrorEnsemble(seven).eval()(*_as_fed(o, a, mask), None, mask)
    for x, y in zip(shipped[:3], widened[:3]):
        assert torch.allclose(x, y, atol=1e-5)


# ------------------------------------------------------------------------------ training data
def _sample(seconds=6.0, sensors=SEVEN):
    return sy.synthesize(procedural.make_motion("walk", seconds=seconds, seed=4), sensors=sensors)


def test_sensor_masking_lacks_the_optional_sensors_and_silences_one_sensor_for_a_window():
    s = _sample()
    hold = round(tr.ENGINE_STALE_AFTER_S * s.fps)
    masking = tr.SensorMasking(SEVEN, ("chest",), optional_absent=1.0, window_probability=1.0,
                               window_seconds=(1.0, 2.0))
    rng = np.random.default_rng(0)
    for _ in range(20):
        fed, mask = masking.apply(s, rng)
        assert mask.shape == (s.num_frames, 7) and mask.dtype == np.float32
        assert (mask[:, CHEST] == 0).all() and (mask[:, 0] == 1).all()
        # a missing sensor's inputs are zero, a present one's untouched (except while held)
        off = mask == 0
        assert (fed.imu_orientation[off] == 0).all() and (fed.imu_acceleration[off] == 0).all()
        lost = [k for k in range(1, CHEST) if (mask[:, k] == 0).any()]
        assert len(lost) == 1
        k = lost[0]
        frames = np.flatnonzero(mask[:, k] == 0)
        start, stop = frames[0], frames[-1] + 1
        assert len(frames) == stop - start                                 # one window
        assert 1.0 * s.fps - hold - 1 <= stop - start <= 2.0 * s.fps + 1
        if start >= hold + 1:   # the engine held the last sample before calling it missing
            held = fed.imu_orientation[start - hold:start, k]
            assert np.array_equal(held, np.broadcast_to(held[0], held.shape))
            assert np.array_equal(held[0], s.imu_orientation[start - hold - 1, k])
        others = [j for j in range(7) if j not in (k, CHEST)]
        assert np.array_equal(fed.imu_orientation[:, others], s.imu_orientation[:, others])
    # probabilities: the chest is absent from about half the clips, a window in about a third
    masking = tr.SensorMasking(SEVEN, ("chest",), optional_absent=0.5, window_probability=0.3)
    draws = [masking.apply(s, rng)[1] for _ in range(400)]
    no_chest = np.mean([(m[:, CHEST] == 0).all() for m in draws])
    windows = np.mean([(m[:, :CHEST] == 0).any() for m in draws])
    assert 0.42 < no_chest < 0.58 and 0.22 < windows < 0.38
    # a window takes one sensor of those present, the chest too when it is there
    partly = [sum(0 < (m[:, k] == 0).sum() < len(m) for k in range(7)) for m in draws]
    assert max(partly) == 1 and any((0 < (m[:, CHEST] == 0).sum() < len(m)) for m in draws)


def test_masked_batches_carry_the_mask_and_unmasked_ones_do_not():
    motions = [procedural.make_motion(k, seconds=3.0, seed=i) for i, k in enumerate(procedural.KINDS)]
    masking = tr.SensorMasking(SEVEN, ("chest",), optional_absent=0.5, window_probability=1.0)
    b = tr.StreamBatcher(motions, 6, 40, np.random.default_rng(1), sensors=SEVEN, masking=masking)
    seen = np.zeros(2)
    for _ in range(5):
        batch, _ = b.next()
        mask = batch["imu_mask"]
        assert mask.shape == (6, 40, 7) and set(np.unique(mask.numpy())) <= {0.0, 1.0}
        assert (batch["imu_orientation"][mask == 0] == 0).all()
        assert (mask[:, :, 0] == 1).all()
        seen += [(mask[:, :, CHEST] == 0).any(), (mask[:, :, CHEST] == 1).any()]
    assert (seen > 0).all()   # six- and seven-sensor streams both
    plain = tr.StreamBatcher(motions, 2, 40, np.random.default_rng(1))
    assert "imu_mask" not in plain.next()[0]


def test_data_workers_carry_the_mask_as_in_process_streams_do():
    motions = [procedural.make_motion(k, seconds=3.0, seed=i) for i, k in enumerate(procedural.KINDS)]
    cfg = tr.TrainConfig(batch=4, window=30, seed=2, data_workers=2, sensor_dropout=1.0)
    net_config = replace(MASKED, sensors=SEVEN)
    masking = tr.sensor_masking(cfg, net_config)
    par = tr.make_batcher(motions, cfg, np.random.default_rng(cfg.seed), SEVEN, masking)
    try:
        shares = [tr.StreamBatcher(motions, 2, 30, np.random.default_rng([2, k]), sensors=SEVEN, masking=masking)
                  for k in range(2)]
        for _ in range(3):
            got, _ = par.next()
            parts = [s.next()[0] for s in shares]
            for key in ("imu_mask", "imu_orientation"):
                torch.testing.assert_close(got[key], torch.cat([p[key] for p in parts]), rtol=0, atol=0)
    finally:
        par.close()


# ------------------------------------------------------------------------------ training runs
def _cli(argv):
    parser = argparse.ArgumentParser()
    tr.add_arguments(parser)
    return tr.config_from_args(parser.parse_args([str(x) for x in argv]))


def test_the_missing_sensor_options_reach_the_training_config(capsys):
    cfg = _cli(["--sensors", ",".join(SEVEN), "--optional", "chest", "--sensor-dropout", "0.5",
                "--dropout-seconds", "1,3", "--optional-absent", "0.25"])
    assert (cfg.sensors, cfg.optional, cfg.sensor_dropout, cfg.dropout_seconds, cfg.optional_absent) == \
        (SEVEN, ("chest",), 0.5, (1.0, 3.0), 0.25)
    assert _cli(["--masked"]).masked and not _cli([]).masked
    for bad, says in ((["--dropout-seconds", "3,1"], "expected 0 < A <= B"),
                      (["--dropout-seconds", "2"], "is not two numbers"),
                      (["--sensors", "pelvis,tail"], "unknown segment 'tail'"),
                      (["--optional", "tail"], "unknown segment 'tail'"),
                      (["--sensor-dropout", "2"], "is not a probability")):
        with pytest.raises(SystemExit):
            _cli(bad)
        assert says in capsys.readouterr().err
    # what the network becomes: asked for, else the warm start's own, never silently unmasked
    six = ModelConfig()
    assert tr.network_sensors(tr.TrainConfig(), None) == (se.DEFAULT_SENSORS, (), False)
    assert tr.network_sensors(tr.TrainConfig(sensor_dropout=0.1), None) == (se.DEFAULT_SENSORS, (), True)
    assert tr.network_sensors(tr.TrainConfig(sensors=SEVEN, optional=("chest",)), six) == (SEVEN, ("chest",), True)
    assert tr.network_sensors(tr.TrainConfig(), MASKED) == (SEVEN, ("chest",), True)
    with pytest.raises(UsageError, match="--sensors / --optional: the pelvis cannot be optional"):
        tr.network_sensors(tr.TrainConfig(sensors=SEVEN, optional=("pelvis",)), None)
    with pytest.raises(UsageError, match="optional sensor 'chest' is not one of the network's sensors"):
        tr.network_sensors(tr.TrainConfig(optional=("chest",)), six)


def _run(tmp_path, name, **kw):
    return tr.TrainConfig(**{**dict(size="tiny", batch=3, window=40, lr=3e-3, warmup=2, steps=6,
                                    budget_minutes=1e6, ckpt_dir=str(tmp_path / name / "ck"),
                                    results_dir=str(tmp_path / name / "res"), progress=False, smoke=True,
                                    eval_every_s=1e9, ckpt_every_s=1e9, sensors=SEVEN, optional=("chest",),
                                    sensor_dropout=0.5), **kw})


def _motions(n, seed):
    return [procedural.make_motion(procedural.KINDS[i % 5], seconds=3.0, seed=seed + i) for i in range(n)]


def test_a_masked_run_stopped_and_resumed_ends_as_an_uninterrupted_one(tmp_path):
    """The streams' masks are part of the saved batcher: a resumed run draws the same batches."""
    train_m = _motions(4, 0)
    assert tr.train(_run(tmp_path, "whole"), train_m, [])["steps"] == 6
    split = _run(tmp_path, "split", stop_after=3)
    tr.train(split, train_m, [])
    tr.train(replace(split, resume=True, stop_after=None), train_m, [])
    a = tr.load_checkpoint_file(tmp_path / "whole" / "ck" / "last.pt")
    b = tr.load_checkpoint_file(tmp_path / "split" / "ck" / "last.pt")
    for key, value in a["model"].items():
        assert torch.equal(value, b["model"][key]), key
    assert any(m is not None and (m == 0).any() for m in a["batcher"]["masks"])
    # the network is the run's: other optional sensors or no mask are refused on resume
    for change in (dict(optional=()), dict(sensors=se.DEFAULT_SENSORS)):
        with pytest.raises(UsageError, match="contradicts"):
            tr.check_resume_config(replace(split, **change), b, "last.pt")
    tr.check_resume_config(replace(split, sensors=None, optional=None, masked=False), b, "last.pt")


def test_init_from_a_contract_one_checkpoint_copies_every_weight_into_the_masked_network(tmp_path):
    six = tr.train(tr.TrainConfig(size="tiny", batch=2, window=30, warmup=2, steps=2, budget_minutes=1e6,
                                  ckpt_dir=str(tmp_path / "six" / "ck"), results_dir=str(tmp_path / "six" / "res"),
                                  progress=False, smoke=True, eval_every_s=1e9), _motions(2, 0), [])
    assert six["steps"] == 2
    source = tmp_path / "six" / "ck" / "last.pt"
    old = tr.load_weights(source)
    tr.train(_run(tmp_path, "seven", init_from=str(source), lr=1e-9, warmup=1, steps=1), _motions(2, 0), [])
    new = tr.load_weights(tmp_path / "seven" / "ck" / "last.pt")
    assert (new.config.sensors, new.config.optional, new.config.masked) == (SEVEN, ("chest",), True)
    labels = feature_labels(SEVEN, True)
    old_cols = {label: i for i, label in enumerate(feature_labels(se.DEFAULT_SENSORS))}
    w_new, w_old = new.embed[0].weight.detach(), old.embed[0].weight.detach()
    for i, label in enumerate(labels):   # one Adam step of lr 1e-9 moves a weight by ~1e-9
        want = w_old[:, old_cols[label]] if label in old_cols else torch.zeros(w_new.shape[0])
        assert torch.allclose(w_new[:, i], want, atol=1e-6), label
    for key, value in old.state_dict().items():
        if key != "embed.0.weight":
            assert torch.allclose(new.state_dict()[key], value, atol=1e-6), key


@pytest.fixture(scope="module")
def chest_run(tmp_path_factory):
    """A few steps with an optional chest and sensor drop-outs, exported as shipped (mirror pair)."""
    d = tmp_path_factory.mktemp("chest")
    summary = tr.train(_run(d, "run", steps=4), _motions(3, 0), _motions(2, 50))
    net, ck = export.load_checkpoint(d / "run" / "ck" / "best.pt")
    with torch.no_grad():   # a few steps leave the outputs near rest: make them depend on the input
        net.head[-1].weight.normal_(0, 0.05)
    model = MirrorEnsemble(net).eval()
    info = export.export(model, d / "onnx", model_name="chest test", check=ort.onnx_runtime_available())
    return summary, model, d / "onnx", info


def test_a_tiny_run_with_an_optional_chest_writes_a_masked_checkpoint(chest_run):
    summary, model, _, _ = chest_run
    assert summary["steps"] == 4 and np.isfinite(summary["best"]["val_loss"])
    c = model.config
    assert (c.sensors, c.optional, c.masked) == (SEVEN, ("chest",), True)


def test_a_masked_network_exports_model_contract_two(chest_run):
    import onnx
    _, model, d, _ = chest_run
    for name, precision in ((export.FP32_NAME, "fp32"), (export.FP16_NAME, "fp16")):
        m = onnx.load(str(d / name))
        onnx.checker.check_model(m)
        meta = {p.key: p.value for p in m.metadata_props}
        assert meta["mocap.contract_version"] == "2" and meta["mocap.precision"] == precision
        assert meta["mocap.sensor_order"] == ",".join(SEVEN)
        assert meta["mocap.sensor_required"] == "1,1,1,1,1,1,0"
        assert list(meta)[:4] == ["mocap.contract_version", "mocap.frame_rate", "mocap.sensor_order",
                                  "mocap.sensor_required"]
        dims = {i.name: [x.dim_param or x.dim_value for x in i.type.tensor_type.shape.dim] for i in m.graph.input}
        L, H = model.state_layers, model.state_size
        assert dims == {"imu_orientation": ["B", "T", 7, 3, 3], "imu_acceleration": ["B", "T", 7, 3],
                        "imu_mask": ["B", "T", 7], "state_in_h": [L, "B", H], "state_in_c": [L, "B", H]}
        assert [i.name for i in m.graph.input] == export.MASKED_INPUT_NAMES


@needs_ort
def test_the_engine_opens_the_contract_two_export_and_runs_it_with_a_mask_as_pytorch_does(chest_run):
    _, model, d, info = chest_run
    check = info["check"]
    assert check["fp32"]["joint_rotations"] <= export.CHECK_TOLERANCE["fp32"]
    assert check["fp16"]["joint_rotations"] <= export.CHECK_TOLERANCE["fp16"]
    got = ort.model_info(d / export.FP32_NAME)
    assert (got["contract_version"], got["sensor_count"], got["optional"], got["imu_mask"]) == ("2", 7, ["chest"], True)
    assert got["sensor_order"] == ",".join(SEVEN)
    # the export check's mask really drops sensors, and the answer depends on it
    ori, acc = export.fixture_inputs(seconds=1.0, sensors=SEVEN)
    mask, fo, fa = export.fixture_mask(model, ori, acc)
    assert (mask[1:, :, CHEST] == 0).all() and (mask[0] == 1).all() and (mask[1:, :, :CHEST] == 0).any()
    ref = export.torch_outputs(model, fo, fa, mask)
    full = export.torch_outputs(model, fo, fa, np.ones_like(mask))
    assert np.abs(ref["joint_rotations"] - full["joint_rotations"]).max() > 1e-3
    for stream in (False, True):
        out = ort.run_onnx(d / export.FP32_NAME, fo, fa, mask=mask, stream=stream)
        for key in export.OUTPUT_NAMES:
            assert np.abs(out[key] - ref[key]).max() <= export.CHECK_TOLERANCE["fp32"], (key, stream)
    # without a mask the engine feeds every sensor as present
    out = ort.run_onnx(d / export.FP32_NAME, ori, acc)
    assert np.abs(out["joint_rotations"] - export.torch_outputs(model, ori, acc)["joint_rotations"]).max() <= 1e-4
    with pytest.raises(ValueError, match="imu_mask must be"):
        ort.run_onnx(d / export.FP32_NAME, fo, fa, mask=mask[:, :, :6])


@needs_ort
def test_a_contract_one_model_takes_no_mask(tmp_path):
    net = export.untrained_model(seed=0, config=ModelConfig(32, 32, 1, 32))
    export.export(net, tmp_path, check=False)
    got = ort.model_info(tmp_path / export.FP32_NAME)
    assert (got["contract_version"], got["sensor_count"], got["optional"], got["imu_mask"]) == ("1", 6, [], False)
    ori, acc = export.fixture_inputs(seconds=0.2)
    with pytest.raises(ort.OnnxRuntimeError, match="holds imu_mask but the model has no mask input"):
        ort.run_onnx(tmp_path / export.FP32_NAME, ori, acc, mask=np.ones(ori.shape[:3], np.float32))


def test_a_masked_six_sensor_network_exports_contract_two_with_every_sensor_required(tmp_path):
    import onnx
    net = export.untrained_model(seed=0, config=ModelConfig(32, 32, 1, 32, masked=True))
    export.export(net, tmp_path, check=False)
    meta = {p.key: p.value for p in onnx.load(str(tmp_path / export.FP32_NAME)).metadata_props}
    assert (meta["mocap.contract_version"], meta["mocap.sensor_required"]) == ("2", "1,1,1,1,1,1")


# ------------------------------------------------------------------------------ contract 1 unchanged
@needs_ort
def test_re_exporting_the_shipped_checkpoint_reproduces_the_shipped_fp32_model(tmp_path):
    """The unmasked path is the shipped model's: the same weights, inputs, outputs and metadata as
    the committed file (but the stride law, which is measured afterwards), and the same answers from ONNX Runtime. (Not the same bytes: the committed
    file was written by an earlier exporter whose graph names two constants and the initializers
    differently, and the graph's bytes depend on the torch version.)"""
    import onnx
    from onnx import numpy_helper
    net, ck = export.load_checkpoint(SHIPPED)
    ens = MirrorEnsemble(net).eval()
    name = f"mocap-pose lstm{net.state_layers}x{net.state_size} mirror-averaged" + export.checkpoint_label(ck)
    export.export_fp32(ens, tmp_path / "fp32.onnx", name)
    shipped_path = export.DEFAULT_OUT / export.FP32_NAME
    new, shipped = onnx.load(str(tmp_path / "fp32.onnx")), onnx.load(str(shipped_path))

    def io(m):
        return [(v.name, [d.dim_param or d.dim_value for d in v.type.tensor_type.shape.dim])
                for v in list(m.graph.input) + list(m.graph.output)]

    def weights(m):
        return sorted(numpy_helper.to_array(i).tobytes() for i in m.graph.initializer)

    assert io(new) == io(shipped)
    # the stride law is measured after export (training stride-scaling --write), not exported
    assert [(p.key, p.value) for p in new.metadata_props] == \
        [(p.key, p.value) for p in shipped.metadata_props if p.key not in MEASURED_KEYS]
    assert weights(new) == weights(shipped)
    ori, acc = export.fixture_inputs(seconds=0.5)
    a = ort.run_onnx(tmp_path / "fp32.onnx", ori, acc)
    b = ort.run_onnx(shipped_path, ori, acc)
    for key in export.OUTPUT_NAMES:
        assert np.abs(a[key] - b[key]).max() <= 1e-6, key


# ------------------------------------------------------------------------------ evaluate with masks
def test_a_sensor_missing_from_a_clip_is_masked_as_the_engine_feeds_it_and_the_baseline_rests_its_bone():
    from training import evaluate as ev
    clip = ev.synthesize_clip(procedural.make_motion("walk", 1.0, seed=0), np.random.default_rng(0),
                              sensors=SEVEN)
    gone = ev.without_sensors(clip, ("chest",))
    assert gone.mask.shape == clip.imu_orientation.shape[:2]
    assert (gone.mask[:, CHEST] == 0).all() and (np.delete(gone.mask, CHEST, axis=1) == 1).all()
    assert not gone.imu_orientation[:, CHEST].any() and not gone.imu_acceleration[:, CHEST].any()
    assert np.array_equal(gone.imu_orientation[:, :CHEST], clip.imu_orientation[:, :CHEST])
    chest_bone = se.sensor_bones("hand", SEVEN)[CHEST]
    with_chest = ev.predict_baseline(clip).local_rot[:, chest_bone]
    without = ev.predict_baseline(gone).local_rot[:, chest_bone]
    assert np.abs(with_chest - np.eye(3)).max() > 1e-3          # the chest sensor turns spine3
    assert np.array_equal(without, np.broadcast_to(np.eye(3), without.shape))
    with pytest.raises(UsageError, match="not among the clip's sensors"):
        ev.without_sensors(ev.synthesize_clip(procedural.make_motion("walk", 1.0, seed=0),
                                              np.random.default_rng(0)), ("chest",))


def test_evaluate_refuses_a_missing_sensor_for_a_network_without_the_mask_and_names_bad_absent_lists():
    from training import evaluate as ev
    clip = ev.without_sensors(ev.synthesize_clip(procedural.make_motion("walk", 1.0, seed=0),
                                                 np.random.default_rng(0)), ("head",))
    with pytest.raises(UsageError, match="no sensor mask"):
        ev.predict_torch(PoseNet(ModelConfig(16, 8, 1, 16)).eval(), [clip])
    assert ev.absent_sensors(None, SEVEN) == () and ev.absent_sensors("chest", SEVEN) == ("chest",)
    with pytest.raises(UsageError, match="chest is not a sensor of the evaluated models"):
        ev.absent_sensors("chest", se.DEFAULT_SENSORS)
    with pytest.raises(UsageError, match="the pelvis cannot be missing"):
        ev.absent_sensors("pelvis", SEVEN)
    with pytest.raises(UsageError, match="--absent"):
        ev.absent_sensors("spleen", SEVEN)


@needs_ort
def test_evaluate_scores_a_contract_two_model_with_and_without_its_optional_sensor(chest_run, tmp_path):
    """The PyTorch network and its ONNX export get the same masked inputs and give the same
    figures; the chest's absence changes them; a contract-1 model cannot be scored on seven."""
    from training import evaluate as ev
    _, model, d, _ = chest_run
    ckpt = tmp_path / "chest.pt"
    torch.save({"model": model.net.state_dict(), "config": model.config.to_dict()}, ckpt)
    motions = [procedural.make_motion(k, 4.0, seed=i) for i, k in enumerate(["walk", "turn"])]
    onnx_path = d / export.FP32_NAME
    assert ev.expected_sensors(None, [onnx_path]) == SEVEN and ev.expected_sensors(ckpt) == SEVEN
    runs = {}
    for absent in ((), ("chest",)):
        r = ev.evaluate(motions, [onnx_path], ckpt, tmp_path / f"r{len(absent)}", seed=1, latency=False,
                        sensors=SEVEN, absent=absent)["results"]
        assert r["ONNX fp32"]["angle_all"] == pytest.approx(r["PyTorch fp32"]["angle_all"], abs=0.02)
        assert r["ONNX fp32"]["pos"] == pytest.approx(r["PyTorch fp32"]["pos"], abs=0.02)
        runs[absent] = r
    assert abs(runs[()]["PyTorch fp32"]["angle_all"] - runs[("chest",)]["PyTorch fp32"]["angle_all"]) > 1e-3
    text = (tmp_path / "r1" / "evaluation.md").read_text()
    assert "Sensors: 6 (pelvis, left_wrist, right_wrist, left_shin, right_shin, head); missing for " \
           "the whole clip, masked: chest." in text
    assert "Sensors: 7" in (tmp_path / "r0" / "evaluation.md").read_text()
    six = tmp_path / "six"
    export.export(export.untrained_model(seed=0, config=ModelConfig(32, 32, 1, 32)), six, check=False)
    with pytest.raises(UsageError, match="reads the sensors pelvis,left_wrist,right_wrist,left_shin,right_shin,head"):
        ev.evaluate(motions[:1], [six / export.FP32_NAME], None, tmp_path / "r6", latency=False, sensors=SEVEN)
