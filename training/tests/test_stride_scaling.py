"""training stride-scaling: the exponent of the height input's stride gain, fitted and stored.

fit() gets clips whose truth moves S times as fast on a body S times the size while the
"model" reads only part of that (predicted speed S^(1 - e0)): it must find the gain S^e0 for
every size and e0 itself. write_metadata must add exactly the two keys, leave the rest of the
file alone, and the engine must read them back (mocapctl model-info)."""
import numpy as np
import onnx
import pytest

from training import export, ort, skeleton as sk, stride_scaling as ss, train as tr
from training.__main__ import main
from training.errors import CommandError

needs_ort = pytest.mark.skipif(not ort.onnx_runtime_available(),
                               reason="ONNX Runtime not available (scripts/fetch_onnxruntime.sh)")
FPS = 60.0


def _clips(scale, true_exponent, seconds=14.0, seeds=(0, 1, 2)):
    """Clips walking along changing headings: truth S x the base speed, 'prediction' S^(1-e0) x."""
    velocities, roots, rates = [], [], []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        n = int(seconds * FPS)
        heading = np.cumsum(rng.normal(0, 0.02, n))
        base = np.stack([np.cos(heading), np.zeros(n), np.sin(heading)], -1) * (1.0 + 0.3 * rng.random())
        true_v = scale * base
        roots.append(np.concatenate([np.zeros((1, 3)), np.cumsum(true_v[1:], 0) / FPS]))
        velocities.append(scale ** (1.0 - true_exponent) * base)
        rates.append(FPS)
    return velocities, roots, rates


@pytest.mark.parametrize("true_exponent", [0.3, 0.57, 1.0])
def test_fit_finds_the_gain_of_every_size_and_the_shared_exponent(true_exponent):
    per_scale = {s: _clips(s, true_exponent) for s in (0.86, 0.93, 1.0, 1.07, 1.14)}
    result = ss.fit(per_scale)
    assert result["exponent"] == pytest.approx(true_exponent, abs=0.011)
    for s, row in result["rows"].items():
        assert row["best_gain"] == pytest.approx(s ** true_exponent, abs=0.003)
        # a 10 s window covers 9-17 m: the 0.005 gain grid leaves a few centimetres
        assert row["drift_best"] < 0.05 and row["drift_fitted"] < 0.08
        if s != 1.0:
            assert row["drift_gain_1"] > 4 * row["drift_fitted"]


def test_training_height_follows_the_clips_skeleton():
    def motion(scale):
        return sk.Motion("m", 1, FPS, np.zeros((2, 24, 3, 3)), np.zeros((2, 3)), sk.DEFAULT_OFFSETS * scale)
    assert ss.training_height([motion(1.0)]) == pytest.approx(sk.STANDING_HEIGHT)
    assert ss.training_height([motion(0.98), motion(0.99)]) == pytest.approx(0.985 * sk.STANDING_HEIGHT)


@pytest.fixture(scope="module")
def tiny_model(tmp_path_factory):
    path = tmp_path_factory.mktemp("stride") / "tiny_fp32.onnx"
    export.export_fp32(export.untrained_model(seed=4, config=tr.SIZES["tiny"]).eval(), path, "tiny")
    return path


def test_write_metadata_adds_the_two_keys_and_keeps_everything_else(tiny_model, tmp_path):
    path = tmp_path / "m.onnx"
    path.write_bytes(tiny_model.read_bytes())
    before = onnx.load(str(path))
    ss.write_metadata(path, 1.7224, 0.571)
    after = onnx.load(str(path))
    meta_before = {p.key: p.value for p in before.metadata_props}
    meta_after = {p.key: p.value for p in after.metadata_props}
    assert meta_after == meta_before | {"mocap.training_height": "1.722", "mocap.stride_exponent": "0.57"}
    assert after.graph.SerializeToString() == before.graph.SerializeToString()
    ss.write_metadata(path, 1.80, 0.4)   # written again: replaced, not repeated
    keys = [p.key for p in onnx.load(str(path)).metadata_props]
    assert keys.count("mocap.stride_exponent") == 1
    assert {p.key: p.value for p in onnx.load(str(path)).metadata_props}["mocap.stride_exponent"] == "0.40"


def test_write_metadata_refuses_a_file_that_is_not_a_pose_model(tmp_path):
    from onnx import TensorProto, helper
    graph = helper.make_graph([helper.make_node("Identity", ["x"], ["y"])], "g",
                              [helper.make_tensor_value_info("x", TensorProto.FLOAT, [1])],
                              [helper.make_tensor_value_info("y", TensorProto.FLOAT, [1])])
    path = tmp_path / "other.onnx"
    onnx.save(helper.make_model(graph), str(path))
    with pytest.raises(CommandError, match="not a mocap pose model"):
        ss.write_metadata(path, 1.72, 0.5)


@needs_ort
def test_the_engine_reads_the_written_scaling(tiny_model, tmp_path):
    path = tmp_path / "m.onnx"
    path.write_bytes(tiny_model.read_bytes())
    assert "training_height" not in ort.model_info(str(path))
    ss.write_metadata(path, 1.72, 0.57)
    info = ort.model_info(str(path))
    assert info["training_height"] == pytest.approx(1.72)
    assert info["stride_exponent"] == pytest.approx(0.57)


def test_shipped_models_carry_one_stride_law_per_set_of_weights():
    """fp32, fp16 and int8 share weights and so their exponent; every shipped model has one."""
    models = sorted(export.DEFAULT_OUT.glob("mocap_pose_*.onnx"))
    assert len(models) >= 4
    meta = {m.name: {p.key: p.value for p in onnx.load(str(m), load_external_data=False).metadata_props}
            for m in models}
    for name, m in meta.items():
        assert 1.6 <= float(m["mocap.training_height"]) <= 1.8, name
        assert 0.0 < float(m["mocap.stride_exponent"]) < 1.0, name
    six = {meta[n]["mocap.stride_exponent"] for n in meta if "chest" not in n}
    assert len(six) == 1, six


def test_cli_refuses_bad_scales(capsys):
    with pytest.raises(SystemExit):
        main(["stride-scaling", "--model", "x.onnx", "--scales", "1.0"])
    assert "at least one other than 1" in capsys.readouterr().err
