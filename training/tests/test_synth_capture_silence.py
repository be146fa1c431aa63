"""synth-capture --silence: windows parsed and checked before anything is written, passed on to
`mocapctl synth --silence`, and recorded in the pose truth."""
import subprocess

import numpy as np
import pytest

from training import bvh, ort, procedural
from training import synth_capture as sc
from training.errors import UsageError


def test_silence_text_is_parsed_or_refused_saying_why():
    s = sc.parse_silence("left_wrist@10+5")
    assert (s.segment, s.start_s, s.length_s, s.end_s) == ("left_wrist", 10.0, 5.0, 15.0)
    assert str(s) == "left_wrist@10.0+5.0" and sc.parse_silence(str(s)) == s
    assert sc.parse_silence(sc.Silence("head", np.float64(1.5), 2)) == sc.Silence("head", 1.5, 2.0)
    for bad, why in (("left_wrist", "not SEGMENT@START"), ("left_wrist@10", "not SEGMENT@START"),
                     ("@1+2", "not SEGMENT@START"), ("head@x+1", "not SEGMENT@START"),
                     ("head@-1+2", "start must be >= 0"), ("head@1+0", "length > 0"),
                     ("head@nan+1", "start must be >= 0"), ("head@1+inf", "length > 0")):
        with pytest.raises(ValueError, match=why):
            sc.parse_silence(bad)
    with pytest.raises(ValueError, match="chest is not one of the capture's sensors"):
        sc.silence_list(["chest@1+1"], sc.TRAJECTORY_SENSORS)
    with pytest.raises(ValueError, match="17 silence windows, at most 16"):
        sc.silence_list(["head@1+1"] * 17, sc.TRAJECTORY_SENSORS)


def test_a_bad_window_is_a_usage_error_before_anything_is_written(tmp_path):
    clip = tmp_path / "clip.bvh"
    bvh.write_bvh(clip, procedural.motion_to_daz(procedural.make_motion("walk", 1.0, seed=3)))
    for bad in ("chest@0.5+1", "head@0.5"):
        with pytest.raises(UsageError, match="--silence"):
            sc.main([str(clip), "--out", str(tmp_path / "c.cap"), "--silence", bad])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.bvh"]


def test_windows_reach_the_capture_and_the_truth(tmp_path):
    """Two windows: each sensor is left out of the capture exactly in its own (the engine's
    per-sensor summary counts the stale frames) and the truth lists both."""
    clip = tmp_path / "clip.bvh"
    bvh.write_bvh(clip, procedural.motion_to_daz(procedural.make_motion("mixed", 5.0, seed=5)))
    cap = tmp_path / "clip.cap"
    assert sc.main([str(clip), "--out", str(cap), "--silence", "head@1+2", "--silence",
                    "left_shin@3.5+1"]) == 0
    truth = sc.load_truth(tmp_path / "clip.truth.npz")
    assert list(truth["silences"]) == ["head@1.0+2.0", "left_shin@3.5+1.0"]
    r = subprocess.run([str(ort.mocapctl_path(require_onnx=False)), "replay", str(cap), "--truth",
                        str(tmp_path / "clip.sensors.csv")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    stale = {}
    for line in r.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 5 and parts[0] in sc.TRAJECTORY_SENSORS and parts[2].endswith("%"):
            stale[parts[0]] = int(parts[4])
    # Stale once a sensor has said nothing for 0.25 s: (2 - 0.24) s and (1 - 0.24) s at 60 Hz.
    assert stale["head"] == pytest.approx(105, abs=1), r.stdout
    assert stale["left_shin"] == pytest.approx(45, abs=1), r.stdout
    assert all(stale[s] == 0 for s in stale if s not in ("head", "left_shin")), r.stdout
