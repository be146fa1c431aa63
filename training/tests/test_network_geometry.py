"""Model contract 3: the learned network alone in the file, the geometry done by the engine
(Native~/src/pose/network_geometry.c). The same weights exported both ways must answer alike
through the real ONNX Runtime and the real engine (`mocapctl infer`), for every kind of network
the exporter writes."""
import numpy as np
import onnx
import pytest
import torch

from training import export, onnx_metadata, ort
from training.model import MirrorEnsemble, ModelConfig, NetworkOnly, PoseNet, feature_size
from training.quantize import quantize_model

SIX = ("pelvis", "left_wrist", "right_wrist", "left_shin", "right_shin", "head")
SEVEN = SIX + ("chest",)
SHUFFLED = ("head", "right_wrist", "chest", "pelvis", "left_shin", "left_wrist", "right_shin")


def _needs_onnx_runtime():
    if not ort.onnx_runtime_available():
        pytest.skip("ONNX Runtime not available (scripts/fetch_onnxruntime.sh)")


def _network(config: ModelConfig, mirror: bool, seed: int = 3):
    """A small network whose last layer is far from its near-zero initialisation, so that every
    residual, anchored bone and velocity the geometry handles is large."""
    torch.manual_seed(seed)
    net = PoseNet(config).eval()
    with torch.no_grad():
        net.head[-1].weight.normal_(0.0, 0.2)
        net.head[-1].bias.normal_(0.0, 0.5)
    return MirrorEnsemble(net).eval() if mirror else net


def _inputs(sensors, masked: bool, seed: int = 0):
    ori, acc = export.fixture_inputs(seconds=1.5, seed=seed, sensors=sensors)
    rng = np.random.default_rng(seed)
    # turn each character about the vertical by its own angle: the heading removal must hold
    for b in range(ori.shape[0]):
        a = rng.uniform(-np.pi, np.pi)
        ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]], np.float32)
        ori[b] = ry @ ori[b]
        acc[b] = acc[b] @ ry.T
    if not masked:
        return ori, acc, None
    mask = np.ones(ori.shape[:3], np.float32)
    t = ori.shape[1]
    k = sensors.index
    mask[1, :, k("chest")] = 0                            # the optional sensor never there
    mask[1, t // 3:(2 * t) // 3, k("left_wrist")] = 0     # a wrist missing for a while
    mask[0, t // 2:, k("right_shin")] = 0                 # a shin gone for good
    mask[0, t // 5:(2 * t) // 5, k("pelvis")] = 0         # even the pelvis
    return ori * mask[..., None, None], acc * mask[..., None], mask


CASES = {
    "six sensors, anchored, mirror-averaged (the shipped kind)":
        (ModelConfig(embed=32, hidden=24, head=32, anchored=True), True, SIX),
    "six sensors, plain network": (ModelConfig(embed=32, hidden=24, head=32), False, SIX),
    "seven sensors, chest optional, wrists on the forearm, mirror-averaged":
        (ModelConfig(embed=32, hidden=24, head=32, sensors=SEVEN, optional=("chest",), masked=True, anchored=True,
                     wrist_anchor="forearm"), True, SEVEN),
    "seven sensors, masked, anchored, plain": (ModelConfig(embed=32, hidden=24, head=32, sensors=SEVEN, optional=("chest",),
                                                           masked=True, anchored=True), False, SEVEN),
    "seven sensors, the pelvis fourth, masked, mirror-averaged":
        (ModelConfig(embed=32, hidden=24, head=32, sensors=SHUFFLED, optional=("chest",), masked=True,
                     anchored=True), True, SHUFFLED),
}


@pytest.mark.parametrize("case", list(CASES))
def test_the_engine_geometry_answers_what_the_whole_graph_does(case, tmp_path):
    _needs_onnx_runtime()
    config, mirror, sensors = CASES[case]
    net = _network(config, mirror)
    whole, alone = tmp_path / "whole.onnx", tmp_path / "alone.onnx"
    export.export_fp32(net, whole, "whole")
    export.export_network_fp32(net, alone, "alone")
    ori, acc, mask = _inputs(sensors, config.masked)
    ref = export.torch_outputs(net, ori, acc, mask)
    assert np.abs(ref["joint_rotations"] - np.eye(3)).max() > 0.5     # far from the rest pose
    for stream in (False, True):
        a = ort.run_onnx(whole, ori, acc, mask=mask, stream=stream)
        b = ort.run_onnx(alone, ori, acc, mask=mask, stream=stream)
        for key in export.OUTPUT_NAMES:
            assert a[key].shape == b[key].shape, key
            assert np.abs(a[key] - b[key]).max() < 2e-5, (key, stream)
            assert np.abs(b[key] - ref[key]).max() < 5e-5, (key, stream)


def test_a_network_only_file_describes_the_geometry_it_leaves_to_the_engine(tmp_path):
    config, mirror, sensors = CASES["seven sensors, chest optional, wrists on the forearm, mirror-averaged"]
    net = _network(config, mirror)
    path = tmp_path / "alone.onnx"
    export.export_network_fp32(net, path, "alone")
    model = onnx.load(str(path))
    meta = onnx_metadata.read(model)
    assert meta["mocap.contract_version"] == "3"
    assert meta["mocap.masked_features"] == "1" and meta["mocap.mirror_average"] == "1"
    # wrists on the forearm: the wrist sensors anchor joints 18/19 (the elbows' children's parents)
    assert meta["mocap.anchor_joints"] == "0,18,19,4,5,15,9"
    assert meta["mocap.mirror_sensors"] == "0,2,1,4,3,5,6"
    assert meta["mocap.state_size"] == str(2 * config_hidden(net))
    names = [i.name for i in model.graph.input]
    assert names == export.NETWORK_INPUT_NAMES
    dims = [d.dim_value or d.dim_param for d in model.graph.input[0].type.tensor_type.shape.dim]
    assert dims == ["R", "T", feature_size(len(sensors), masked=True)]
    # no geometry left in the graph: no normalisation, no gathers of joints, no sigmoid
    ops = {n.op_type for n in model.graph.node}
    assert sum(n.op_type == "MatMul" for n in model.graph.node) == 4      # the four weight matrices
    assert not ops & {"LpNormalization", "Gather", "Div", "Sqrt", "ReduceSum", "Sigmoid"}, ops


def config_hidden(net):
    return (net.net if isinstance(net, MirrorEnsemble) else net).config.hidden


def test_the_network_alone_reorders_the_head_into_joint_row_column(tmp_path):
    net = _network(ModelConfig(embed=32, hidden=24, head=32), False)
    alone = NetworkOnly(net).eval()
    x = torch.randn(2, 3, feature_size(6))
    h, c = net.zero_state(2)
    with torch.no_grad():
        ours, _, _ = alone(x, h, c)
        y, _ = net.lstm(net.embed(x), (h, c))
        theirs = net.head(y)
    # the network writes a joint's column 0 then column 1; the reordered head writes row by row
    j, r, col = 7, 2, 1
    assert torch.allclose(ours[..., j * 6 + r * 2 + col], theirs[..., j * 6 + col * 3 + r])
    assert torch.allclose(ours[..., 144:], theirs[..., 144:])


def test_an_int8_network_only_file_keeps_the_contract_and_its_geometry(tmp_path):
    _needs_onnx_runtime()
    config, mirror, sensors = CASES["six sensors, anchored, mirror-averaged (the shipped kind)"]
    net = _network(config, mirror)
    path = tmp_path / "alone.onnx"
    export.export_network_fp32(net, path, "alone")
    q, summary = quantize_model(onnx.load(str(path)))
    assert summary["lstms"] == 2 and summary["matmuls"] >= 3
    int8 = tmp_path / "alone_int8.onnx"
    onnx.save(q, str(int8))
    meta = onnx_metadata.read(onnx.load(str(int8)))
    assert meta["mocap.contract_version"] == "3" and meta["mocap.precision"] == "int8"
    ori, acc, _ = _inputs(sensors, False)
    a = ort.run_onnx(path, ori, acc, stream=True)
    b = ort.run_onnx(int8, ori, acc, stream=True)
    dev = np.abs(a["joint_rotations"] - b["joint_rotations"])
    assert 0 < dev.max() < 0.1                                 # quantised, and still the same pose


def test_stride_law_is_taken_over_or_refused(tmp_path):
    net = _network(ModelConfig(embed=32, hidden=24, head=32), False)
    src, dst = tmp_path / "src.onnx", tmp_path / "dst.onnx"
    export.export_fp32(net, src, "src")
    export.export_network_fp32(net, dst, "dst")
    with pytest.raises(export.UsageError, match="mocap.training_height"):
        export.copy_stride_law(src, dst)
    model = onnx.load(str(src))
    onnx_metadata.replace(model, onnx_metadata.read(model) | {"mocap.training_height": "1.7",
                                                              "mocap.stride_exponent": "0.5"})
    onnx.save(model, str(src))
    export.copy_stride_law(src, dst)
    meta = onnx_metadata.read(onnx.load(str(dst)))
    assert meta["mocap.training_height"] == "1.7" and meta["mocap.stride_exponent"] == "0.5"
    assert meta["mocap.contract_version"] == "3"


def test_the_cli_keeps_each_kind_of_file_where_it_belongs(tmp_path, capsys):
    """The shipped fp32/fp16 files are complete graphs and the shipped int8 file is the network
    alone: `export --geometry engine` without --out, and `quantize` of a complete graph onto the
    shipped int8 file, are refused before anything is written."""
    from training.__main__ import main
    from training import quantize as qz
    before = qz.DEFAULT_OUT.stat().st_mtime_ns
    assert main(["export", "--untrained", "--geometry", "engine"]) == 1
    assert "--geometry engine needs --out" in capsys.readouterr().err
    assert main(["quantize", "--model", str(qz.DEFAULT_MODEL), "--no-check"]) == 1
    err = capsys.readouterr().err
    assert "is a complete graph" in err and "--geometry engine" in err
    assert qz.DEFAULT_OUT.stat().st_mtime_ns == before
    # elsewhere, a complete graph quantises as before
    out = tmp_path / "int8.onnx"
    assert main(["quantize", "--model", str(qz.DEFAULT_MODEL), "--out", str(out), "--no-check"]) == 0
    assert onnx_metadata.read(onnx.load(str(out)))["mocap.contract_version"] == "1"
