"""synth-capture end to end: procedural BVH -> capture -> the engine's replay calibrates and
matches the truth."""
import re
import subprocess

import numpy as np
import pytest

from training import bvh, ort, procedural, retarget
from training import skeleton as sk
from training import synth_capture as sc
from training.errors import UsageError


def test_trajectory_resampling_keeps_the_signal():
    m = procedural.make_motion("walk", 2.0, seed=1)
    ori, acc = sc.sensor_signals(m)
    t, q, a = sc.resample_signals(ori, acc, m.fps)
    assert np.isclose(t[1] - t[0], 0.01) and t[-1] <= (m.num_frames - 1) / m.fps + 1e-9
    # Samples that fall on a 60 Hz frame (every 3rd 60 Hz frame = every 5th 100 Hz sample).
    np.testing.assert_allclose(sk.rot_from_quat(q[::5]), ori[::3][:len(q[::5])], atol=1e-6)
    np.testing.assert_allclose(a[::5], acc[::3][:len(a[::5])], atol=1e-6)


def test_lead_in_starts_at_rest_and_ends_on_the_clip():
    m = procedural.make_motion("turn", 2.0, seed=2)
    full = sc.with_lead_in(m, 0.5)
    assert full.num_frames == m.num_frames + 30
    np.testing.assert_allclose(full.local_rot[0], np.broadcast_to(np.eye(3), (24, 3, 3)), atol=1e-6)
    np.testing.assert_allclose(full.local_rot[30:], m.local_rot)


def test_procedural_bvh_capture_replays_with_small_error(tmp_path):
    motion = procedural.make_motion("mixed", 4.0, seed=5)
    clip_path = tmp_path / "clip.bvh"
    bvh.write_bvh(clip_path, procedural.motion_to_daz(motion))
    cap = tmp_path / "clip.cap"
    assert sc.main([str(clip_path), "--out", str(cap), "--seed", "7", "--world", "enu"]) == 0
    truth = sc.load_truth(tmp_path / "clip.truth.npz")
    assert truth["local_rot"].shape[1:] == (24, 3, 3)
    assert int(truth["motion_start"]) == 60 and float(truth["fps"]) == 60.0
    assert float(truth["prelude_s"]) == pytest.approx(8.0, abs=0.02)
    # The truth is the clip as read back through BVH + retarget (after the lead-in).
    again = retarget.to_smpl_motion(bvh.read_bvh(clip_path))
    np.testing.assert_allclose(truth["local_rot"][60:], again.local_rot, atol=1e-5)

    r = subprocess.run([str(ort.mocapctl_path(require_onnx=False)), "replay", str(cap), "--truth",
                        str(tmp_path / "clip.sensors.csv")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.count("accepted") == 2, r.stdout
    worst = float(re.search(r"worst sensor mean ([\d.]+) deg", r.stdout).group(1))
    assert worst < 1.5, r.stdout
    calibrated = int(re.search(r"(\d+) calibrated", r.stdout).group(1))
    assert calibrated >= 0.9 * truth["local_rot"].shape[0], r.stdout


def test_a_capture_with_a_chest_sensor_replays_with_the_chest_calibrated(tmp_path):
    """--sensors: the trajectory names its segments, mocapctl synth writes the seventh node, and
    the engine's replay calibrates the chest and matches the generator's truth."""
    clip_path = tmp_path / "clip.bvh"
    bvh.write_bvh(clip_path, procedural.motion_to_daz(procedural.make_motion("mixed", 2.0, seed=5)))
    cap = tmp_path / "clip.cap"
    seven = "pelvis,left_wrist,right_wrist,left_shin,right_shin,head,chest"
    assert sc.main([str(clip_path), "--out", str(cap), "--seed", "7", "--sensors", seven,
                    "--keep-trajectory"]) == 0
    lines = (tmp_path / "clip.trajectory.txt").read_text().splitlines()
    assert "segments " + seven.replace(",", " ") in lines
    assert list(sc.load_truth(tmp_path / "clip.truth.npz")["sensors"]) == seven.split(",")
    r = subprocess.run([str(ort.mocapctl_path(require_onnx=False)), "replay", str(cap), "--truth",
                        str(tmp_path / "clip.sensors.csv"), "--sensors",
                        "pelvis=0,left_wrist=1,right_wrist=2,left_shin=3,right_shin=4,head=5,chest=6"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.count("accepted") == 2, r.stdout
    chest = re.search(r"^\s*chest\s+6\s+[\d.]+%\s+\d+\s+\d+\s+([\d.]+)", r.stdout, re.M)
    assert chest and float(chest.group(1)) < 1.5, r.stdout
    worst = float(re.search(r"worst sensor mean ([\d.]+) deg", r.stdout).group(1))
    assert worst < 1.5, r.stdout


def test_sensors_option_refuses_unknown_and_repeated_segments(tmp_path, capsys):
    clip_path = tmp_path / "clip.bvh"
    bvh.write_bvh(clip_path, procedural.motion_to_daz(procedural.make_motion("walk", 1.0, seed=1)))
    for bad, message in (("pelvis,tail", "unknown segment 'tail'"), ("pelvis,head,head", "head listed more than once")):
        with pytest.raises(UsageError, match=message):
            sc.synth_capture(clip_path, tmp_path / "c.cap", sensors=bad)
    assert not list(tmp_path.glob("c.*"))


def test_truth_path_without_npz_suffix_is_the_file_written(tmp_path, monkeypatch):
    """np.savez appends .npz to a name without it: the returned path must be that file."""
    from training import ort as ort_module

    def fake_synth(cmd, **kw):   # stands in for `mocapctl synth`: writes the sensor truth CSV
        sensors = cmd[cmd.index("--truth") + 1]
        with open(sensors, "w") as f:
            f.write("t,phase\n0.000,0\n8.000,3\n")
        return subprocess.CompletedProcess(cmd, 0, "synth ok", "")
    monkeypatch.setattr(ort_module, "mocapctl_path", lambda **k: "mocapctl")
    monkeypatch.setattr(sc.subprocess, "run", fake_synth)
    motion = procedural.make_motion("walk", 1.0, seed=1)
    for given, written in (("pose", "pose.npz"), ("pose.truth", "pose.truth.npz"), ("p.npz", "p.npz")):
        info = sc.synth_capture(None, tmp_path / "c.cap", truth=tmp_path / given, motion=motion)
        assert info["truth"] == tmp_path / written and info["truth"].is_file()
        assert int(sc.load_truth(info["truth"])["motion_start"]) == 60


def _clip(tmp_path, seconds=1.0):
    path = tmp_path / "clip.bvh"
    bvh.write_bvh(path, procedural.motion_to_daz(procedural.make_motion("walk", seconds, seed=3)))
    return path


def test_outputs_that_would_destroy_the_clip_or_each_other_are_refused(tmp_path):
    """`--out clip.bvh` (or --truth-csv / --sensor-truth) replaced the BVH being read; two outputs
    naming one file overwrote each other; an existing folder as output was half written."""
    from training.errors import UsageError
    clip = _clip(tmp_path)
    before = clip.read_bytes()
    for option in ("--out", "--truth-csv", "--sensor-truth"):
        argv = [str(clip), "--out", str(tmp_path / "x.cap"), option, str(clip)]
        with pytest.raises(UsageError, match="is the BVH clip this command reads"):
            sc.main(argv)
        assert clip.read_bytes() == before
    with pytest.raises(UsageError, match="name the same file"):
        sc.main([str(clip), "--out", str(tmp_path / "y.cap"), "--truth-csv", str(tmp_path / "y.cap")])
    (tmp_path / "folder").mkdir()
    with pytest.raises(UsageError, match="not a regular file"):
        sc.main([str(clip), "--out", str(tmp_path / "folder")])
    with pytest.raises(UsageError, match="names a folder"):
        sc.main([str(clip), "--out", str(tmp_path / "newfolder") + "/"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.bvh", "folder"]


@pytest.mark.parametrize("option,value", [("--seed", "-1"), ("--seed", "x"), ("--lead-in", "nan"),
                                          ("--lead-in", "inf"), ("--lead-in", "-1"),
                                          ("--lead-in", "100000")])
def test_out_of_range_values_are_usage_errors(tmp_path, option, value, capsys):
    with pytest.raises(SystemExit) as e:
        sc.main([str(tmp_path / "clip.bvh"), "--out", str(tmp_path / "x.cap"), option, value])
    assert e.value.code == 2
    assert option in capsys.readouterr().err


def test_a_failing_engine_step_is_one_error_and_leaves_no_files(tmp_path):
    """mocapctl synth cannot write the sensor truth (its folder does not exist): before, a
    traceback, and the trajectory and a capture were left behind."""
    from training.errors import CommandError
    clip = _clip(tmp_path)
    with pytest.raises(CommandError, match="mocapctl synth failed: .*missing"):
        sc.main([str(clip), "--out", str(tmp_path / "x.cap"),
                 "--sensor-truth", str(tmp_path / "missing" / "s.csv")])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.bvh"]
    # A file that was there before a failed run is not removed: it may be an earlier result.
    (tmp_path / "x.cap").write_bytes(b"earlier")
    with pytest.raises(CommandError):
        sc.main([str(clip), "--out", str(tmp_path / "x.cap"),
                 "--sensor-truth", str(tmp_path / "missing" / "s.csv")])
    assert (tmp_path / "x.cap").exists()
