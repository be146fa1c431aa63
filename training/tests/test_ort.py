"""training/ort.py against the real ONNX Runtime (through mocapctl infer), on the fixture models of
Native~/tests/make_onnx_fixtures.py."""
import importlib.util

import numpy as np
import pytest

from training import ort

FIXTURES_PY = ort.NATIVE / "tests" / "make_onnx_fixtures.py"

needs_ort = pytest.mark.skipif(not ort.onnx_runtime_available(),
                               reason="ONNX Runtime not fetched (scripts/fetch_onnxruntime.sh)")


@pytest.fixture(scope="module")
def fixtures(tmp_path_factory):
    spec = importlib.util.spec_from_file_location("make_onnx_fixtures", FIXTURES_PY)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.write_all(str(tmp_path_factory.mktemp("onnx")))


def test_bundle_round_trip(tmp_path):
    a = np.arange(24, dtype=np.float32).reshape(2, 3, 4)
    b = np.array([1.5], dtype=np.float32)
    ort.write_bundle(tmp_path / "x.tensors", {"a": a, "b": b})
    back = ort.read_bundle(tmp_path / "x.tensors")
    assert list(back) == ["a", "b"]
    np.testing.assert_array_equal(back["a"], a)
    np.testing.assert_array_equal(back["b"], b)
    with pytest.raises(ort.OnnxRuntimeError):
        (tmp_path / "bad").write_bytes(b"nope" * 8)
        ort.read_bundle(tmp_path / "bad")


@needs_ort
def test_run_onnx_matches_closed_form_and_streams(fixtures):
    rng = np.random.default_rng(0)
    B, T = 3, 9
    ori = rng.normal(size=(B, T, 6, 3, 3)).astype(np.float32)
    acc = rng.normal(size=(B, T, 6, 3)).astype(np.float32)
    whole = ort.run_onnx(fixtures["valid"], ori, acc)
    cum = np.cumsum(acc.sum(axis=(2, 3)), axis=1)
    np.testing.assert_allclose(whole["root_velocity"], np.repeat(cum[..., None], 3, -1), atol=1e-4)
    np.testing.assert_array_equal(whole["joint_rotations"][:, :, 7], ori[:, :, 1])
    assert whole["state_out_h"].shape == (2, B, 4)
    stream = ort.run_onnx(fixtures["valid"], ori, acc, stream=True, threads=1, timing=True)
    np.testing.assert_allclose(stream["root_velocity"], whole["root_velocity"], atol=1e-4)
    assert stream["timing"]["calls"] == T and stream["timing"]["p50_us"] > 0
    # Continuing from a previous state equals one longer run.
    first = ort.run_onnx(fixtures["valid"], ori[:, :4], acc[:, :4])
    rest = ort.run_onnx(fixtures["valid"], ori[:, 4:], acc[:, 4:], state=first)
    np.testing.assert_allclose(rest["root_velocity"], whole["root_velocity"][:, 4:], atol=1e-4)


@needs_ort
def test_contract_violation_is_reported(fixtures):
    ori = np.zeros((1, 2, 6, 3, 3), np.float32)
    acc = np.zeros((1, 2, 6, 3), np.float32)
    with pytest.raises(ort.OnnxRuntimeError, match="mocap.contract_version is '9'"):
        ort.run_onnx(fixtures["wrong_version"], ori, acc)
    with pytest.raises(ort.OnnxRuntimeError, match="not a model ONNX Runtime can load"):
        ort.run_onnx(fixtures["not_onnx"], ori, acc)
    with pytest.raises(ValueError):
        ort.run_onnx(fixtures["valid"], ori[:, :, :5], acc)


@needs_ort
def test_model_info(fixtures):
    info = ort.model_info(fixtures["valid"])
    assert info["joint_names"][20] == "left_wrist"
    assert info["joint_parents"][20] == 18
    assert info["state_layers"] == 2 and info["state_size"] == 4
    assert info["rest_offsets"].shape == (24, 3)
    assert info["frame_rate"] == 60.0


def test_contract_two_fixtures_differ_from_v2_chest_in_their_one_defect(fixtures):
    """The engine's refusal tests rely on each v2 fixture breaking exactly one rule; every file is
    valid ONNX (the defects are the contract's), and a contract-1 model names no mask."""
    import onnx

    def facts(name):
        m = onnx.load(fixtures[name])
        onnx.checker.check_model(m)
        meta = {p.key: p.value for p in m.metadata_props}
        inputs = {i.name: [d.dim_param or d.dim_value for d in i.type.tensor_type.shape.dim]
                  for i in m.graph.input}
        return meta, inputs

    meta, inputs = facts("v2_chest")
    assert meta["mocap.contract_version"] == "2"
    assert meta["mocap.sensor_order"] == "pelvis,left_wrist,right_wrist,left_shin,right_shin,head,chest"
    assert meta["mocap.sensor_required"] == "1,1,1,1,1,1,0"
    assert inputs == {"imu_orientation": ["B", "T", 7, 3, 3], "imu_acceleration": ["B", "T", 7, 3],
                      "imu_mask": ["B", "T", 7], "state_in_h": [2, "B", 4], "state_in_c": [2, "B", 4]}
    changed = {
        "v2_unknown_segment": ({"mocap.sensor_order": meta["mocap.sensor_order"].replace("chest", "tail")}, {}),
        "v2_duplicate_segment": ({"mocap.sensor_order": meta["mocap.sensor_order"].replace("chest", "head")}, {}),
        "v2_required_length": ({"mocap.sensor_required": "1,1,1,1,1,1"}, {}),
        "v2_missing_mask": ({}, {"imu_mask": None}),
        "v2_wrong_sensor_dim": ({}, {"imu_orientation": ["B", "T", 6, 3, 3]}),
    }
    for name, (meta_change, input_change) in changed.items():
        want_meta = {**meta, **meta_change}
        want_inputs = {k: v for k, v in {**inputs, **input_change}.items() if v is not None}
        assert facts(name) == (want_meta, want_inputs), name
    v1_meta, v1_inputs = facts("valid")
    assert facts("v1_with_mask") == (v1_meta, {**v1_inputs, "imu_mask": ["B", "T", 6]})
    assert "mocap.sensor_required" not in v1_meta and v1_meta["mocap.contract_version"] == "1"
    assert facts("wrong_version")[0]["mocap.contract_version"] == "9"
