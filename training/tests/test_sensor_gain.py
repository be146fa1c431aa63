"""training/sensor_gain.py: known bones replace exactly what they name, and the command's report
on procedural clips with a tiny real model."""
import numpy as np
import pytest
import torch

from training import evaluate as ev
from training import procedural
from training import sensor_gain as sg
from training import skeleton as sk
from training.model import ModelConfig, PoseNet
from training.synthesis import with_orientation_errors


def _poses_wrong_at(bones):
    """A true pose and a prediction whose global orientations equal the truth's except at bones."""
    truth = procedural.make_motion("mixed", 2.0, seed=5).local_rot.astype(np.float64)
    g = sg.global_rotations(truth)
    rng = np.random.default_rng(2)
    for j in bones:
        g[:, j] = g[:, j] @ sk.rot_axis("xyz"[j % 3], rng.uniform(0.3, 0.6))
    return sk.global_to_local(g), truth


def test_known_bones_take_the_truth_and_leave_the_other_bones_as_predicted():
    pred, truth = _poses_wrong_at(range(24))
    g_pred, g_true = sg.global_rotations(pred), sg.global_rotations(truth)
    arms = sg.joint_indices(sg.CANDIDATES["both upper arms (8 sensors)"].bones)
    assert arms == [16, 17]
    g = sg.global_rotations(sg.with_known_bones(pred, truth, arms))
    # (the procedural rotations are float32: orthonormal to ~1e-7)
    np.testing.assert_allclose(g[:, arms], g_true[:, arms], atol=1e-5)
    rest = [j for j in range(24) if j not in arms]
    np.testing.assert_allclose(g[:, rest], g_pred[:, rest], atol=1e-5)
    # no bone known: the prediction; every bone known: the truth
    np.testing.assert_allclose(sg.with_known_bones(pred, truth, []), pred, atol=1e-5)
    np.testing.assert_allclose(sg.with_known_bones(pred, truth, range(24)), truth, atol=1e-5)


def test_a_known_upper_arm_removes_the_error_that_bone_makes():
    pred, truth = _poses_wrong_at([16, 17])
    offsets = sk.DEFAULT_OFFSETS
    _, before = sg.pose_errors(pred, truth, offsets)
    _, left = sg.pose_errors(sg.with_known_bones(pred, truth, [16]), truth, offsets)
    _, both = sg.pose_errors(sg.with_known_bones(pred, truth, [16, 17]), truth, offsets)
    assert before.min() > 1.0                           # cm, mean over 24 joints
    np.testing.assert_allclose(left, before / 2, rtol=0.35)   # one arm of two put right
    assert both.max() < 1e-3
    # the left elbow, wrist and hand are put right; nothing else moves
    _, p_pred = ev.root_aligned_positions(pred, offsets)
    _, p_known = ev.root_aligned_positions(sg.with_known_bones(pred, truth, [16]), offsets)
    moved = np.flatnonzero(np.abs(p_known - p_pred).max(axis=(0, 2)) > 1e-4)   # m
    assert list(moved) == [18, 20, 22]


def test_a_spread_spine_shares_the_bend_to_a_known_chest_evenly():
    pred, truth = _poses_wrong_at([3, 6, 9])
    local = sg.with_known_bones(pred, truth, [9], spread_spine=True)
    g, g_true, g_pred = sg.global_rotations(local), sg.global_rotations(truth), sg.global_rotations(pred)
    np.testing.assert_allclose(g[:, 9], g_true[:, 9], atol=1e-5)     # the chest as sensed
    np.testing.assert_allclose(g[:, 0], g_pred[:, 0], atol=1e-5)     # the pelvis as predicted
    # the three spine joints turn by the same local rotation, which makes up the pelvis-chest turn
    np.testing.assert_allclose(local[:, 3], local[:, 6], atol=1e-6)
    np.testing.assert_allclose(local[:, 6], local[:, 9], atol=1e-6)
    np.testing.assert_allclose(g[:, 0] @ local[:, 3] @ local[:, 3] @ local[:, 3], g_true[:, 9], atol=1e-5)
    # the neck, head and arms keep their predicted global orientation
    np.testing.assert_allclose(g[:, 12:], g_pred[:, 12:], atol=1e-5)
    # without spreading, spine1 and spine2 stay as predicted
    kept = sg.global_rotations(sg.with_known_bones(pred, truth, [9]))
    np.testing.assert_allclose(kept[:, [3, 6]], g_pred[:, [3, 6]], atol=1e-5)


def test_sensed_bones_carry_the_sensor_errors_and_exact_ones_none():
    pred, truth = _poses_wrong_at([16, 17])
    T = len(truth)
    clip = ev.Clip("c", 60.0, np.asarray(sk.DEFAULT_OFFSETS, np.float64), np.zeros((T, 6, 3, 3)),
                   np.zeros((T, 6, 3)), truth, np.zeros((T, 3)), subject=7)
    p = ev.Prediction(pred, np.zeros((T, 3)))
    arms = {"both": sg.Candidate(("left_shoulder", "right_shoulder"))}
    exact = sg.measure([clip], [p], arms, ev.eval_augmentation("none"))
    assert exact["model"]["pos"] > 1.0 and exact["both"]["pos"] < 1e-3
    assert exact["both"]["pos_sensed"] == pytest.approx(exact["both"]["pos"], abs=1e-6)
    assert exact["model"]["subjects"] == {7: pytest.approx(exact["model"]["pos"])}
    noisy = sg.measure([clip], [p], arms, ev.eval_augmentation("realistic"), np.random.default_rng(3))
    # a few degrees on two upper arms: some error comes back, far less than the model's
    assert 0.05 < noisy["both"]["pos_sensed"] < 0.5 * noisy["model"]["pos"]
    g = sg.global_rotations(truth)[:, [16, 17]]
    sensed, _ = with_orientation_errors(g, np.random.default_rng(4), ev.eval_augmentation("realistic"))
    angle = ev.rotation_angle_deg(sensed, g)
    assert 0.3 < angle.mean() < 12.0


def test_the_command_reports_every_candidate_per_subject(tmp_path, fixture_dir, capsys):
    torch.manual_seed(0)
    cfg = ModelConfig(embed=16, hidden=8, layers=1, head=16)
    ckpt = tmp_path / "tiny.pt"
    torch.save({"model": PoseNet(cfg).eval().state_dict(), "config": cfg.to_dict()}, ckpt)
    d, _ = fixture_dir
    out = tmp_path / "gain"
    assert sg.main(["--bvh", str(d), "--checkpoint", str(ckpt), "--out", str(out), "--max-clips", "3",
                    "--max-seconds", "2", "--no-cache"]) == 0
    text = (out / "sensor_gain.md").read_text()
    overall = text.split("## Position error by subject")[0]
    rows = {line.split("|")[1].strip(): line.split("|") for line in overall.splitlines()
            if line.startswith("| ") and not line.startswith("| sensor added")}
    model_pos = float(rows["none (the model as it is)"][4])
    for label in sg.CANDIDATES:
        assert label in rows, label
        pos, gain, sensed = float(rows[label][4]), float(rows[label][5]), float(rows[label][7])
        assert gain == pytest.approx(model_pos - pos, abs=0.011) and sensed > 0
    # an untrained network is wrong everywhere: two known bones beat one
    assert float(rows["both upper arms (8 sensors)"][4]) < float(rows["left upper arm"][4])
    assert "## Position error by subject (cm)" in text
    assert (out / "sensor_gain.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "wrote" in capsys.readouterr().out


def test_a_missing_or_wrong_checkpoint_is_one_line_naming_it(tmp_path, fixture_dir, capsys):
    from training.__main__ import main
    d, _ = fixture_dir
    (tmp_path / "notes.txt").write_text("not a checkpoint\n")
    for ckpt, says in ((tmp_path / "missing.pt", "no such file"), (tmp_path / "notes.txt", "is not a PyTorch checkpoint")):
        capsys.readouterr()
        assert main(["sensor-gain", "--bvh", str(d), "--checkpoint", str(ckpt), "--no-cache",
                     "--out", str(tmp_path / "out")]) == 1
        err = capsys.readouterr().err.strip()
        last = err.splitlines()[-1]
        assert last.startswith("training sensor-gain: ") and str(ckpt) in last and says in last, err
        assert "Traceback" not in err
    assert not (tmp_path / "out").exists()
