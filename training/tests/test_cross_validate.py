"""training cv: subject folds, the inner validation, the per-fold runs and the report.

The folds must hold whole subjects, each once, with about equal motion; no fold's people may
reach its run's training or its checkpoint choice; a short run of the real trainer and evaluator
on procedural clips must give a finite score per fold and a report with the spread."""
import json

import numpy as np
import pytest

from training import cross_validate as cv, procedural, skeleton as sk
from training.errors import CommandError, UsageError
from training.train import TrainConfig


def _motion(subject, frames, name=None):
    return sk.Motion(name or f"{subject:02d}_{frames}", subject, 60.0, np.zeros((frames, 24, 3, 3), np.float32),
                     np.zeros((frames, 3), np.float32), sk.DEFAULT_OFFSETS.astype(np.float32))


def test_folds_hold_whole_subjects_once_with_about_equal_motion():
    rng = np.random.default_rng(0)
    motions = [_motion(int(s), int(rng.integers(100, 3000))) for s in rng.integers(1, 40, 200)]
    folds = cv.subject_folds(motions, 4)
    subjects = sorted({m.subject for m in motions})
    assert sorted(s for f in folds for s in f) == subjects
    frames = [sum(m.num_frames for m in motions if m.subject in f) for f in folds]
    largest_subject = max(sum(m.num_frames for m in motions if m.subject == s) for s in subjects)
    assert max(frames) - min(frames) <= largest_subject
    assert cv.subject_folds(list(reversed(motions)), 4) == folds   # the order of clips does not matter
    with pytest.raises(UsageError, match="cannot fill 5 folds"):
        cv.subject_folds([_motion(s, 100) for s in (1, 2, 3, 4)], 5)


def test_inner_validation_takes_whole_subjects_out_of_training():
    motions = [_motion(s, 100, f"{s}_{i}") for s in range(1, 21) for i in range(3)]
    fit, inner = cv.inner_validation(motions)
    held = {m.subject for m in inner}
    assert len(held) == 2 and not held & {m.subject for m in fit}
    assert len(fit) + len(inner) == len(motions)


def test_spread_of_fold_scores():
    s = cv.spread([1.0, 2.0, 3.0])
    assert s == {"mean": 2.0, "std": 1.0, "min": 1.0, "max": 3.0}


def test_recipe_options_leave_out_cvs_own():
    assert cv.recipe_options(["--folds", "3", "--size", "tiny", "--out=x", "--runs", "r",
                              "--budget-minutes", "5"]) == ["--size", "tiny", "--budget-minutes", "5"]


def test_data_options_and_clock_budgets_are_refused(capsys):
    for extra in (["--bvh", "x"], ["--init-from", "x.pt"], ["--smoke"], ["--resume"]):
        with pytest.raises(UsageError, match="recipe options only"):
            cv.main(["--folds", "2", "--steps", "10", *extra])
    for extra in ([], ["--budget-minutes", "5"], ["--steps", "10", "--budget-minutes", "5"]):
        with pytest.raises(UsageError, match="needs --steps N"):
            cv.main(["--folds", "2", *extra])


def test_a_short_cross_validation_trains_and_scores_every_fold(tmp_path):
    kinds = procedural.KINDS
    motions = []
    for subject in range(1, 7):
        for j in range(2):
            m = procedural.make_motion(kinds[(subject + j) % len(kinds)], seconds=12, seed=10 * subject + j,
                                       name=f"{subject:02d}_{j:02d}")
            motions.append(sk.Motion(m.name, subject, m.fps, m.local_rot, m.root_pos, m.offsets))
    cfg = TrainConfig(size="tiny", steps=3, batch=2, window=60, warmup=1, eval_every_s=1e9,
                      progress=False, device="cpu")
    result = cv.run_folds(motions, cfg, 3, tmp_path / "runs", progress=lambda *_: None)
    assert [r["fold"] for r in result["folds"]] == [1, 2, 3]
    assert sorted(s for r in result["folds"] for s in r["subjects"]) == list(range(1, 7))
    for r in result["folds"]:
        assert np.isfinite([r["angle_all"], r["pos"], r["drift_10s"]]).all(), r
        assert "travel_ratio" in r   # nan where no held-out window travels 0.5 m
        assert r["clips"] == 4 and r["steps"] == 3
        assert (tmp_path / "runs" / f"fold{r['fold']}" / "checkpoints" / r["checkpoint"]).is_file()
        log = json.loads((tmp_path / "runs" / f"fold{r['fold']}" / "results" / "train_log.json").read_text())
        assert f"cv fold {r['fold']} of 3" in json.dumps(log)
    s = result["summary"]["angle_all"]
    assert s["min"] <= s["mean"] <= s["max"] and s["std"] >= 0
    path = cv.write_report(tmp_path / "out", result, {"recipe": "--size tiny --steps 3", "command": "python3 -m training cv",
                                                      "clips": len(motions), "subjects": 6})
    text = path.read_text()
    assert "| **mean** |" in text and "spread: std (min - max)" in text
    assert json.loads((tmp_path / "out" / "cv.json").read_text())["folds"][0]["fold"] == 1


def test_missing_packs_are_named(tmp_path):
    (tmp_path / "train.mpack").write_bytes(b"")
    with pytest.raises(UsageError, match="val.mpack missing"):
        cv.main(["--packs", str(tmp_path), "--size", "tiny", "--steps", "10"])


def _procedural_people(subjects=6):
    kinds = procedural.KINDS
    motions = []
    for subject in range(1, subjects + 1):
        for j in range(2):
            m = procedural.make_motion(kinds[(subject + j) % len(kinds)], seconds=12, seed=10 * subject + j,
                                       name=f"{subject:02d}_{j:02d}")
            motions.append(sk.Motion(m.name, subject, m.fps, m.local_rot, m.root_pos, m.offsets))
    return motions


def test_folds_trained_at_once_score_as_folds_trained_in_turn(tmp_path):
    motions = _procedural_people()
    cfg = TrainConfig(size="tiny", steps=3, batch=2, window=60, warmup=1, eval_every_s=1e9,
                      progress=False, device="cpu")
    in_turn = cv.run_folds(motions, cfg, 3, tmp_path / "turn", progress=lambda *_: None)
    lines = []
    at_once = cv.run_folds(motions, cfg, 3, tmp_path / "once", progress=lines.append, jobs=3)
    assert [r["subjects"] for r in at_once["folds"]] == [r["subjects"] for r in in_turn["folds"]]
    for a, b in zip(at_once["folds"], in_turn["folds"]):
        for key in ("angle_all", "pos", "drift_10s", "travel_ratio"):
            assert a[key] == pytest.approx(b[key], rel=1e-5, nan_ok=True), (key, a, b)
        assert a["steps"] == b["steps"] == 3
    for n in (1, 2, 3):   # each fold's console went to its own log, its row to row.json
        assert "train:" in (tmp_path / "once" / f"fold{n}" / "console.log").read_text()
        assert json.loads((tmp_path / "once" / f"fold{n}" / "row.json").read_text())["fold"] == n
    assert sum("started" in line for line in lines) == 3


def test_a_fold_that_fails_beside_others_is_named_with_its_cause(tmp_path):
    motions = _procedural_people()
    bad = motions[0]   # subject 1: every fold that trains on it refuses its non-finite root
    bad.root_pos[5] = np.nan
    cfg = TrainConfig(size="tiny", steps=2, batch=2, window=60, warmup=1, eval_every_s=1e9,
                      progress=False, device="cpu")
    with pytest.raises(CommandError, match=r"of 3 folds failed") as e:
        cv.run_folds(motions, cfg, 3, tmp_path / "runs", progress=lambda *_: None, jobs=2)
    held_out_one = next(i + 1 for i, f in enumerate(cv.subject_folds(motions, 3)) if 1 in f)
    message = str(e.value)
    assert "3 of 3 folds failed" in message
    for n in (1, 2, 3):
        cause = ("results are not finite" if n == held_out_one   # it scores the damaged clip
                 else "training clip 01_00: its root_pos holds NaN")   # it trains on it
        assert f"fold {n}: " in message and cause in message.split(f"fold {n}: ")[1].split("; fold")[0]
        assert cause in (tmp_path / "runs" / f"fold{n}" / "console.log").read_text()


def _result(scores, subjects=((1, 2), (3, 4), (5, 6))):
    return {"folds": [{"fold": i + 1, "subjects": list(s), "angle_all": a, "pos": p, "drift_10s": d}
                      for i, (s, (a, p, d)) in enumerate(zip(subjects, scores))]}


def test_paired_differences_are_taken_fold_by_fold():
    a = _result([(10.0, 7.0, 0.30), (12.0, 8.0, 0.50), (11.0, 9.0, 0.20)])
    b = _result([(10.5, 7.0, 0.25), (12.25, 8.5, 0.40), (11.75, 8.0, 0.30)])
    d = cv.paired_differences(a, b)
    assert d["angle_all"]["per_fold"] == pytest.approx([-0.5, -0.25, -0.75])
    assert d["angle_all"]["mean"] == pytest.approx(-0.5) and d["angle_all"]["lower"] == 3
    assert d["pos"]["per_fold"] == pytest.approx([0.0, -0.5, 1.0]) and d["pos"]["lower"] == 1
    assert d["drift_10s"]["std"] == pytest.approx(np.std([0.05, 0.10, -0.10], ddof=1))
    # the spread between folds (1 deg) is far wider than the paired differences' (0.25 deg)
    assert cv.spread([r["angle_all"] for r in a["folds"]])["std"] > 3 * d["angle_all"]["std"]
    assert "travel_ratio" not in d   # runs without the travel ratio compare on the rest
    for r, t in zip(a["folds"] + b["folds"], (0.90, 0.95, 0.97, 0.93, 0.95, 0.96)):
        r["travel_ratio"] = t
    assert cv.paired_differences(a, b)["travel_ratio"]["per_fold"] == pytest.approx([-0.03, 0.0, 0.01])
    assert "| travel, predicted / true | -0.030 | +0.000 | +0.010 |" in cv.compare_report(a, b)
    with pytest.raises(UsageError, match="different folds"):
        cv.paired_differences(a, _result([(1, 1, 1)] * 3, subjects=((1, 3), (2, 4), (5, 6))))


def test_compare_prints_the_paired_table_without_training(tmp_path, capsys):
    (tmp_path / "a.json").write_text(json.dumps(_result([(10.0, 7.0, 0.3), (12.0, 8.0, 0.5), (11.0, 9.0, 0.2)])))
    (tmp_path / "b.json").write_text(json.dumps(_result([(10.5, 7.0, 0.25), (12.25, 8.5, 0.4), (11.75, 8.0, 0.3)])))
    assert cv.main(["--compare", str(tmp_path / "a.json"), str(tmp_path / "b.json")]) == 0
    out = capsys.readouterr().out
    assert "| angle (deg) | -0.50 | -0.25 | -0.75 | -0.50 | 0.25 | 3 of 3 |" in out
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(UsageError, match="not a cv.json"):
        cv.main(["--compare", str(tmp_path / "a.json"), str(tmp_path / "bad.json")])


def test_the_shown_command_names_no_folder_outside_the_repository():
    shown = cv.shown_command(["--runs", "/tmp/tmp.abc/runs", "--out=/root/out", "--packs", ".packs",
                              "--size", "medium", "--steps", "293"])
    assert "/tmp" not in shown and "/root" not in shown
    assert shown == ("python3 -m training cv --runs runs --out=out --packs .packs --size medium --steps 293")


def test_cv_on_gpu_script_dry_run_on_cpu(fixture_dir, tmp_path):
    """scripts/cv_on_gpu.sh with DEVICE=cpu: the probe fixes the steps from the pace and what is
    left of the time (none here: one step), or STEPS skips it; the report, and an archive of each
    fold's row, console, training log and evaluation, land in the output folder."""
    import os
    import subprocess
    import sys
    import tarfile
    from pathlib import Path
    from training import dataset as ds, motion_pack as mp
    d, _ = fixture_dir
    packs = tmp_path / "packs"
    for split in ("train", "val"):
        mp.write_pack(ds.list_clips(d, split), packs / f"{split}.mpack", workers=1, progress=False)
    script = Path(__file__).resolve().parents[2] / "scripts" / "cv_on_gpu.sh"
    recipe = ["--size", "tiny", "--batch", "2", "--window", "30"]
    env = dict(os.environ, DEVICE="cpu", PYTHON=sys.executable, FOLDS="2", PROBE_STEPS="2", WORKERS="1",
               EVAL_SECONDS="20", RESERVE_SECONDS="0")
    for extra, steps in (({}, 1), ({"STEPS": "2"}, 2)):
        out = tmp_path / f"out{steps}"
        r = subprocess.run(["bash", str(script), str(packs), str(out), "1", *recipe], env=dict(env, **extra),
                           capture_output=True, text=True, timeout=600)
        console = (out / "console.log").read_text()
        assert r.returncode == 0, console[-3000:] + r.stderr[-2000:]
        assert ("probe: 2 folds at once" in console) == (steps == 1)
        result = json.loads((out / "cv.json").read_text())
        assert [f["steps"] for f in result["folds"]] == [steps, steps]
        assert "--jobs 2" in result["meta"]["command"] and str(tmp_path) not in result["meta"]["command"]
        with tarfile.open(out / "folds.tar.gz") as tar:
            names = set(tar.getnames())
        for n in (1, 2):
            for f in ("row.json", "console.log", "results/train_log.json", "eval/evaluation.md"):
                assert f"fold{n}/{f}" in names, (f, names)
    bad = subprocess.run(["bash", str(script), str(packs)], env=env, capture_output=True, text=True)
    assert bad.returncode == 2 and "usage" in bad.stderr
