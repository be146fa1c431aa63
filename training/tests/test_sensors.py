"""training/sensors.py: the engine's segment table as training reads it, and sensor lists other
than the default six through synthesis, the network and export."""
from pathlib import Path

import numpy as np
import pytest
import torch

from training import export, ort, procedural
from training import sensors as se
from training import skeleton as sk
from training import synthesis as sy
from training.errors import UsageError
from training.stride_scaling import MEASURED_KEYS
from training.model import MirrorEnsemble, ModelConfig, PoseNet, feature_size

SMALL = ModelConfig(32, 32, 1, 32)
WITH_CHEST = ("pelvis", "left_wrist", "right_wrist", "left_shin", "right_shin", "head", "chest")
ROW = 'MOCAP_SEGMENT_ROW({}, {}, "{}", {}, {})\n'


def _table(*rows) -> str:
    return "/* a comment, as the real table has */\n" + "".join(ROW.format(*r) for r in rows)


def test_parse_reads_rows_and_skips_comments():
    segs = se.parse_segments(_table(("PELVIS", 0, "pelvis", 0, 0), ("CHEST", 1, "chest", 9, -1))
                             + "// a line comment\n")
    assert [(s.enum, s.id, s.name, s.joint, s.default_node) for s in segs] == [
        ("PELVIS", 0, "pelvis", 0, 0), ("CHEST", 1, "chest", 9, -1)]


@pytest.mark.parametrize("rows, message", [
    ((("PELVIS", 1, "pelvis", 0, 0),), "id 1, expected 0"),
    ((("PELVIS", 0, "pelvis", 0, 0), ("HEAD", 2, "head", 15, 1)), "id 2, expected 1"),
    ((("PELVIS", 0, "Pelvis", 0, 0),), "lower-case ENUM"),
    ((("PELVIS", 0, "hips", 0, 0),), "lower-case ENUM 'pelvis'"),
    ((("PELVIS", 0, "pelvis", 24, 0),), "joint 24 is not a skeleton joint"),
    ((("PELVIS", 0, "pelvis", 0, 0), ("HEAD", 1, "head", 15, 0)), "default node 0 is already"),
    ((("PELVIS", 0, "pelvis", 0, -2),), "default node -2"),
])
def test_parse_refuses_a_bad_table_naming_the_row(rows, message):
    with pytest.raises(ValueError, match=message):
        se.parse_segments(_table(*rows), "t.def")


def test_parse_refuses_text_that_is_no_row_and_an_empty_table():
    with pytest.raises(ValueError, match="not a MOCAP_SEGMENT_ROW"):
        se.parse_segments(_table(("PELVIS", 0, "pelvis", 0, 0)) + "MOCAP_SEGMENT_ROW(HEAD, 1, head, 15, 1)\n")
    with pytest.raises(ValueError, match="no MOCAP_SEGMENT_ROW rows"):
        se.parse_segments("/* nothing */\n")
    with pytest.raises(ValueError, match="cannot be read"):
        se.load_segments(Path("/nonexistent/segments.def"))


def test_the_table_has_a_mirror_partner_and_a_sensor_placement_for_every_segment():
    for s in se.SEGMENTS:
        other = se.segment(se.mirror_segment(s.name))
        assert other.joint == sk.MIRROR_JOINTS[s.joint], s.name
    # every segment can be synthesised: a new table row needs its placement in synthesis.py
    off = sy.sensor_offsets(sk.DEFAULT_OFFSETS, se.SEGMENT_NAMES)
    assert off.shape == (len(se.SEGMENTS), 3)
    assert (np.linalg.norm(off, axis=-1) < 0.35).all()   # on the body, near its joint
    assert se.DEFAULT_SENSORS == tuple(s.name for s in se.SEGMENTS if s.default_node >= 0)


def test_sensor_list_refuses_unknown_repeated_and_too_many_segments():
    assert se.sensor_list("pelvis, chest") == ("pelvis", "chest")
    with pytest.raises(ValueError, match="unknown segment 'tail'"):
        se.sensor_list(["pelvis", "tail"])
    with pytest.raises(ValueError, match="head listed more than once"):
        se.sensor_list(["head", "pelvis", "head"])
    with pytest.raises(ValueError, match="1 to 16 segments, got 0"):
        se.sensor_list([])
    with pytest.raises(ValueError, match="1 to 16 segments, got 17"):
        se.sensor_list(["pelvis"] * 17)
    with pytest.raises(ValueError, match="chest has no mirror image|left_wrist has no mirror image"):
        se.mirror_indices(["pelvis", "left_wrist"])
    assert se.mirror_indices(WITH_CHEST) == [0, 2, 1, 4, 3, 5, 6]


def test_synthesis_of_a_chest_sensor_reports_the_spine3_bone_and_keeps_the_six_unchanged():
    m = procedural.make_motion("mixed", 2.0, seed=4)
    six = sy.synthesize(m)
    seven = sy.synthesize(m, sensors=WITH_CHEST)
    assert seven.imu_orientation.shape == (m.num_frames, 7, 3, 3) and seven.sensors == WITH_CHEST
    np.testing.assert_array_equal(seven.imu_orientation[:, :6], six.imu_orientation)
    np.testing.assert_array_equal(seven.imu_acceleration[:, :6], six.imu_acceleration)
    g, p = sk.forward_kinematics(m.local_rot.astype(np.float64), m.root_pos, m.offsets)
    np.testing.assert_allclose(seven.imu_orientation[:, 6], g[:, 9], atol=1e-5)
    # the chest sensor sits in front of the spine3 joint, and its acceleration is its own
    forward = np.einsum("tab,b->ta", g[:, 9], [0.0, 0.0, 1.0])
    ahead = np.einsum("ta,ta->t", seven.sensor_position[:, 6] - p[:, 9], forward)
    assert (ahead > 0.05).all()
    assert np.abs(seven.imu_acceleration[:, 6] - seven.imu_acceleration[:, 0]).max() > 0.1
    # any order: the sensors come out in the order asked for
    rev = sy.synthesize(m, sensors=WITH_CHEST[::-1])
    np.testing.assert_array_equal(rev.imu_orientation, seven.imu_orientation[:, ::-1])


def test_a_network_on_seven_sensors_with_the_pelvis_anywhere():
    torch.manual_seed(0)
    moved = ("chest", "left_wrist", "right_wrist", "pelvis", "left_shin", "right_shin", "head")
    net = PoseNet(ModelConfig(32, 32, 1, 32, sensors=moved)).eval()
    assert net.embed[0].in_features == feature_size(7) == 24 * 7 - 12
    with torch.no_grad():
        net.head[-1].weight.normal_(0, 0.3)
    m = procedural.make_motion("walk", 1.0, seed=2)
    s = sy.synthesize(m, sensors=moved)
    o, a = torch.from_numpy(s.imu_orientation[None]), torch.from_numpy(s.imu_acceleration[None])
    with torch.no_grad():
        rot, vel, contact, _ = net(o, a)
        yaw = torch.from_numpy(sk.rot_axis("y", 0.7).astype(np.float32))
        turned = net(yaw @ o, (yaw @ a.unsqueeze(-1)).squeeze(-1))[0]
    assert rot.shape == (1, m.num_frames, 24, 3, 3)
    # the heading comes from the pelvis sensor wherever it is in the list
    assert torch.allclose(turned[:, :, 0], yaw @ rot[:, :, 0], atol=1e-4)
    assert torch.allclose(turned[:, :, 1:], rot[:, :, 1:], atol=1e-4)
    # anchoring follows the list: chest on spine3, pelvis excluded
    net.enable_anchoring()
    assert net.anchor_joints == [9, 20, 21, 0, 4, 5, 15]
    with torch.no_grad():
        g, _ = sk.forward_kinematics(net(o, a)[0][0].double().numpy(), np.zeros((m.num_frames, 3)))
    err = np.degrees(sk.angle_between_rots(g[:, 9], s.imu_orientation[:, 0].astype(np.float64)))
    assert err.max() < 1e-3
    with pytest.raises(ValueError, match="needs a pelvis sensor"):
        PoseNet(ModelConfig(32, 32, 1, 32, sensors=("head", "chest")))
    with pytest.raises(ValueError, match="unknown segment 'tail'"):
        ModelConfig.from_dict({**SMALL.to_dict(), "sensors": ["pelvis", "tail"]})


def test_mirror_ensemble_of_a_chest_network_is_mirror_equivariant():
    torch.manual_seed(1)
    net = PoseNet(ModelConfig(32, 32, 1, 32, sensors=WITH_CHEST)).eval()
    with torch.no_grad():
        net.head[-1].weight.normal_(0, 0.3)
    ens = MirrorEnsemble(net).eval()
    s = sy.synthesize(procedural.make_motion("mixed", 0.5, seed=3), sensors=WITH_CHEST)
    o, a = torch.from_numpy(s.imu_orientation[None]), torch.from_numpy(s.imu_acceleration[None])
    m = torch.diag(torch.tensor([-1.0, 1.0, 1.0]))
    mirror = se.mirror_indices(WITH_CHEST)
    with torch.no_grad():
        r = ens(o, a)[0]
        rm = ens(m @ o[:, :, mirror] @ m, a[:, :, mirror] @ m)[0]
    assert torch.allclose(m @ rm[:, :, sk.MIRROR_JOINTS] @ m, r, atol=1e-5)


def test_a_checkpoint_config_without_sensors_is_the_default_six():
    legacy = {k: v for k, v in SMALL.to_dict().items() if k != "sensors"}
    assert ModelConfig.from_dict(legacy).sensors == se.DEFAULT_SENSORS
    assert ModelConfig.from_dict({**legacy, "sensors": list(WITH_CHEST)}).sensors == WITH_CHEST


def test_export_refuses_a_sensor_list_other_than_contract_one_and_writes_nothing(tmp_path):
    torch.manual_seed(0)
    net = PoseNet(ModelConfig(32, 32, 1, 32, sensors=WITH_CHEST)).eval()
    with pytest.raises(UsageError, match="reads the sensors .*chest.*contract 1.*nothing written"):
        export.export(net, tmp_path, check=False)
    assert list(tmp_path.iterdir()) == []


def test_the_shipped_models_metadata_is_what_export_writes_for_the_default_six():
    """Reading the sensor list from the table must not change a byte of contract 1's metadata:
    the shipped checkpoint, exported as `training export` does, gives the shipped files' own."""
    import onnx
    root = Path(__file__).resolve().parents[2]
    net, ck = export.load_checkpoint(root / "training" / "checkpoints" / "mocap_pose.pt")
    name = (f"mocap-pose lstm{net.state_layers}x{net.state_size} mirror-averaged"
            + export.checkpoint_label(ck))
    ens = MirrorEnsemble(net).eval()
    models = root / "Packages" / "com.mocap.imu" / "Runtime" / "Models"
    for file, precision in ((export.FP32_NAME, "fp32"), (export.FP16_NAME, "fp16")):
        shipped = onnx.load(str(models / file), load_external_data=False)
        want = [(p.key, p.value) for p in shipped.metadata_props if p.key not in MEASURED_KEYS]
        assert list(export.contract_metadata(ens, precision, name).items()) == want, file
    meta = dict(want)
    assert meta["mocap.contract_version"] == "1"
    assert meta["mocap.sensor_order"] == "pelvis,left_wrist,right_wrist,left_shin,right_shin,head"


def test_the_contract_pages_segment_table_is_the_engines():
    """docs/model-contract.md lists the segment table for model authors: it must say what
    segments.def says (name, joint, default index), row for row."""
    import re
    page = (Path(__file__).resolve().parents[2] / "docs" / "model-contract.md").read_text()
    section = page.split("## Segments", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| (\w+) \| (\d+) \w+[^|]*\| (yes \(index \d+\)|yes \(\d+\)|no) \|$", section, re.M)
    listed = [(name, int(joint), -1 if flag == "no" else int(re.search(r"\d+", flag).group()))
              for name, joint, flag in rows]
    default_index = {n: i for i, n in enumerate(se.DEFAULT_SENSORS)}
    assert listed == [(s.name, s.joint, default_index.get(s.name, -1)) for s in se.SEGMENTS]


def test_node_ids_keep_default_nodes_and_give_others_the_lowest_free_ones():
    assert se.node_ids() == [0, 1, 2, 3, 4, 5]
    assert se.node_ids(WITH_CHEST) == [0, 1, 2, 3, 4, 5, 6]
    assert se.node_ids(("chest", "head", "pelvis")) == [1, 5, 0]


def test_evaluation_refuses_to_feed_a_model_other_sensors_than_it_reads():
    from training import evaluate as ev
    m = procedural.make_motion("walk", 0.5, seed=1)
    chest_clip = ev.synthesize_clip(m, np.random.default_rng(0), sensors=WITH_CHEST)
    assert chest_clip.sensors == WITH_CHEST and chest_clip.imu_orientation.shape[1] == 7
    six = PoseNet(SMALL).eval()
    with pytest.raises(UsageError, match="PyTorch network reads the sensors pelvis,.*,head; clip"):
        ev.predict_torch(six, [chest_clip])
    if ort.onnx_runtime_available():   # the ONNX model's sensor list comes from mocapctl model-info
        with pytest.raises(UsageError, match="mocap_pose_int8.onnx .model contract 3. reads the sensors .*; "
                                             "clip .* has .*chest"):
            ev.predict_onnx(ev.MODELS_DIR / "mocap_pose_int8.onnx", [chest_clip])
    # the baseline follows the clip's own list: the chest sensor lands on spine3
    pred = ev.predict_baseline(chest_clip)
    pelvis = chest_clip.imu_orientation[:, 0].astype(np.float64)
    np.testing.assert_allclose(pred.local_rot[:, 9], np.swapaxes(pelvis, -1, -2) @ chest_clip.imu_orientation[:, 6],
                               atol=1e-6)
