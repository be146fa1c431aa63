"""training cv: subject folds, the inner validation, the per-fold runs and the report.

The folds must hold whole subjects, each once, with about equal motion; no fold's people may
reach its run's training or its checkpoint choice; a short run of the real trainer and evaluator
on procedural clips must give a finite score per fold and a report with the spread."""
import json

import numpy as np
import pytest

from training import cross_validate as cv, procedural, skeleton as sk
from training.errors import UsageError
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
