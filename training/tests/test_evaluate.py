"""training/evaluate.py: metrics on known cases, the baseline, and the whole run on procedural
fixtures with a tiny PyTorch model and its ONNX export on the real ONNX Runtime."""
import importlib.util
from dataclasses import replace

import numpy as np
import pytest
import torch

from training import evaluate as ev
from training import ort, procedural
from training import sensors as se
from training import skeleton as sk
from training.model import ExportWrapper, MirrorEnsemble, ModelConfig, PoseNet


def test_rotation_angle():
    a = sk.rot_axis("y", np.radians(30.0))
    b = sk.rot_axis("x", np.radians(-50.0))
    assert ev.rotation_angle_deg(np.eye(3), a) == pytest.approx(30.0, abs=1e-6)
    assert ev.rotation_angle_deg(b, b @ a) == pytest.approx(30.0, abs=1e-6)


def test_drift_and_jitter_on_known_signals():
    fps = 60.0
    t = np.arange(0, 12, 1 / fps)
    root = np.stack([1.0 * t, 0 * t, 0 * t], -1)          # 1 m/s along x
    vel = np.tile([1.0, 0, 0], (len(t), 1))
    assert np.allclose(ev.drift_errors(vel, root, fps, 5.0), 0.0, atol=1e-9)
    still = ev.drift_errors(np.zeros_like(vel), root, fps, 5.0)
    assert len(still) == 7 and np.allclose(still, 5.0)
    assert len(ev.drift_errors(vel, root[:100], fps, 2.0)) == 0   # clip shorter than the window
    cubic = np.zeros((len(t), 2, 3))
    cubic[:, :, 1] = (t ** 3)[:, None]                  # third derivative 6 m/s^3
    assert ev.jitter(cubic, fps) == pytest.approx(6.0, rel=1e-6)


def test_travel_ratio_reads_speed_and_counts_only_moving_windows():
    fps = 60.0
    t = np.arange(0, 30, 1 / fps)
    walk = np.stack([1.2 * t, 0.05 * np.sin(t), 0 * t], -1)     # 1.2 m/s along x, bobbing
    vel = np.gradient(walk, 1 / fps, axis=0)
    assert np.allclose(ev.travel_ratios(vel, walk, fps), 1.0, atol=0.01)
    slow = ev.travel_ratios(vel * [0.9, 1.0, 1.0], walk, fps)
    assert len(slow) == 20 and np.allclose(slow, 0.9, atol=0.01)
    # a heading error keeps the distance: the ratio is the speed's, not the direction's
    turned = vel @ sk.rot_axis("y", np.radians(40.0)).T
    assert np.allclose(ev.travel_ratios(turned, walk, fps), 1.0, atol=0.01)
    standing = np.zeros_like(walk)
    assert len(ev.travel_ratios(vel, standing, fps)) == 0     # never moved 0.5 m: no window


def test_elbow_angles_are_the_elbows_own_rotation():
    local = np.broadcast_to(np.eye(3), (5, 24, 3, 3)).copy()
    local[:, sk.JOINT_NAMES.index("left_elbow")] = sk.rot_axis("y", np.radians(70.0))
    local[:, sk.JOINT_NAMES.index("right_elbow")] = sk.rot_axis("x", np.radians(-15.0))
    local[:, sk.JOINT_NAMES.index("left_wrist")] = sk.rot_axis("z", np.radians(90.0))   # not an elbow
    a = ev.elbow_angles(local).reshape(5, 2)
    assert np.allclose(a[:, 0], 70.0, atol=1e-4) and np.allclose(a[:, 1], 15.0, atol=1e-4)


def test_baseline_puts_sensor_orientations_on_their_bones():
    m = procedural.make_motion("mixed", 2.0, seed=3)
    rng = np.random.default_rng(0)
    clip = ev.synthesize_clip(m, rng)
    pred = ev.predict_baseline(clip)
    g, _ = sk.forward_kinematics(pred.local_rot, np.zeros((len(pred.local_rot), 3)), clip.offsets)
    np.testing.assert_allclose(g[:, se.sensor_joints()], clip.imu_orientation, atol=1e-5)
    rest = [j for j in range(24) if j not in se.sensor_joints()]
    np.testing.assert_allclose(pred.local_rot[:, rest], np.broadcast_to(np.eye(3), (len(g), len(rest), 3, 3)))
    assert not pred.root_velocity.any()
    # Noise is realistic, not absent: the pelvis orientation differs from the truth by a little.
    err = ev.rotation_angle_deg(clip.imu_orientation[:, 0], clip.local_rot[:, 0])
    assert 0.05 < err.mean() < 8.0


def _baseline_reports(tmp_path, fixture_dir, option, values) -> dict:
    """evaluate's report on two fixture clips (baseline only) for each value of one option."""
    d, _ = fixture_dir
    reports = {}
    for value in values:
        out = tmp_path / value
        assert ev.main(["--bvh", str(d), "--no-torch", "--models", "--out", str(out), "--max-clips", "2",
                        "--no-latency", "--no-cache", option, value]) == 0
        reports[value] = (out / "evaluation.md").read_text()
    return reports


def test_noise_none_gives_perfect_sensors_and_says_so(tmp_path, fixture_dir):
    m = procedural.make_motion("mixed", 2.0, seed=3)
    clip = ev.synthesize_clip(m, np.random.default_rng(0), noise="none")
    g, _ = sk.forward_kinematics(clip.local_rot, np.zeros((len(clip.local_rot), 3)), clip.offsets)
    # every sensor reports its bone exactly, so the baseline's own bones carry no error at all
    np.testing.assert_allclose(clip.imu_orientation, g[:, se.sensor_joints()], atol=1e-5)
    pred = ev.predict_baseline(clip)
    assert ev.rotation_angle_deg(pred.local_rot[:, 0], clip.local_rot[:, 0]).max() < 0.05
    with pytest.raises(ValueError, match="noise 'loud'"):
        ev.eval_augmentation("loud")
    reports = _baseline_reports(tmp_path, fixture_dir, "--noise", ("none", "realistic"))
    assert "from perfect sensors" in reports["none"] and "perfect sensors, not whether" in reports["none"]
    assert "with realistic sensor noise" in reports["realistic"] and "perfect" not in reports["realistic"]
    pelvis = {k: next(line for line in t.splitlines() if line.startswith("| 0 pelvis |"))
              for k, t in reports.items()}
    assert float(pelvis["none"].split("|")[2]) < 0.05      # baseline pelvis: exact (float32 arccos)
    assert float(pelvis["realistic"].split("|")[2]) > 0.05


def _export(net, path, L, H):
    """Tiny contract export for the test (metadata from the engine's fixture generator)."""
    spec = importlib.util.spec_from_file_location("fx", ort.NATIVE / "tests" / "make_onnx_fixtures.py")
    fx = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fx)
    import onnx
    w = ExportWrapper(net).eval()
    args = (torch.zeros(1, 2, 6, 3, 3), torch.zeros(1, 2, 6, 3), torch.zeros(L, 1, H), torch.zeros(L, 1, H))
    names_in = ["imu_orientation", "imu_acceleration", "state_in_h", "state_in_c"]
    names_out = ["joint_rotations", "root_velocity", "foot_contact", "state_out_h", "state_out_c"]
    dyn = {"imu_orientation": {0: "B", 1: "T"}, "imu_acceleration": {0: "B", 1: "T"},
           "state_in_h": {1: "B"}, "state_in_c": {1: "B"}, "joint_rotations": {0: "B", 1: "T"},
           "root_velocity": {0: "B", 1: "T"}, "foot_contact": {0: "B", 1: "T"},
           "state_out_h": {1: "B"}, "state_out_c": {1: "B"}}
    torch.onnx.export(w, args, str(path), input_names=names_in, output_names=names_out,
                      dynamic_axes=dyn, opset_version=14)
    model = onnx.load(str(path))
    md = fx.metadata(state_layers=str(L), state_size=str(H), model_name="tiny-test")
    onnx.helper.set_model_props(model, md)
    onnx.save(model, str(path))


def test_evaluate_end_to_end(tmp_path):
    torch.manual_seed(0)
    cfg = ModelConfig(embed=16, hidden=8, layers=1, head=16)
    net = PoseNet(cfg).eval()
    ckpt = tmp_path / "tiny.pt"
    torch.save({"model": net.state_dict(), "config": cfg.to_dict()}, ckpt)
    motions = [procedural.make_motion(k, 6.0, seed=i) for i, k in enumerate(["walk", "turn"])]
    models = []
    if ort.onnx_runtime_available():
        # as shipped: the mirror-averaged pair, which evaluate's PyTorch row also runs
        _export(MirrorEnsemble(net), tmp_path / "tiny_fp32.onnx", cfg.layers, 2 * cfg.hidden)
        models.append(tmp_path / "tiny_fp32.onnx")
    out = tmp_path / "results"
    r = ev.evaluate(motions, models, ckpt, out, seed=1, latency_frames=120, source="procedural")
    res = r["results"]
    assert set(res) >= {"PyTorch fp32", "baseline"}
    for s in res.values():
        assert 0 <= s["angle_all"] < 180 and s["pos"] >= 0 and s["drift_2s"] >= 0
        assert np.isfinite(s["jitter"])
        # per-joint position errors: the roots are aligned, and their mean is the headline figure
        assert s["per_joint_pos"].shape == (24,) and s["per_joint_pos"][0] == pytest.approx(0.0, abs=1e-6)
        assert float(np.mean(s["per_joint_pos"])) == pytest.approx(s["pos"], rel=1e-9)
    # The baseline has zero velocity: its drift is the true displacement (walk: > 1 m in 2 s).
    assert res["baseline"]["drift_2s"] > 1.0
    if models:
        # ONNX Runtime reproduces PyTorch on the same inputs.
        assert res["ONNX fp32"]["angle_all"] == pytest.approx(res["PyTorch fp32"]["angle_all"], abs=0.05)
        assert res["ONNX fp32"]["pos"] == pytest.approx(res["PyTorch fp32"]["pos"], abs=0.05)
        assert r["latency"]["calls"] == 120 and r["latency"]["p50_us"] > 0
    text = (out / "evaluation.md").read_text()
    assert "| baseline |" in text and "<= 10 deg" in text and "<= 4 M" in text
    # the baseline holds every bone without a sensor at rest: straight elbows (they carry no
    # sensor); 6 s clips hold no 10 s window, so no travel ratio, shown as "-"
    assert res["baseline"]["elbow_p95"] == pytest.approx(0.0, abs=1e-3)
    assert res["baseline"]["travel_windows"] == 0 and np.isnan(res["baseline"]["travel_ratio"])
    assert "## Speed and reach" in text and "| baseline | - | 0.0 / 0.0 |" in text
    assert "## Per joint" in text and "| 20 left_wrist |" in text and "| 23 right_hand |" in text
    wrist = next(line for line in text.splitlines() if line.startswith("| 20 left_wrist |"))
    assert len(wrist.split("|")) == 2 + 1 + 2 * len(res)                       # joint + 2 per method
    if models:
        assert "(the same model)" in text and "different models" not in text
    # the model's hardest clip, with the baseline's figure beside it; one subject: no subject table
    model = "ONNX fp32" if models else "PyTorch fp32"
    hardest = max(res[model]["per_clip"], key=lambda c: c.pos)
    base_of = {c.name: c.pos for c in res["baseline"]["per_clip"]}
    assert f"## Hardest clips ({model}, by position error)" in text and "## Per subject" not in text
    assert f"| {hardest.name} | - | 6.0 | {hardest.angle:.2f} | {hardest.pos:.2f} | {base_of[hardest.name]:.2f} |" in text
    for png in ("per_joint_error.png", "error_over_time.png", "drift.png", "per_clip_error.png"):
        assert (out / png).stat().st_size > 1000


def test_per_clip_scores_add_up_to_the_headline_and_name_the_hardest_clip(tmp_path):
    """The per-clip figures are frame-weighted parts of the headline means; the report's hardest
    clip and the per-subject rows come from them, and clips.csv holds every clip."""
    import csv
    # The baseline leaves the thighs at rest: a squat's knees and feet are far off.
    kinds = ["arm_swing", "squat", "walk"]
    motions = [replace(procedural.make_motion(k, 3.0 + i, seed=i), name=f"{k}_clip", subject=10 + i % 2)
               for i, k in enumerate(kinds)]
    out = tmp_path / "res"
    r = ev.evaluate(motions, [], None, out, seed=2, latency=False, source="procedural")
    base = r["results"]["baseline"]
    scores = base["per_clip"]
    assert [c.name for c in scores] == [m.name for m in motions]
    assert [c.frames for c in scores] == [m.num_frames for m in motions]
    assert ev._frame_mean(scores, "pos") == pytest.approx(base["pos"], rel=1e-9)
    assert ev._frame_mean(scores, "angle") == pytest.approx(base["angle_all"], rel=1e-9)
    hardest = max(scores, key=lambda c: c.pos)
    assert hardest.name == "squat_clip"
    # one clip's figure recomputed from its own prediction
    clip = ev.synthesize_clip(motions[0], np.random.default_rng(2))
    _, p_pred = ev.root_aligned_positions(ev.predict_baseline(clip).local_rot, clip.offsets)
    _, p_true = ev.root_aligned_positions(clip.local_rot, clip.offsets)
    assert scores[0].pos == pytest.approx(100 * np.linalg.norm(p_pred - p_true, axis=-1).mean(), rel=1e-9)
    text = (out / "evaluation.md").read_text()
    assert "## Per subject (baseline)" in text and "## Hardest clips (baseline" in text
    rows = [line for line in text.split("## Hardest clips")[1].splitlines() if line.startswith("| ")]
    assert rows[1].startswith(f"| {hardest.name} | ")          # after the header, worst first
    assert len(rows) == 1 + len(motions) - 1                      # all but one clip, at most 10
    # "without them": the one clip left is the easiest
    easiest = min(scores, key=lambda c: c.pos)
    assert f"would be {easiest.pos:.2f} cm instead of {base['pos']:.2f}" in text
    subj10 = [c for c in scores if c.subject == 10]
    row10 = next(line for line in text.split("## Per subject")[1].splitlines() if line.startswith("| 10 |"))
    assert f"| {ev._frame_mean(subj10, 'pos'):.2f} |" in row10
    with open(out / "clips.csv") as f:
        table = list(csv.DictReader(f))
    assert [t["clip"] for t in table] == [m.name for m in motions]
    for t, c in zip(table, scores):
        assert float(t["baseline position (cm)"]) == pytest.approx(c.pos, abs=1e-4)
        assert int(t["subject"]) == c.subject


def test_a_checkpoint_that_is_not_the_onnx_model_is_flagged(tmp_path, capsys):
    if not ort.onnx_runtime_available():
        pytest.skip("ONNX Runtime not available")
    torch.manual_seed(0)
    cfg = ModelConfig(embed=16, hidden=8, layers=1, head=16)
    exported, other = PoseNet(cfg).eval(), PoseNet(cfg).eval()
    _export(MirrorEnsemble(exported), tmp_path / "tiny_fp32.onnx", cfg.layers, 2 * cfg.hidden)
    ckpt = tmp_path / "other.pt"
    torch.save({"model": other.state_dict(), "config": cfg.to_dict()}, ckpt)
    motions = [procedural.make_motion("walk", 3.0, seed=0)]
    ev.evaluate(motions, [tmp_path / "tiny_fp32.onnx"], ckpt, tmp_path / "res", seed=1, latency=False)
    assert "is not the model the ONNX fp32 file was exported from" in capsys.readouterr().out
    text = (tmp_path / "res" / "evaluation.md").read_text()
    assert "**different models**" in text and "other.pt" in text


def test_default_checkpoint_is_never_a_running_jobs_last_pt():
    assert not any(c.endswith("last.pt") for c in ev.CHECKPOINT_CANDIDATES)
    assert ev.CHECKPOINT_CANDIDATES[-1] == "training/checkpoints/mocap_pose.pt"
    assert (ev.REPO / ev.CHECKPOINT_CANDIDATES[-1]).is_file()


def test_cli_on_a_bvh_folder(tmp_path, fixture_dir):
    d, _ = fixture_dir
    out = tmp_path / "res"
    rc = ev.main(["--bvh", str(d), "--no-torch", "--models", "--out", str(out), "--max-clips", "2",
                  "--no-latency", "--no-cache"])
    assert rc == 0
    text = (out / "evaluation.md").read_text()
    assert "2 clips" in text and "| baseline |" in text


def test_a_damaged_bvh_in_the_folder_is_named_without_a_traceback(tmp_path, fixture_dir, capsys):
    import shutil
    from training.__main__ import main as training_main
    src, _ = fixture_dir
    d = tmp_path / "folder"
    shutil.copytree(src, d)
    victim = sorted(d.rglob("*.bvh"))[1]
    lines = victim.read_text().split("\n")
    motion = lines.index("MOTION")
    lines[motion + 5] = " ".join(["nan"] + lines[motion + 5].split()[1:])   # one frame damaged
    victim.write_text("\n".join(lines))
    rc = training_main(["evaluate", "--bvh", str(d), "--no-torch", "--models", "--out", str(tmp_path / "r"),
                        "--no-latency", "--no-cache"])
    err = capsys.readouterr().err
    assert rc == 1
    assert victim.name in err and "not finite" in err, err
    assert "Traceback" not in err


def test_wrist_sensor_place_changes_what_the_wrist_sensors_report():
    m = procedural.make_motion("mixed", 2.0, seed=3)
    strap = ev.synthesize_clip(m, np.random.default_rng(0), wrist="forearm")
    hand = ev.synthesize_clip(m, np.random.default_rng(0))
    # same noise draws: only the wrist sensors differ, by the hand's bend
    np.testing.assert_allclose(strap.imu_orientation[:, [0, 3, 4, 5]], hand.imu_orientation[:, [0, 3, 4, 5]])
    assert ev.rotation_angle_deg(strap.imu_orientation[:, 1:3], hand.imu_orientation[:, 1:3]).max() > 2.0
    g, _ = sk.forward_kinematics(hand.local_rot, np.zeros((len(hand.local_rot), 3)), hand.offsets)
    pred = ev.predict_baseline(strap, "forearm")
    gb, _ = sk.forward_kinematics(pred.local_rot, np.zeros((len(g), 3)), strap.offsets)
    np.testing.assert_allclose(gb[:, 18:20], strap.imu_orientation[:, 1:3], atol=1e-5)
    with pytest.raises(ValueError, match="wrist sensor place 'elbow'"):
        ev.synthesize_clip(m, np.random.default_rng(0), wrist="elbow")


def test_body_scale_is_the_same_motion_on_a_larger_performer(tmp_path, fixture_dir):
    m = procedural.make_motion("walk", 3.0, seed=2)
    base = ev.synthesize_clip(m, np.random.default_rng(0))
    tall = ev.synthesize_clip(m, np.random.default_rng(0), body_scale=1.15)
    np.testing.assert_allclose(tall.offsets, 1.15 * base.offsets, rtol=1e-6)
    np.testing.assert_allclose(tall.root_pos, 1.15 * base.root_pos, rtol=1e-5, atol=1e-6)
    np.testing.assert_array_equal(tall.local_rot, base.local_rot)
    # the same noise draws: orientations identical, the sensors' accelerations larger
    np.testing.assert_array_equal(tall.imu_orientation, base.imu_orientation)
    ratio = np.abs(tall.imu_acceleration).mean() / np.abs(base.imu_acceleration).mean()
    assert 1.08 < ratio < 1.16
    with pytest.raises(ValueError, match="body scale 3"):
        ev.eval_augmentation("realistic", 3.0)
    reports = _baseline_reports(tmp_path, fixture_dir, "--body-scale", ("1", "0.86"))
    assert "Every performer 0.86 times their size" in reports["0.86"]
    assert "times their size" not in reports["1"]


@pytest.mark.parametrize("option, value", [("--seed", "-1"), ("--max-seconds", "nan"), ("--max-seconds", "inf"),
                                           ("--max-seconds", "-1"), ("--max-seconds", "0"),
                                           ("--max-clips", "-1"), ("--max-clips", "0"),
                                           ("--body-scale", "0.4"), ("--body-scale", "2.5"),
                                           ("--body-scale", "nan")])
def test_bad_option_values_are_usage_errors(option, value, capsys):
    parser = ev.add_arguments(__import__("argparse").ArgumentParser(prog="evaluate"))
    with pytest.raises(SystemExit) as e:
        parser.parse_args([option, value])
    assert e.value.code == 2 and f"argument {option}" in capsys.readouterr().err


def test_max_seconds_shorter_than_a_frame_is_refused():
    from training.errors import UsageError
    m = procedural.make_motion("walk", 1.0, seed=0)
    with pytest.raises(UsageError, match="--max-seconds 0.001 is shorter than one frame"):
        ev._trim([m], 0, 0.001)
    assert ev._trim([m, m], 1, 0.5)[0].num_frames == 30


def test_a_report_with_nan_model_metrics_is_refused(tmp_path):
    """NaN metrics are a broken model (or input), not a "-" in a report."""
    from training.errors import CommandError
    torch.manual_seed(0)
    cfg = ModelConfig(embed=16, hidden=8, layers=1, head=16)
    net = PoseNet(cfg).eval()
    with torch.no_grad():
        next(net.parameters()).fill_(float("nan"))
    ckpt = tmp_path / "nan.pt"
    torch.save({"model": net.state_dict(), "config": cfg.to_dict()}, ckpt)
    out = tmp_path / "res"
    with pytest.raises(CommandError, match=r"the PyTorch fp32 results are not finite \(angle_all"):
        ev.evaluate([procedural.make_motion("walk", 1.0, seed=0)], (), ckpt, out, latency=False)
    assert not (out / "evaluation.md").exists()


def test_an_unusable_clip_in_the_folder_is_one_line_naming_it(tmp_path, fixture_dir, capsys):
    import shutil
    import re
    from training.__main__ import main as training_main
    src, _ = fixture_dir
    d = tmp_path / "folder"
    shutil.copytree(src, d)
    victim = sorted(d.rglob("*.bvh"))[1]
    victim.write_text(re.sub(r"(End Site\s*\{\s*OFFSET)[^\n]*", r"\1 0 0 0", victim.read_text()))
    rc = training_main(["evaluate", "--bvh", str(d), "--no-torch", "--models", "--out", str(tmp_path / "r"),
                        "--no-latency", "--no-cache"])
    err = capsys.readouterr().err
    assert rc == 1 and "Traceback" not in err
    assert f"{victim}: the bone" in err and "zero length" in err, err
    assert not (tmp_path / "r" / "evaluation.md").exists()


@pytest.mark.skipif(not ort.onnx_runtime_available(),
                    reason="ONNX Runtime not available (scripts/fetch_onnxruntime.sh)")
@pytest.mark.parametrize("geometry", ["graph", "engine"])
def test_latency_is_timed_on_the_models_own_sensors(tmp_path, geometry):
    """A seven-sensor masked model (graph or network-only file) is timed on seven sensors with its
    mask, not on the default six, which mocapctl would refuse."""
    from training import export
    seven = se.DEFAULT_SENSORS + ("chest",)
    cfg = ModelConfig(32, 32, 1, 32, anchored=True, sensors=seven, optional=("chest",), masked=True)
    export.export(export.untrained_model(seed=0, config=cfg), tmp_path / "m", check=False,
                  geometry=geometry)
    timing = ev.measure_latency(tmp_path / "m" / export.FP32_NAME, frames=90)
    assert timing["calls"] == 90 and timing["p50_us"] > 0
