"""engine-eval: the drift, lag and contact measures on series whose answer is known, and one
short run through mocapctl whose figures agree with mocapctl's own."""
import math
import re

import numpy as np
import pytest

from training import engine_eval as ee
from training import ort, skeleton as sk
from training.errors import UsageError

needs_ort = pytest.mark.skipif(not ort.onnx_runtime_available(),
                               reason="ONNX Runtime not fetched (scripts/fetch_onnxruntime.sh)")


def test_window_drift_compares_displacements_over_windows_starting_every_second():
    t = np.arange(0, 12.0 + 1e-9, 1 / 60.0)
    true = np.stack([t, np.zeros_like(t), np.zeros_like(t)], -1)       # 1 m/s along x
    pred = true * 0.9                                                  # 10 % short
    d = ee.window_drift(t, pred, true, 5.0)
    assert len(d) == 8                                                 # starts 0..7 s end by 12 s
    assert np.allclose(d, 0.5, atol=1e-6)
    assert ee.window_drift(t, true + 3.0, true, 10.0) == pytest.approx([0.0] * 3, abs=1e-12)
    assert ee.window_drift(t[:30], pred[:30], true[:30], 2.0) == []     # shorter than a window


def test_integrated_root_starts_at_zero_and_sums_the_velocity():
    v = np.tile([[0.6, 0.0, -1.2]], (61, 1))
    r = ee.integrated_root(v, 60.0)
    assert np.array_equal(r[0], [0, 0, 0]) and r[60] == pytest.approx([0.6, 0.0, -1.2])


def test_the_lag_of_a_delayed_copy_is_its_delay():
    rng = np.random.default_rng(0)
    rot = np.cumsum(rng.normal(0, 0.05, (600, 24, 3)), axis=0)             # a wandering pose
    q = sk.quat_from_rot(_rotvec_to_matrix(rot))
    for delay in (0, 4, 9):
        delayed = np.concatenate([np.repeat(q[:1], delay, axis=0), q[:len(q) - delay]])
        assert ee.filter_lag_ms(delayed, q, 60.0) == pytest.approx(1000 * delay / 60.0, abs=3.0)
    # a half-frame delay (linear interpolation) lands between frames
    half = sk.quat_from_rot(_rotvec_to_matrix(np.concatenate([rot[:1], 0.5 * (rot[1:] + rot[:-1])])))
    assert ee.filter_lag_ms(half, q, 60.0) == pytest.approx(1000 * 0.5 / 60.0, abs=4.0)
    assert math.isnan(ee.filter_lag_ms(q[:2], q[:2], 60.0))


def _rotvec_to_matrix(v):
    theta = np.linalg.norm(v, axis=-1, keepdims=True)
    k = v / np.maximum(theta, 1e-12)
    K = np.zeros(v.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -k[..., 2], k[..., 1], -k[..., 0]
    K = K - np.swapaxes(K, -1, -2)
    th = theta[..., None]
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def test_contact_quality_counts_hits_predictions_and_truths():
    pred = np.array([[1, 0], [1, 1], [0, 0]], bool)
    true = np.array([[1, 1], [0, 1], [0, 1]], bool)
    assert ee.contact_quality(pred, true) == (2, 3, 4)


def test_bad_options_are_usage_errors(tmp_path):
    with pytest.raises(UsageError, match="no such file"):
        ee.main(["--procedural", "--model", str(tmp_path / "none.onnx")])
    with pytest.raises(SystemExit):
        ee.main(["--procedural", "--smoothing", "-1"])


@needs_ort
def test_a_short_run_through_mocapctl_agrees_with_mocapctls_own_figures(tmp_path):
    out, keep = tmp_path / "engine.md", tmp_path / "keep"
    # Broken poses judged against a range the test makes: the procedural motions', with the right
    # elbow allowed only straight, which the model's bent elbow leaves in every pose.
    from training import dropout_eval as de, pose_range
    limits = pose_range.build_pose_range(de.procedural_clips(5, 10.0, 7), source="test motions")
    limits.covers[19] = np.array([[1.0, 0.0, 0.0, 0.0]])
    saved = limits.save(tmp_path / "range.npz")
    assert ee.main(["--procedural", "--clips", "2", "--clip-seconds", "16", "--smoothing", "2,12", "6,12",
                    "--out", str(out), "--keep", str(keep), "--pose-range", str(saved)]) == 0
    text = out.read_text()
    assert "python3 -m training engine-eval --procedural --clips 2 --clip-seconds 16 --seed 0 " \
           "--smoothing 2,12 6,12" in text
    for row in ("| raw model output (--smoothing 0) |", "| --smoothing 2,12 (the engine's default) |",
                "| --smoothing 6,12 |"):
        assert text.count(row) == 3, row          # the filter, broken-pose and drift tables
    assert "`python3 -m training pose-range`: test motions" in text
    broken = re.search(r"^\| raw model output \(--smoothing 0\) \| (\d+) \| 100\.000 % \| 2 of 2 \| "
                       r"right_elbow (\d+)", text, re.M)
    assert broken and broken.group(1) == broken.group(2), text
    # This module's drift windows over the replayed poses are mocapctl's (--metrics-json).
    from training.synth_capture import load_truth
    import json
    for cap in sorted(keep.glob("*.cap")):
        truth = load_truth(cap.with_suffix(".truth.npz"))
        r = ee.read_replay(cap.with_suffix(".2_12.csv"), cap.with_suffix(".2_12.json"), truth)
        m = json.loads(cap.with_suffix(".2_12.json").read_text())
        assert len(r.times) == m["poses"]
        true = np.asarray(truth["root_pos"], np.float64)[r.truth_index]
        for w in (2.0, 5.0, 10.0):
            key = f"{w:g}s"
            assert np.mean(ee.window_drift(r.times, r.root, true, w)) == pytest.approx(m["root_drift_m"][key], abs=2e-3)
            assert np.mean(ee.window_drift(r.times, ee.integrated_root(r.velocity, 60.0), true, w)) == \
                pytest.approx(m["root_drift_integrated_velocity_m"][key], abs=2e-3)
    # The filter removes jitter, a higher cut-off less of it; with its trend it adds no more than
    # a frame of latency.
    s = ee.summarize(_clips_from(keep), ["2,12", "6,12"])
    assert s["2,12"]["jitter"] < s["6,12"]["jitter"] < s["0"]["jitter"]
    assert -5 < s["6,12"]["lag_ms"] < 10 and -5 < s["2,12"]["lag_ms"] < 10 and s["0"]["lag_ms"] == 0


def _clips_from(keep):
    """The kept replays as ClipResults, as run_evaluation made them."""
    from training.synth_capture import load_truth
    clips = []
    for cap in sorted(keep.glob("*.cap")):
        truth = load_truth(cap.with_suffix(".truth.npz"))
        c = ee.ClipResult.from_truth(cap.stem, len(truth["root_pos"]) / 60.0, truth)
        for s, tag in (("0", "raw"), ("2,12", "2_12"), ("6,12", "6_12")):
            c.runs[s] = ee.read_replay(cap.with_suffix(f".{tag}.csv"), cap.with_suffix(f".{tag}.json"), truth)
        clips.append(c)
    return clips


def test_scaled_motion_scales_the_body_and_its_path_only():
    from training import procedural
    m = procedural.make_motion("walk", seconds=2, seed=1, name="walk")
    big = ee.scaled_motion(m, 1.14)
    assert np.allclose(big.offsets, 1.14 * m.offsets, atol=1e-6)
    assert np.allclose(big.root_pos, 1.14 * m.root_pos, atol=1e-5)
    assert np.array_equal(big.local_rot, m.local_rot)
    assert ee.scaled_motion(m, 1.0) is m


@needs_ort
def test_a_height_reaches_the_engine_and_drift_is_read_in_the_performers_metres(tmp_path):
    out, keep = tmp_path / "engine.md", tmp_path / "keep"
    assert ee.main(["--procedural", "--pose-range", "none", "--clips", "1", "--clip-seconds", "16", "--body-scale", "1.14",
                    "--height", "1.96", "--out", str(out), "--keep", str(keep)]) == 0
    text = out.read_text()
    assert "--body-scale 1.14 --height 1.96" in text
    assert "told the performer is 1.96 m tall" in text
    from training import ort
    from training.synth_capture import load_truth
    info = ort.model_info(str(ee.add_arguments().get_default("model")))
    unit = 1.96 / info["training_height"]
    gain = unit ** (info["stride_exponent"] - 1.0)
    cap = next(keep.glob("*.cap"))
    truth = load_truth(cap.with_suffix(".truth.npz"))
    told = ee.read_replay(cap.with_suffix(".2_12.csv"), cap.with_suffix(".2_12.json"), truth)
    # the same capture without the height: the engine's velocity is the model's times the gain
    plain_csv, plain_json = tmp_path / "plain.csv", tmp_path / "plain.json"
    from training.dropout_eval import replay_command
    from training.ort import mocapctl_path
    import subprocess
    cmd = replay_command(mocapctl_path(), cap, cap.with_suffix(".truth.csv"),
                         ee.add_arguments().get_default("model"), plain_csv, plain_json) + ["--smoothing", "2,12"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    plain = ee.read_replay(plain_csv, plain_json, truth)
    assert len(plain.velocity) == len(told.velocity) > 500
    assert np.allclose(told.velocity, gain * plain.velocity, atol=2e-5)
    # the clip's drift reads the engine's root back in the performer's metres
    c = ee.ClipResult.from_truth(cap.stem, 16.0, truth)
    c.runs["2,12"], c.root_unit = told, unit
    true = np.asarray(truth["root_pos"], np.float64)[told.truth_index]
    assert ee.clip_drift(c, "2,12")[10.0][0] == pytest.approx(ee.window_drift(told.times, told.root * unit, true, 10.0))


def test_wait_settings_are_read_and_checked():
    assert ee.wait_frames("wait2") == 2 and ee.wait_frames("2,12") == 0 and ee.wait_frames("0") == 0
    for good in ("wait1", "wait4", "2,12", "0"):
        assert ee._smoothing_ok(good), good
    for bad in ("wait0", "wait5", "wait", "waitx", "wait1,2"):
        assert not ee._smoothing_ok(bad), bad


@needs_ort
def test_smoothing_that_waits_runs_through_mocapctl(tmp_path):
    # the engine's waiting smoother (mocapctl --smoothing wait1): poses stamped with their own
    # frames, so they align with the raw ones and the latency is the frame waited for; less
    # jitter than the raw output at about its angle error
    out, keep = tmp_path / "engine.md", tmp_path / "keep"
    assert ee.main(["--procedural", "--pose-range", "none", "--clips", "2", "--clip-seconds", "16", "--smoothing", "wait1",
                    "--out", str(out), "--keep", str(keep)]) == 0
    assert out.read_text().count("| --smoothing wait1 |") == 2
    from training.synth_capture import load_truth
    clips = []
    for cap in sorted(keep.glob("*.cap")):
        truth = load_truth(cap.with_suffix(".truth.npz"))
        c = ee.ClipResult.from_truth(cap.stem, len(truth["root_pos"]) / 60.0, truth)
        for s, tag in (("0", "raw"), ("wait1", "wait1")):
            c.runs[s] = ee.read_replay(cap.with_suffix(f".{tag}.csv"), cap.with_suffix(f".{tag}.json"), truth)
        assert len(c.runs["wait1"].times) == len(c.runs["0"].times)   # every frame keeps its pose
        clips.append(c)
    s = ee.summarize(clips, ["wait1"])
    assert s["wait1"]["lag_ms"] == pytest.approx(1000.0 / 60.0, abs=1.0)
    assert s["wait1"]["jitter"] < 0.6 * s["0"]["jitter"]
    assert s["wait1"]["angle"] < s["0"]["angle"] + 0.05


def test_foot_slide_counts_only_frame_pairs_where_the_foot_stays_planted():
    pos = np.zeros((10, 24, 3))
    pos[:, 10, 0] = 0.01 * np.arange(10)          # the left foot moves 1 cm a frame
    pos[:, 11, 1] = 0.02 * np.arange(10)          # the right one only rises
    planted = np.zeros((10, 2), bool)
    planted[:5, 0] = True                         # left planted in frames 0-4: 4 pairs
    planted[3:, 1] = True                         # right planted in 3-9: 6 pairs
    speeds = ee.foot_slide(pos, planted, 60.0)
    assert len(speeds) == 10
    assert sorted(speeds.round(9).tolist()) == [0.0] * 6 + [0.6] * 4   # vertical motion is not slide


def test_pin_settings_are_read_and_checked():
    assert ee.setting_parts("2,12+pin0.06") == ("2,12", 0.06, 0.0, 0.0)
    assert ee.setting_parts("wait1") == ("wait1", 0.0, 0.0, 0.0)
    for good in ("2,12+pin0.06", "wait1+pin0.1", "0+pin1"):
        assert ee._smoothing_ok(good), good
    for bad in ("2,12+pin0", "2,12+pin1.5", "2,12+pinx", "+pin0.06", "wait0+pin0.06"):
        assert not ee._smoothing_ok(bad), bad
    assert ee._label("2,12+pin0.06") == "--smoothing 2,12 --foot-pin 0.06"


def test_limit_settings_are_read_and_checked():
    assert ee.setting_parts("2,12+limit25") == ("2,12", 0.0, 25.0, 0.0)
    assert ee.setting_parts("wait1+pin0.06+limit25") == ("wait1", 0.06, 25.0, 0.0)
    for good in ("2,12+limit25", "0+limit2", "wait1+pin0.06+limit90"):
        assert ee._smoothing_ok(good), good
    for bad in ("2,12+limit0", "2,12+limit0.5", "2,12+limit91", "2,12+limitx", "+limit25",
                "2,12+limit25+pin0.06"):
        assert not ee._smoothing_ok(bad), bad
    assert ee._label("2,12+limit25") == "--smoothing 2,12 --pose-limits 25"
    assert ee._label("wait1+pin0.06+limit25") == "--smoothing wait1 --foot-pin 0.06 --pose-limits 25"


@needs_ort
def test_pose_limits_in_the_engine_are_the_reference_guard(tmp_path):
    """With every sensor live the network reads the same inputs either way, so the engine's
    guarded poses are pose_range.guard_quats of its raw ones, on the engine's own table."""
    from training import pose_range as pr
    from training.synth_capture import load_truth
    keep = tmp_path / "keep"
    assert ee.main(["--procedural", "--pose-range", "none", "--clips", "1", "--clip-seconds", "16",
                    "--smoothing", "0+limit3", "--keep", str(keep), "--out", str(tmp_path / "e.md")]) == 0
    cap = sorted(keep.glob("*.cap"))[0]
    truth = load_truth(cap.with_suffix(".truth.npz"))
    raw = ee.read_replay(cap.with_suffix(".raw.csv"), cap.with_suffix(".raw.json"), truth)
    held = ee.read_replay(cap.with_suffix(".0+limit3.csv"), cap.with_suffix(".0+limit3.json"), truth)
    assert len(raw.quats) == len(held.quats) > 500
    cover = pr.read_engine_table()
    want, moved = pr.guard_quats(raw.quats, cover, 3.0)
    assert moved.sum() > len(raw.quats), "a 3 deg tolerance turns joints back"
    assert not moved[:, 0].any()
    sign = np.sign(np.sum(want * held.quats, axis=-1, keepdims=True))
    assert np.abs(want * sign - held.quats).max() < 1e-4
    assert (held.quats[~moved] == raw.quats[~moved]).all(), "a joint in range is left as it was"


@needs_ort
def test_foot_pinning_runs_through_mocapctl_and_slows_planted_feet(tmp_path):
    out = tmp_path / "engine.md"
    assert ee.main(["--procedural", "--pose-range", "none", "--clips", "2", "--clip-seconds", "16", "--smoothing", "2,12",
                    "2,12+pin0.06", "--out", str(out)]) == 0
    text = out.read_text()
    slide = {}
    for line in text.splitlines():
        for label in ("--smoothing 2,12 (the engine's default)", "--smoothing 2,12 --foot-pin 0.06"):
            if line.startswith(f"| {label} |") and line.count("|") == 10:   # the drift table's row
                slide[label] = float(line.split("|")[-2])
    free, pinned = slide["--smoothing 2,12 (the engine's default)"], slide["--smoothing 2,12 --foot-pin 0.06"]
    assert 0.0 < pinned < free, (pinned, free)
    assert "planted feet slide" in text and "The motion capture's own planted feet slide" in text


def test_chest_settings_are_read_checked_and_passed_to_mocapctl():
    assert ee.setting_parts("2,12+chest0.5") == ("2,12", 0.0, 0.0, 0.5)
    assert ee.setting_parts("wait1+pin0.06+limit25+chest1") == ("wait1", 0.06, 25.0, 1.0)
    for good in ("2,12+chest0.5", "0+limit25+chest0.25", "wait1+pin0.06+limit25+chest1"):
        assert ee._smoothing_ok(good), good
    for bad in ("2,12+chest0", "2,12+chest1.5", "2,12+chestx", "+chest0.5", "2,12+chest0.5+limit25"):
        assert not ee._smoothing_ok(bad), bad
    assert ee.engine_options("2,12+limit25+chest0.5") == [
        "--smoothing", "2,12", "--pose-limits", "25", "--chest-follow", "0.5"]
    assert ee._label("2,12+chest0.5") == "--smoothing 2,12 --chest-follow 0.5"
