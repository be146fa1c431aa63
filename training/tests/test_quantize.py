"""training quantize: int8 weights for the pose model (graph rewrite, contract, weights within
half a quantisation step, the committed int8 file, ONNX Runtime against fp32)."""
import numpy as np
import onnx
import pytest
from onnx import numpy_helper

from training import export, ort, quantize as qz, train as tr
from training.__main__ import main
from training.errors import UsageError
from training.model import _COLUMN_ORDER, MirrorEnsemble, NUM_JOINTS, OUTPUT_SIZE

SHIPPED_FP32 = qz.DEFAULT_MODEL
SHIPPED_INT8 = qz.DEFAULT_OUT
needs_ort = pytest.mark.skipif(not ort.onnx_runtime_available(),
                               reason="ONNX Runtime not available (scripts/fetch_onnxruntime.sh)")


@pytest.fixture(scope="module")
def tiny_fp32(tmp_path_factory):
    """A small mirror-averaged network exported as the shipped one is (random weights)."""
    path = tmp_path_factory.mktemp("tiny") / "tiny_fp32.onnx"
    net = MirrorEnsemble(export.untrained_model(seed=3, config=tr.SIZES["tiny"])).eval()
    export.export_fp32(net, path, "tiny test network")
    return path


def _inits(model) -> dict:
    return {i.name: numpy_helper.to_array(i) for i in model.graph.initializer}


def _meta(model) -> dict:
    return {p.key: p.value for p in model.metadata_props}


def _io(model) -> list:
    return [(v.name, v.type.SerializeToString()) for v in list(model.graph.input) + list(model.graph.output)]


def _within_half_a_step(original, q, scale, axis):
    """Every weight reproduced by q * scale within half its scale step (float rounding aside)."""
    assert q.dtype == np.int8 and np.abs(q.astype(int)).max() <= qz.QMAX
    err = np.abs(qz.dequantize(q, scale, axis) - original)
    step = np.expand_dims(scale, axis)
    assert np.all(err <= 0.5 * step * (1 + 1e-5) + 1e-12), float((err / step).max())


def _weight_pairs(fp32, int8):
    """(original fp32 array, int8 array, scale, axis, what) for every quantised weight of int8,
    mapped back to the fp32 model's layout."""
    a, b = _inits(fp32), _inits(int8)
    lstm32 = [n for n in fp32.graph.node if n.op_type == "LSTM"]
    lstm8 = [n for n in int8.graph.node if n.op_type == "DynamicQuantizeLSTM"]
    mm8 = [n for n in int8.graph.node if n.op_type == "DynamicQuantizeMatMul"]
    out = []
    for n32, n8 in zip(lstm32, lstm8):
        for k, scale_at in ((1, 8), (2, 10)):   # W with W_scale, R with R_scale
            original = np.transpose(a[n32.input[k]], (0, 2, 1))   # [dir, 4H, in] -> [dir, in, 4H]
            out.append((original, b[n8.input[k]], b[n8.input[scale_at]], 1, f"{n8.name} input {k}"))
    # the weight matrices by name where both files are one graph, else by shape (each of the
    # shipped four has its own); the network alone writes the joints' columns in (joint, row,
    # column) order, where the complete graph gathers them so
    matrices = {a[n.input[1]].shape: a[n.input[1]] for n in fp32.graph.node
                if n.op_type == "MatMul" and n.input[1] in a and a[n.input[1]].ndim == 2
                and min(a[n.input[1]].shape) >= qz.MIN_WEIGHT_DIM}
    reordered = _COLUMN_ORDER + list(range(NUM_JOINTS * 6, OUTPUT_SIZE))
    for n8 in mm8:
        q = b[n8.input[1]]
        source = n8.input[1][:-len("_int8")]
        original = a[source] if source in a else matrices[q.shape]
        if q.shape[1] == OUTPUT_SIZE and _meta(int8).get("mocap.contract_version") == "3":
            original = original[:, reordered]
        out.append((original, q, b[n8.input[2]], 0, n8.name))
    return lstm32, lstm8, mm8, out


# ------------------------------------------------------------------------------ weights
def test_symmetric_int8_is_within_half_a_step_per_column():
    rng = np.random.default_rng(0)
    w = rng.normal(0, 0.05, (40, 6)).astype(np.float32)
    w[:, 2] = 0.0                      # a dead column
    w[7, 4] = 3.0                      # an outlier sets its own column's scale only
    q, scale = qz.symmetric_int8(w, axis=0)
    assert q.shape == w.shape and scale.shape == (6,)
    live = [0, 1, 3, 4, 5]
    assert np.allclose(scale[live], np.abs(w[:, live]).max(axis=0) / 127, rtol=1e-6, atol=0)
    assert scale[2] == 1.0 and np.all(q[:, 2] == 0) and q[7, 4] == 127
    assert scale[4] > 10 * scale[[0, 1, 3, 5]].max()   # the outlier's scale stays in its column
    _within_half_a_step(w, q, scale, 0)
    assert np.all(qz.dequantize(q, scale, 0)[w == 0] == 0)       # zero stays exactly zero
    assert np.all(np.sign(q) == -np.sign(qz.symmetric_int8(-w, axis=0)[0]))   # symmetric


def test_symmetric_int8_refuses_non_finite_weights():
    with pytest.raises(qz.CommandError, match="NaN or inf"):
        qz.symmetric_int8(np.array([[1.0, np.nan]], np.float32), axis=0)


# ------------------------------------------------------------------------------ graph
def test_quantized_graph_keeps_the_contract_and_its_weights(tiny_fp32):
    fp32 = onnx.load(str(tiny_fp32))
    int8, summary = qz.quantize_model(fp32)
    onnx.checker.check_model(int8)
    assert any(o.domain == qz.CONTRIB_DOMAIN for o in int8.opset_import)
    assert _io(int8) == _io(fp32)
    m32, m8 = _meta(fp32), _meta(int8)
    assert m8.pop("mocap.precision") == "int8" and m32.pop("mocap.precision") == "fp32"
    assert m8.pop("mocap.model_name") == m32.pop("mocap.model_name") + ", int8 weights"
    assert m8 == m32
    ops = [n.op_type for n in int8.graph.node]
    assert "LSTM" not in ops and ops.count("DynamicQuantizeLSTM") == 1    # tiny: one layer
    assert ops.count("DynamicQuantizeMatMul") == 4                        # embed x2, head x2
    # every remaining float MatMul multiplies by something that is not a weight (3x3 geometry)
    inits = _inits(int8)
    for n in int8.graph.node:
        if n.op_type == "MatMul":
            assert n.input[1] not in inits or min(inits[n.input[1]].shape) < qz.MIN_WEIGHT_DIM
    lstm32, lstm8, mm8, pairs = _weight_pairs(fp32, int8)
    assert len(pairs) == 2 + 4 and summary["matmuls"] == 4 and summary["lstms"] == 1
    assert summary["int8_values"] == sum(p[1].size for p in pairs)
    for original, q, scale, axis, what in pairs:
        assert q.dtype == np.int8, what
        _within_half_a_step(original, q, scale, axis)
    # LSTM: same activations and sizes, zero points 0, the biases and states untouched
    for n32, n8 in zip(lstm32, lstm8):
        assert len(n8.input) == 12 and n8.domain == qz.CONTRIB_DOMAIN
        assert {a.name: a for a in n32.attribute} == {a.name: a for a in n8.attribute}
        assert [n32.input[i] for i in (0, 3, 5, 6)] == [n8.input[i] for i in (0, 3, 5, 6)]
        for zp in (9, 11):
            assert inits[n8.input[zp]].dtype == np.int8 and not inits[n8.input[zp]].any()
        assert list(n8.output) == list(n32.output)
    # the bias Adds were folded into the quantised MatMuls
    for n in mm8:
        assert len(n.input) == 5 and n.input[3] == "" and inits[n.input[4]].shape == (inits[n.input[1]].shape[1],)
    # the fp32 weights are gone (they would double the file)
    fp32_weights = {n.input[k] for n in lstm32 for k in (1, 2)}
    assert not fp32_weights & set(inits)


def test_quantize_refuses_what_it_cannot_quantise(tiny_fp32, tmp_path):
    fp32 = onnx.load(str(tiny_fp32))
    with pytest.raises(UsageError, match="precision is 'fp16'"):
        fp16 = tmp_path / "tiny_fp16.onnx"
        export.convert_fp16(tiny_fp32, fp16)
        qz.quantize_model(onnx.load(str(fp16)))
    int8, _ = qz.quantize_model(fp32)
    with pytest.raises(UsageError, match="precision is 'int8'"):
        qz.quantize_model(int8)
    bare = onnx.load(str(tiny_fp32))
    keep = [n for n in bare.graph.node if n.op_type not in ("LSTM", "MatMul")]
    del bare.graph.node[:]
    bare.graph.node.extend(keep)
    with pytest.raises(UsageError, match="nothing to quantise"):
        qz.quantize_model(bare)
    with pytest.raises(UsageError, match="is the model to quantise"):
        qz.quantize_file(tiny_fp32, tiny_fp32, check=False)


def test_cli_errors_are_one_line(tiny_fp32, tmp_path, capsys):
    text = tmp_path / "notes.txt"
    text.write_text("not a model\n")
    for argv, says in ((["--model", tmp_path / "nope.onnx"], "no such file"),
                       (["--model", text, "--out", tmp_path / "o.onnx"], "not an ONNX model"),
                       (["--model", tiny_fp32, "--out", tiny_fp32], "is the model to quantise"),
                       (["--model", tiny_fp32, "--out", tmp_path / "missing.onnx", "--measure"],
                        "--measure compares existing models")):
        capsys.readouterr()
        assert main(["quantize", *map(str, argv)]) == 1
        err = capsys.readouterr().err.strip()
        assert err.startswith("training quantize: ") and says in err and "Traceback" not in err, err
    assert not (tmp_path / "o.onnx").exists()


# ------------------------------------------------------------------------------ the committed file
def test_committed_int8_model_is_the_quantised_shipped_model():
    """Fails when the int8 file is missing, not quantised, or stale (fp32 exported again without
    exporting its network alone and running `python3 -m training quantize` on it). The int8 file
    is the network alone (model contract 3, `export --geometry engine`) of the fp32 file's
    weights; the fp32 file is the complete graph (contract 1)."""
    assert SHIPPED_INT8.is_file(), "run python3 -m training quantize"
    fp32, int8 = onnx.load(str(SHIPPED_FP32)), onnx.load(str(SHIPPED_INT8))
    onnx.checker.check_model(int8)
    assert [i.name for i in int8.graph.input] == export.NETWORK_INPUT_NAMES
    assert [o.name for o in int8.graph.output] == export.NETWORK_OUTPUT_NAMES
    m32, m8 = _meta(fp32), _meta(int8)
    assert m8["mocap.precision"] == "int8" and "int8" in m8["mocap.model_name"]
    assert m8["mocap.model_name"].startswith(m32["mocap.model_name"])
    assert m8["mocap.contract_version"] == "3" and m8["mocap.mirror_average"] == "1"
    own = ("mocap.precision", "mocap.model_name", "mocap.contract_version")
    geometry = set(m8) - set(m32)
    assert geometry == {"mocap.acceleration_scale", "mocap.anchor_joints", "mocap.masked_features",
                        "mocap.mirror_average", "mocap.mirror_sensors", "mocap.mirror_joints"}
    assert {k: v for k, v in m8.items() if k not in own and k not in geometry} == \
        {k: v for k, v in m32.items() if k not in own}
    lstm32, lstm8, mm8, pairs = _weight_pairs(fp32, int8)
    assert len(lstm32) == len(lstm8) == 2 and len(mm8) == 4
    assert not [n for n in int8.graph.node if n.op_type == "LSTM"]
    for original, q, scale, axis, what in pairs:
        _within_half_a_step(original, q, scale, axis)
    int8_values = sum(q.size for _, q, _, _, _ in pairs)
    assert int8_values > 0.99 * 2_405_525 - 10_000   # nearly every parameter is int8
    assert SHIPPED_INT8.stat().st_size < 0.3 * SHIPPED_FP32.stat().st_size


# ------------------------------------------------------------------------------ ONNX Runtime
@needs_ort
def test_int8_follows_fp32_on_onnx_runtime(tiny_fp32, tmp_path):
    out = tmp_path / "tiny_int8.onnx"
    info = qz.quantize_file(tiny_fp32, out, check=True)
    assert qz.check_failures(info["check"]) == [] and out.is_file()
    # a short random clip, whole and streamed, on the shipped pair (the tiny one is checked above)
    ori, acc = qz.fixture_inputs(seconds=1.5, seed=11)
    r = qz.check_against_fp32(SHIPPED_FP32, SHIPPED_INT8, ori, acc)
    for tag in ("whole", "stream"):
        assert 0 < r[tag]["joint_rotations"] <= qz.CHECK_TOLERANCE, r
        assert r[tag]["root_velocity"] <= 0.1 and r[tag]["foot_contact"] <= 0.1, r


@needs_ort
def test_a_wrong_int8_model_fails_the_check_and_is_not_installed(tmp_path, monkeypatch):
    out = tmp_path / "int8.onnx"
    out.write_bytes(b"previous")
    real = qz.quantize_model

    def gates_reordered(model, *args):   # W's gate blocks in PyTorch's order (i, f, g, o): a plausible slip
        m, s = real(model, *args)
        lstm_w = {n.input[1] for n in m.graph.node if n.op_type == "DynamicQuantizeLSTM"}
        for init in m.graph.initializer:
            if init.name in lstm_w:
                w = numpy_helper.to_array(init)
                i, o, f, c = np.split(w, 4, axis=2)
                init.CopyFrom(numpy_helper.from_array(np.concatenate([i, f, c, o], axis=2), init.name))
        return m, s

    monkeypatch.setattr(qz, "quantize_model", gates_reordered)
    with pytest.raises(qz.QuantizeCheckError, match="joint_rotations differ"):
        qz.quantize_file(SHIPPED_FP32, out, check=True)
    assert out.read_bytes() == b"previous" and sorted(p.name for p in tmp_path.iterdir()) == ["int8.onnx"]


@needs_ort
def test_a_contract_two_model_with_an_optional_chest_quantises_and_checks(tmp_path):
    """The check feeds the model's own sensors and, for a masked model, a mask that leaves its
    optional chest out: a seven-sensor contract-2 network quantises like the six-sensor one."""
    from training import sensors as se
    from training.model import ModelConfig
    config = ModelConfig(48, 48, 2, 48, sensors=se.DEFAULT_SENSORS + ("chest",), optional=("chest",),
                         masked=True)
    fp32 = tmp_path / "seven_fp32.onnx"
    net = MirrorEnsemble(export.untrained_model(seed=5, config=config)).eval()
    export.export_fp32(net, fp32, "seven-sensor test network")
    info = ort.model_info(fp32)
    assert info["contract_version"] in (2, "2") and info["imu_mask"]
    out = tmp_path / "seven_int8.onnx"
    result = qz.quantize_file(fp32, out, check=True)
    assert qz.check_failures(result["check"]) == [] and out.is_file()
    assert ort.model_info(out)["sensor_count"] in (7, "7")
