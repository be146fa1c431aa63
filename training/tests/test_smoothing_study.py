"""smoothing-study: centred binomial windows on joint rotations. They must leave motion that is
linear over the window exactly as it was (no lag against the frame they are stamped with), take
out frame-to-frame noise, and score better than the noisy output they smooth."""
import numpy as np
import pytest

from training import procedural, skeleton as sk
from training import smoothing_study as ss
from training.evaluate import Prediction, synthesize_clip


def test_binomial_weights():
    assert ss.binomial_weights(1) == pytest.approx([0.25, 0.5, 0.25])
    assert ss.binomial_weights(2) == pytest.approx(np.array([1, 4, 6, 4, 1]) / 16)
    assert ss.binomial_weights(3).sum() == pytest.approx(1.0)


def test_a_steady_turn_passes_unchanged_and_noise_is_taken_out():
    T = 120
    # a steady turn of 1.7 deg per frame through 206 deg: past 180 deg the quaternions (w >= 0)
    # jump to the other hemisphere, which the window must follow
    angle = np.linspace(0.0, 3.6, T)
    steady = np.repeat(sk.rot_axis("y", angle)[:, None], 24, axis=1)
    for d in (1, 2):
        out = ss.centered_smooth(steady, d)
        inner = slice(d, T - d)   # the ends repeat their frame, so only the middle is exact
        assert np.abs(out[inner] - steady[inner]).max() < 1e-12
    assert np.array_equal(ss.centered_smooth(steady, 0), steady)
    rng = np.random.default_rng(0)
    noise = sk.axis_angle_to_rot(rng.normal(scale=np.radians(2.0), size=(T, 24, 3)))
    noisy = steady @ noise
    from training.evaluate import rotation_angle_deg
    err_raw = rotation_angle_deg(noisy, steady)[5:-5].mean()
    err_1 = rotation_angle_deg(ss.centered_smooth(noisy, 1), steady)[5:-5].mean()
    err_2 = rotation_angle_deg(ss.centered_smooth(noisy, 2), steady)[5:-5].mean()
    assert err_2 < err_1 < 0.75 * err_raw   # white noise: error falls as the window widens


def test_the_study_scores_the_smoothed_output_better_than_the_noisy_one():
    rng = np.random.default_rng(1)
    clips = [synthesize_clip(procedural.make_motion(kind, seconds=6, seed=i), rng, noise="none")
             for i, kind in enumerate(procedural.KINDS[:3])]
    predictions = []
    for c in clips:   # the truth with noise on every joint: what a network's output looks like
        noise = sk.axis_angle_to_rot(rng.normal(scale=np.radians(1.5), size=c.local_rot.shape[:2] + (3,)))
        predictions.append(Prediction(c.local_rot @ noise, np.zeros((c.local_rot.shape[0], 3))))
    rows = ss.study(clips, predictions, [1, 2])
    assert [r["delay"] for r in rows] == [0, 1, 2]
    raw, one, two = rows
    assert one["angle"] < raw["angle"] and two["angle"] < one["angle"]
    assert one["jitter_ratio"] < 0.5 * raw["jitter_ratio"] and two["jitter"] < one["jitter"]


def test_the_report_states_latency_and_the_changes(tmp_path):
    rows = [{"label": "raw network output", "delay": 0, "angle": 9.0, "pos": 6.0, "jitter": 10.0, "jitter_ratio": 3.0},
            {"label": "centred window, 1 frame later", "delay": 1, "angle": 8.99, "pos": 5.99, "jitter": 4.0,
             "jitter_ratio": 1.2}]
    path = ss.write_report(tmp_path / "s.md", rows, {"clips": 2, "split": "val", "clip_seconds": 40,
                                                    "seconds": 80, "model": "m.onnx", "command": "c"})
    text = path.read_text()
    assert "| centred window, 1 frame later | 16.7 | 8.990 | 5.990 | 4.00 | 1.20 |" in text
    assert "angle -0.010 deg, position -0.010 cm, jitter 1.20x" in text
