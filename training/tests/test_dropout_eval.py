"""missing-sensor: the freeze / explode / recovery measures on series whose answer is known, a
broken condition caught by the per-condition scores, and one short run through mocapctl in which
the silence is exactly where it was put."""
import json
import math
import re
import subprocess

import numpy as np
import pytest

from training import dropout_eval as de
from training import ort, procedural
from training import skeleton as sk
from training.errors import UsageError

FPS = 60.0
needs_ort = pytest.mark.skipif(not ort.onnx_runtime_available(),
                               reason="ONNX Runtime not fetched (scripts/fetch_onnxruntime.sh)")


# ------------------------------------------------------------------------------ measures
def test_moving_average_is_centred_and_shrinks_at_the_ends():
    x = np.array([0.0, 0.0, 3.0, 0.0, 0.0, 6.0])
    np.testing.assert_allclose(de.moving_average(x, 3), [0.0, 1.0, 1.0, 1.0, 2.0, 3.0])
    np.testing.assert_allclose(de.moving_average(x, 1), x)
    assert de.longest_run([0, 1, 1, 0, 1, 1, 1, 0]) == 3 and de.longest_run([]) == 0


def test_a_pose_that_stops_while_the_truth_moves_is_a_freeze_of_about_that_length():
    truth = np.full(600, 1.0)                 # joints moving at 1 m/s for 10 s
    pred = truth.copy()
    pred[180:360] = 0.0                       # the pose stands still for 3 s
    frozen = de.longest_freeze(pred, truth, FPS, moving=0.1)
    # The 0.5 s averaging trims the edges: a quarter of a second at most on each side.
    assert 2.6 <= frozen <= 3.0, frozen
    assert de.longest_freeze(truth, truth, FPS, moving=0.1) == 0.0
    # Slow is not frozen; nor is standing still while the truth stands still.
    assert de.longest_freeze(np.full(600, 0.5), truth, FPS, moving=0.1) == 0.0
    assert de.longest_freeze(np.zeros(600), np.full(600, 0.05), FPS, moving=0.1) == 0.0
    # Only frames of the window count.
    window = np.zeros(600, bool)
    window[300:] = True
    assert 0.8 <= de.longest_freeze(pred, truth, FPS, moving=0.1, window=window) <= 1.0


def test_exploding_frames_are_nan_huge_joint_errors_and_root_jumps():
    T = 50
    angle = np.full((T, 24), 10.0)
    root = np.cumsum(np.full((T, 3), 0.01), axis=0)
    finite = np.ones(T, bool)
    assert not de.exploded_frames(angle, root, finite).any()
    angle[7, 13] = 95.0                       # one joint turned the wrong way
    angle[20, 3] = np.nan                     # a NaN angle
    finite[30] = False                        # a NaN pose
    root[40:, 0] += 0.6                       # the root jumps 0.6 m between frames 39 and 40
    assert set(np.nonzero(de.exploded_frames(angle, root, finite))[0]) == {7, 20, 30, 40}
    causes = de.explosion_causes(angle, root, finite)
    assert {c: list(np.nonzero(v)[0]) for c, v in causes.items()} == \
        {"pelvis": [], "joint": [7], "root": [40], "nan": [20, 30]}
    angle[12, 0] = 120.0                      # the pelvis facing the wrong way
    assert list(np.nonzero(de.explosion_causes(angle, root, finite)["pelvis"])[0]) == [12]
    root[40:, 0] -= 0.2                       # 0.4 m: a fast step, not an explosion
    assert set(np.nonzero(de.exploded_frames(angle, root, finite))[0]) == {7, 12, 20, 30}


def test_recovery_time_is_when_the_error_is_back_near_the_reference_and_stays():
    t = np.arange(1200) / FPS                 # 20 s, gap ends at 10 s
    ref = np.full_like(t, 10.0)
    gap_end, tau = 10.0, 0.5
    err = np.where(t < gap_end, 30.0, 10.0 + 20.0 * np.exp(-(t - gap_end) / tau))
    # 10 + 20 exp(-x / tau) <= 1.2 * 10 + slack 0.5 at x = tau ln(20 / 2.5)
    expect = tau * math.log(20.0 / 2.5)
    got = de.recovery_time(t, [err], [ref], [0.5], gap_end, FPS)
    assert abs(got - expect) < 0.1, (got, expect)
    assert de.recovery_time(t, [ref], [ref], [0.5], gap_end, FPS) == 0.0
    # Never back: inf. Back only for a moment (shorter than the hold): not yet recovered there.
    assert de.recovery_time(t, [np.full_like(t, 20.0)], [ref], [0.5], gap_end, FPS) == math.inf
    blip = np.where(t < 14.0, 20.0, 10.0)
    blip[(t >= 11.0) & (t < 11.5)] = 10.0
    got = de.recovery_time(t, [blip], [ref], [0.5], gap_end, FPS)
    assert 4.0 <= got <= 4.25, got   # back for good at 14 s, a few frames later once averaged
    # Every series must be back: a second one still off keeps it unrecovered.
    assert de.recovery_time(t, [ref, np.full_like(t, 20.0)], [ref, ref], [0.5, 0.3], gap_end,
                            FPS) == math.inf


# ------------------------------------------------------------------------------ a broken condition
def _run(motion, pred_local=None, pred_root=None, flags=None):
    T = motion.num_frames
    return de.Run(t=np.arange(T) / motion.fps, fps=motion.fps,
                  flags=np.zeros(T, np.int64) if flags is None else flags,
                  pred_local=motion.local_rot.astype(np.float64).copy() if pred_local is None else pred_local,
                  pred_root=motion.root_pos.astype(np.float64).copy() if pred_root is None else pred_root,
                  true_local=motion.local_rot.astype(np.float64), offsets=np.asarray(motion.offsets, np.float64),
                  finite=np.ones(T, bool), metrics={})


def _score(motion, run, ref_run, windows, bone=20):
    ref = (ref_run, de.frame_errors(ref_run))
    return de.score_condition(motion.name, "left_wrist", run, de.frame_errors(run), windows, ref=ref, bone=bone)


def test_the_scores_catch_a_frozen_an_exploding_and_a_never_recovering_pose():
    motion = procedural.make_motion("walk", 14.0, seed=4, name="walk")
    windows = de.Windows(5.0, 8.0)
    ref = _run(motion)
    fine = _score(motion, _run(motion), ref, windows)
    assert fine.freeze_body == 0.0 and fine.freeze_bone == 0.0 and fine.explode == 0
    assert fine.recovery == 0.0 and fine.same_before_gap == 0.0
    assert fine.angle["gap"] / fine.frames["gap"] < 0.01 and fine.bone < 0.01

    t = ref.t
    gap = (t >= 5.0) & (t < 8.0)
    frozen = motion.local_rot.astype(np.float64).copy()
    frozen[gap] = frozen[np.argmax(gap)]            # the whole pose held through the gap
    s = _score(motion, _run(motion, frozen), ref, windows)
    assert 2.5 <= s.freeze_body <= 3.1 and 2.5 <= s.freeze_bone <= 3.1, (s.freeze_body, s.freeze_bone)
    assert s.angle["gap"] / s.frames["gap"] > 5.0 and s.recovery < 0.3

    exploding = motion.local_rot.astype(np.float64).copy()
    exploding[gap, 18] = exploding[gap, 18] @ sk.rot_axis("z", np.pi)[None]   # elbow turned 180 deg
    root = motion.root_pos.astype(np.float64).copy()
    after_gap = int(np.nonzero(gap)[0][-1]) + 30
    root[after_gap:] += 1.0                                                   # and a 1 m jump after it
    s = _score(motion, _run(motion, exploding, root), ref, windows)
    assert s.explode == s.explode_extra == int(gap.sum()) + 1 and s.explode_elsewhere == 0
    assert s.explode_extra_causes == {"pelvis": 0, "joint": int(gap.sum()), "root": 1, "nan": 0}
    # Frames that explode with every sensor too are not new.
    s = _score(motion, _run(motion, exploding, root), _run(motion, exploding), windows)
    assert s.explode == int(gap.sum()) + 1 and s.explode_extra == 1

    drifting = motion.local_rot.astype(np.float64).copy()
    drifting[t >= 5.0, 13] = drifting[t >= 5.0, 13] @ sk.rot_axis("x", np.radians(60.0))[None]
    s = _score(motion, _run(motion, drifting), ref, windows)
    assert s.recovery == math.inf

    # The silence changed the poses before the gap: the check says by how much.
    early = motion.local_rot.astype(np.float64).copy()
    early[10, 4] = early[10, 4] @ sk.rot_axis("y", np.radians(2.0))
    assert _score(motion, _run(motion, early), ref, windows).same_before_gap == pytest.approx(2.0, abs=1e-3)


def test_a_pose_no_person_takes_is_broken_and_a_wrong_one_is_not():
    from training import pose_range
    motion = procedural.make_motion("arm_swing", 14.0, seed=3, name="swing")
    others = [procedural.make_motion(k, 14.0, seed=9) for k in ("walk", "squat")]
    limits = pose_range.build_pose_range([motion, *others], frame_step=1)
    windows = de.Windows(5.0, 8.0)
    t = np.arange(motion.num_frames) / motion.fps
    gap = (t >= 5.0) & (t < 8.0)
    ref = _run(motion)

    def score(run, reference=ref):
        return de.score_condition(motion.name, "left_wrist", run, de.frame_errors(run), windows,
                                  ref=(reference, de.frame_errors(reference)), bone=20,
                                  pose_range=limits)

    fine = score(_run(motion))
    assert fine.broken == fine.broken_extra == 0
    # Another motion's poses in the gap (a squat in the swing): far from the truth and in range;
    # only the cuts into and out of it snap too fast.
    other = motion.local_rot.astype(np.float64).copy()
    squat = others[1].local_rot.astype(np.float64)
    other[gap] = squat[np.nonzero(gap)[0]]
    s = score(_run(motion, other))
    assert s.angle["gap"] / s.frames["gap"] > 2.0
    assert s.broken_extra_causes == {"range": 0, "speed": 2, "root": 0, "nan": 0}
    # An elbow bent backwards through the gap: broken, out of range every frame, too fast where it
    # flips in and out, and the joint is named.
    bent = motion.local_rot.astype(np.float64).copy()
    bent[gap, 18] = bent[gap, 18] @ sk.rot_axis("y", np.radians(-120.0))[None]
    s = score(_run(motion, bent))
    assert s.broken == s.broken_extra == int(gap.sum()) + 1
    assert s.broken_extra_causes == {"range": int(gap.sum()), "speed": 2, "root": 0, "nan": 0}
    assert s.broken_extra_joints == {18: int(gap.sum()) + 1}
    assert s.broken_elsewhere == 0
    # Broken in the run with every sensor too: not new.
    s = score(_run(motion, bent), _run(motion, bent))
    assert s.broken == int(gap.sum()) + 1 and s.broken_extra == 0
    # Without a range of motion nothing is counted, and the summary says "not measured".
    plain = de.score_condition(motion.name, "left_wrist", _run(motion, bent),
                               de.frame_errors(_run(motion, bent)), windows,
                               ref=(ref, de.frame_errors(ref)), bone=20)
    assert plain.broken is None and de.summarize([plain])["left_wrist"]["broken"] is None


def test_flags_outside_the_gap_are_counted_beyond_the_reference_run():
    motion = procedural.make_motion("arm_swing", 12.0, seed=2)
    windows = de.Windows(4.0, 7.0)
    ref_flags = np.zeros(motion.num_frames, np.int64)
    ref_flags[-5:] = de.POSE_INCOMPLETE                   # the capture's last frames, both runs
    flags = ref_flags.copy()
    t = np.arange(motion.num_frames) / motion.fps
    flags[(t >= 4.0) & (t < 7.0)] |= de.POSE_INCOMPLETE
    ref = _run(motion, flags=ref_flags)
    s = _score(motion, _run(motion, flags=flags), ref, windows)
    assert s.incomplete_in_gap == s.frames["gap"] == 180 and s.incomplete_extra == 0
    flags[(t >= 7.0) & (t < 7.5)] |= de.POSE_INCOMPLETE   # a silence longer than asked
    s = _score(motion, _run(motion, flags=flags), ref, windows)
    assert s.incomplete_extra == 30


def test_clips_are_chosen_evenly_among_the_long_enough_and_cut():
    motions = [procedural.make_motion("walk", s, seed=i, name=f"c{i}")
               for i, s in enumerate([5, 21, 30, 22, 40, 19.9, 26])]
    chosen = de.choose_clips(motions, 3, clip_s=25.0, min_s=20.0)
    assert [m.name for m in chosen] == ["c1", "c3", "c6"]
    assert [m.num_frames for m in chosen] == [21 * 60, 22 * 60, 25 * 60]
    with pytest.raises(UsageError, match="no clip is 50 s or longer"):
        de.choose_clips(motions, 3, min_s=50.0)
    with pytest.raises(UsageError, match="too short"):
        de.gap_window(motions[0], 5.0)
    w = de.gap_window(chosen[2], 5.0)
    assert (w.gap_start, w.gap_end) == (1.0 + 10.0, 1.0 + 15.0)
    # A clip of 21.4667 s: the middle would start at 9.2333 s, between two sensor samples; the
    # gap starts on a tick of both the sensors (100 Hz) and the poses (60 Hz).
    odd = procedural.make_motion("walk", 1288 / 60.0, seed=1)
    w = de.gap_window(odd, 5.0)
    assert w.gap_start == pytest.approx(9.25) and w.gap_end == pytest.approx(14.25)
    # A frame on an edge belongs to the later window, whatever the last bit of either number.
    w = de.Windows(de.on_grid(9.95), de.on_grid(9.95) + 5.0)
    assert w.gap_start > 597 / 60.0                      # 9.950000000000001 against 9.95
    m = w.masks(np.arange(1200) / 60.0)
    assert np.nonzero(m["gap"])[0][[0, -1]].tolist() == [597, 896]
    assert not m["before"][597] and m["before"][596] and m["after"][897]


def test_bad_options_are_usage_errors(tmp_path):
    with pytest.raises(UsageError, match="no such file"):
        de.main(["--procedural", "--model", str(tmp_path / "none.onnx")])


def test_pose_limits_reach_the_replay_and_bad_ones_are_refused(capsys):
    plain = de.replay_command("mocapctl", "a.cap", "a.truth.csv", "m.onnx", "p.csv", "m.json")
    held = de.replay_command("mocapctl", "a.cap", "a.truth.csv", "m.onnx", "p.csv", "m.json",
                             rules=de.rule_options(pose_limits=25.0))
    assert "--pose-limits" not in plain and held == plain + ["--pose-limits", "25"]
    for bad in ("0.5", "91", "-1", "x"):
        with pytest.raises(SystemExit):
            de.add_arguments().parse_args(["--pose-limits", bad])
    assert "0 (off) or a tolerance" in capsys.readouterr().err
    assert de.add_arguments().parse_args(["--pose-limits", "25"]).pose_limits == 25.0
    assert de.add_arguments().parse_args([]).pose_limits == 0.0


def test_chest_following_reaches_the_replay_and_bad_shares_are_refused(capsys):
    plain = de.replay_command("mocapctl", "a.cap", "a.truth.csv", "m.onnx", "p.csv", "m.json")
    both = de.replay_command("mocapctl", "a.cap", "a.truth.csv", "m.onnx", "p.csv", "m.json",
                             rules=de.rule_options(pose_limits=25.0, chest_follow=0.5))
    assert both == plain + ["--pose-limits", "25", "--chest-follow", "0.5"]
    assert de.rule_options() == ()
    for bad in ("-0.1", "1.5", "x", "nan"):
        with pytest.raises(SystemExit):
            de.add_arguments().parse_args(["--chest-follow", bad])
    assert "a share from 0 (off) to 1" in capsys.readouterr().err
    args = de.add_arguments().parse_args(["--split", "val", "--chest-follow", "0.5", "--pose-limits", "25"])
    assert args.chest_follow == 0.5
    assert de._argv_of(args)[-4:] == ["--pose-limits", "25", "--chest-follow", "0.5"]


@needs_ort
def test_bad_segment_options_are_usage_errors():
    with pytest.raises(UsageError, match="chest is not a sensor of the capture"):
        de.main(["--procedural", "--segments", "chest"])
    with pytest.raises(UsageError, match="mocap_pose_int8.onnx does not read chest"):
        de.main(["--procedural", "--sensors", "pelvis,left_wrist,right_wrist,left_shin,right_shin,head,chest"])
    with pytest.raises(UsageError, match="mocap_pose_int8.onnx needs head"):
        de.main(["--procedural", "--sensors", "pelvis,left_wrist,right_wrist,left_shin,right_shin"])
    with pytest.raises(UsageError, match="--sensors: unknown segment"):
        de.main(["--procedural", "--sensors", "pelvis,tail"])
    with pytest.raises(UsageError, match="leaves no room"):
        de.main(["--procedural", "--clip-seconds", "6", "--seconds", "5"])


# ------------------------------------------------------------------------------ through mocapctl
@needs_ort
def test_a_short_run_through_mocapctl_has_the_gap_where_it_was_put(tmp_path):
    """One procedural clip, the right wrist silent for 2 s: the report, and in the replayed
    frames the sensor held exactly in the gap, the poses flagged incomplete exactly there, the
    poses before the gap those of the run without it, and this module's angle error equal to
    mocapctl's own."""
    out, keep = tmp_path / "report.md", tmp_path / "keep"
    # A range of motion the test makes: the procedural motions', with the right elbow allowed
    # only straight, which the model's bent elbow leaves on every frame of both runs.
    from training import pose_range
    limits = pose_range.build_pose_range(de.procedural_clips(5, 10.0, 7), source="test motions")
    limits.covers[19] = np.array([[1.0, 0.0, 0.0, 0.0]])   # the right elbow: only straight
    saved = limits.save(tmp_path / "range.npz")
    assert de.main(["--procedural", "--clips", "1", "--clip-seconds", "10", "--seconds", "2",
                    "--segments", "right_wrist", "--out", str(out), "--keep", str(keep),
                    "--pose-range", str(saved)]) == 0
    text = out.read_text()
    assert "python3 -m training missing-sensor --procedural --clips 1 --clip-seconds 10 --seconds 2" in text
    assert "Range of motion (`python3 -m training pose-range`): test motions." in text
    # the default model (contract 3, no masked features) gets stand-ins for a silent sensor
    assert "(contract 3) reads no mask" in text and "as the model posed it" in text
    assert "turned about the vertical by the shins' mean heading change" in text
    assert re.search(r"^\| none \| [\d.]+ \|", text, re.M), text
    row = re.search(r"^\| right_wrist \| ([\d.]+) \| .*\| (\d+) \((\d+)\) \| ([\d.]+|never) / ", text, re.M)
    assert row, text
    assert int(row.group(2)) == 0 and row.group(4) != "never"   # nothing far off; it recovered
    # the bent right elbow breaks every frame of both runs, so none is new; the counts are there
    broken = re.search(r"^\| right_wrist \| (\d+) \| (\d+) \| (\d+) \| (\d+) \| 0 \| 0 \| .* \| (\d+) \|$",
                       text, re.M)
    assert broken, text
    assert int(broken.group(1)) == 120 + 120 and int(broken.group(2)) == 0, broken.group(0)
    assert re.search(r"^\| right_wrist \| 120 of 120 \| 0 \| 0\.000 \|", text, re.M), text

    clip_dir = next(keep.iterdir())
    silent = next(clip_dir.glob("*-right_wrist.cap"))
    gap = de.gap_window(de.procedural_clips(1, 10.0, 0)[0], 2.0)
    assert (gap.gap_start, gap.gap_end) == (5.0, 7.0)   # 1 s lead-in + (10 - 2) / 2
    truth = np.load(silent.with_suffix(".truth.npz"))
    assert list(truth["silences"]) == ["right_wrist@5.0+2.0"]
    t0 = float(truth["t_session_start"])

    # The sensor frames (no model): the right wrist held exactly in the gap, nobody else.
    frames_csv = tmp_path / "frames.csv"
    r = subprocess.run([str(ort.mocapctl_path(require_onnx=False)), "replay", str(silent), "--csv",
                        str(frames_csv)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    header = frames_csv.read_text().splitlines()[0].split(",")
    a = np.loadtxt(frames_csv, delimiter=",", skiprows=1)
    t = a[:, header.index("time_s")] - t0
    held = {seg: (a[:, header.index(f"{seg}_flags")].astype(int) & 2) != 0
            for seg in ("pelvis", "left_wrist", "right_wrist", "left_shin", "right_shin", "head")}
    near = (t > gap.gap_start - 1.0) & (t < gap.gap_end + 1.0)
    in_gap = (t > gap.gap_start - 1e-6) & (t < gap.gap_end - 1e-6)
    np.testing.assert_array_equal(held["right_wrist"][near], in_gap[near])
    assert held["right_wrist"][near].sum() == 120
    for seg, h in held.items():
        if seg != "right_wrist":
            assert not h[near].any(), seg

    # The poses through the model: incomplete exactly in the gap (and where the run without
    # the silence has them too: the capture's end).
    def incomplete_times(cond):
        time_s, flags, _, _ = de.read_pose_csv(next(clip_dir.glob(f"*-{cond}.poses.csv")))
        return set(np.round(time_s[(flags & de.POSE_INCOMPLETE) != 0] - t0, 4))
    extra = incomplete_times("right_wrist") - incomplete_times("none")
    assert len(extra) == 120 and min(extra) >= gap.gap_start - 1e-6 and max(extra) < gap.gap_end

    # This module's figures are mocapctl's: the whole replay's mean angle error agrees.
    for cond in ("none", "right_wrist"):
        stem = next(clip_dir.glob(f"*-{cond}.cap")).with_suffix("")
        run = de.align_to_truth(*de.read_pose_csv(stem.with_suffix(".poses.csv")),
                                np.load(stem.with_suffix(".truth.npz")),
                                json.loads(stem.with_suffix(".metrics.json").read_text()))
        err = de.frame_errors(run)
        assert np.nanmean(err.angle) == pytest.approx(run.metrics["angle_error_deg"], abs=0.01)
        assert len(run.t) == run.metrics["poses"]


@needs_ort
def test_a_contract_two_model_runs_on_seven_sensors_and_on_six_without_its_optional_chest(tmp_path):
    """A masked model with an optional chest: the chest silenced in a 7-sensor capture, and the
    right wrist in a capture of the six (the chest absent throughout); the replays carry the
    capture's sensors and the gaps are where they were put."""
    from training import export, sensors as se
    from training.model import ModelConfig
    seven = se.DEFAULT_SENSORS + ("chest",)
    cfg = ModelConfig(32, 32, 1, 32, anchored=True, sensors=seven, optional=("chest",), masked=True)
    export.export(export.untrained_model(seed=0, config=cfg), tmp_path / "m", check=False)
    model = tmp_path / "m" / export.FP32_NAME
    assert de.model_info(model) == (2, seven, ("chest",))
    assert de.session_sensors_argument(seven) == \
        "pelvis=0,left_wrist=1,right_wrist=2,left_shin=3,right_shin=4,head=5,chest=6"
    common = ["--procedural", "--pose-range", "none", "--clips", "1", "--clip-seconds", "10", "--seconds", "2", "--model", str(model)]
    out7, keep7 = tmp_path / "seven.md", tmp_path / "k7"
    assert de.main(common + ["--segments", "chest", "--out", str(out7), "--keep", str(keep7)]) == 0
    text = out7.read_text()
    assert re.search(r"^\| chest \| [\d.]+ \|", text, re.M), text
    assert "--sensors" not in text.split("Made by:")[1].split("\n\n")[1]
    assert "contract 2" in text and "reads the mask" in text and "marked present" in text
    truth = np.load(next(next(keep7.iterdir()).glob("*-chest.cap")).with_suffix(".truth.npz"))
    assert list(truth["sensors"]) == list(seven) and list(truth["silences"]) == ["chest@5.0+2.0"]

    out6 = tmp_path / "six.md"
    six = ",".join(se.DEFAULT_SENSORS)
    assert de.main(common + ["--sensors", six, "--segments", "right_wrist", "--out", str(out6)]) == 0
    text = out6.read_text()
    assert f"--sensors {six}" in text and "the model's chest is absent throughout (masked)" in text
    assert re.search(r"^\| right_wrist \| [\d.]+ \|", text, re.M), text
    assert re.search(r"^\| right_wrist \| 120 of 120 \| 0 \| 0\.000 \|", text, re.M), text
    with pytest.raises(UsageError, match="is not a sensor of the capture"):
        de.main(common + ["--sensors", six, "--segments", "chest"])
