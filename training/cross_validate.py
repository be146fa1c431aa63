"""cv: a training recipe scored by cross-validation over subject folds.

    python3 -m training cv --steps N [--folds 4] [--jobs J] [--out training/results/cv] [--runs DIR]
        [--packs DIR] [--eval-max-seconds S] [train options: --size, --seed, --lr, augmentation ...]
    python3 -m training cv --compare A/cv.json B/cv.json

One validation set of a few subjects is a noisy judge: choosing among runs by it fits those
people (twelve fine-tunes once moved error between the validation subjects without closing the
gap to unseen ones). Here the people of the train and validation splits are dealt into K folds
of about equal motion (whole subjects, never split); the recipe given by the train options is
trained K times, each time on K - 1 folds, and scored on the fold it never saw. The test split
takes no part. The report gives each fold's joint angle error, position error and 10 s root drift
(`evaluate`'s definitions, realistic sensor noise, the mirror-averaged network as exported), their
mean and the spread between folds (standard deviation, lowest and highest). Most of that spread
is the people (the same folds rank alike under different recipes), so two recipes run over the
same folds compare fold by fold (--compare): the spread of the paired differences is the noise.

Inside each run the trainer keeps the checkpoint that scores best on an inner validation set
(every 10th subject of its own training folds, held out of its training), so the fold it is
judged on plays no part in any choice. Runs go to --runs (default training/data/cv/), one folder
per fold with its checkpoints and training log; OUT/cv.md and OUT/cv.json hold the result.

Every train option that describes the recipe is taken (size, steps, seed, augmentation, sensors,
loss weights); every fold trains the same --steps, never to a wall-clock budget (a fold trained
while the machine is busy would get fewer steps). The data options are not taken (--bvh, --val-bvh, --max-clips, --smoke: the
folds are the data), nor --init-from (weights that have seen a fold's people would score it)
or --resume.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from .cli import POSITIVE_INT, number_type
from .errors import CommandError, UsageError

REPO = Path(__file__).resolve().parent.parent
DEFAULT_OUT = REPO / "training" / "results" / "cv"
DEFAULT_RUNS = REPO / "training" / "data" / "cv"
# travel_ratio: the median of predicted / true horizontal distance over 10 s windows (evaluate's);
# measured on people the run never saw, it is the speed a network shrinks to on new people, which
# no validation figure can set without fitting its subjects
METRICS = (("angle_all", "angle (deg)", 2), ("pos", "position (cm)", 2), ("drift_10s", "drift 10 s (m)", 3),
           ("travel_ratio", "travel, predicted / true", 3))


def _cell(value, digits: int) -> str:
    return "-" if value is None or not math.isfinite(float(value)) else f"{float(value):.{digits}f}"


def _fold_line(row) -> str:
    """A scored fold's console line."""
    return f"cv: fold {row['fold']}: " + "  ".join(f"{label} {_cell(row.get(key), d)}" for key, label, d in METRICS)


def _summary(rows) -> dict:
    """Mean and spread per metric over the folds (metrics that every row has)."""
    return {key: spread([r[key] for r in rows]) for key, _, _ in METRICS if all(key in r for r in rows)}
REFUSED = (("bvh", "--bvh"), ("val_bvh", "--val-bvh"), ("max_clips", "--max-clips"),
           ("smoke", "--smoke"), ("init_from", "--init-from"), ("resume", "--resume"),
           ("ckpt_dir", "--ckpt-dir"), ("results_dir", "--results-dir"))
# Every fold gets the same training: a wall-clock budget gives a fold trained while the machine
# is busy fewer steps (a first run here trained one fold 562 steps and the others ~1,450), and
# its score then says more about the load than about its people.
NO_CLOCK_BUDGET = 1e9


def subject_folds(motions, k: int) -> list:
    """Subjects dealt into k folds of about equal frames: the largest subject first, each to the
    fold with the fewest frames so far (ties: the lower fold). Deterministic. Returns k sorted
    lists of subject numbers."""
    frames = {}
    for m in motions:
        frames[int(m.subject)] = frames.get(int(m.subject), 0) + int(m.num_frames)
    if len(frames) < k:
        raise UsageError(f"{len(frames)} subjects cannot fill {k} folds")
    folds = [[] for _ in range(k)]
    load = [0] * k
    for subject in sorted(frames, key=lambda s: (-frames[s], s)):
        i = min(range(k), key=lambda j: (load[j], j))
        folds[i].append(subject)
        load[i] += frames[subject]
    return [sorted(f) for f in folds]


def inner_validation(motions) -> tuple:
    """(training motions, inner validation motions): every 10th subject of the training folds,
    in number order (at least one, never all)."""
    from .train import _spread
    subjects = sorted({int(m.subject) for m in motions})
    held = {subjects[i] for i in _spread(len(subjects), 0.1)}
    return ([m for m in motions if int(m.subject) not in held],
            [m for m in motions if int(m.subject) in held])


def spread(values) -> dict:
    v = np.asarray(values, np.float64)
    return {"mean": float(v.mean()), "std": float(v.std(ddof=1)) if len(v) > 1 else 0.0,
            "min": float(v.min()), "max": float(v.max())}


def score_fold(i: int, folds, motions, cfg, runs_dir: Path, eval_max_seconds=None, progress=print) -> dict:
    """Trains cfg's recipe on every fold but fold i (0-based) and scores it on fold i's people.
    The row is also written to RUNS/foldN/row.json, so folds trained at once (or a run cut short)
    leave what they measured."""
    from .evaluate import evaluate
    from .train import pick_device, train
    k = len(folds)
    held = folds[i]
    held_set = set(held)
    test_motions = [m for m in motions if int(m.subject) in held_set]
    fit_motions, inner = inner_validation([m for m in motions if int(m.subject) not in held_set])
    fold_dir = Path(runs_dir) / f"fold{i + 1}"
    fold_cfg = replace(cfg, ckpt_dir=str(fold_dir / "checkpoints"), results_dir=str(fold_dir / "results"),
                       train_source=f"cv fold {i + 1} of {k}: the other folds",
                       val_source=f"cv fold {i + 1} of {k}: inner validation subjects")
    progress(f"cv: fold {i + 1}/{k}: training on {len(fit_motions)} clips "
             f"({len(inner)} inner validation), held out subjects {', '.join(map(str, held))}")
    t0 = time.monotonic()
    trained = train(fold_cfg, motions=fit_motions, val_motions=inner)
    train_minutes = (time.monotonic() - t0) / 60.0
    ckpt = fold_dir / "checkpoints" / "best.pt"
    if not ckpt.is_file():
        ckpt = fold_dir / "checkpoints" / "last.pt"
    scored = test_motions
    if eval_max_seconds:
        from .evaluate import _trim
        scored = _trim(test_motions, None, eval_max_seconds)
    r = evaluate(scored, models=(), checkpoint=str(ckpt), out_dir=fold_dir / "eval", latency=False,
                 source=f"fold {i + 1} (subjects {', '.join(map(str, held))})", progress=False,
                 torch_device=str(pick_device(cfg.device)))
    s = r["results"]["PyTorch fp32"]
    row = {"fold": i + 1, "subjects": held, "clips": len(test_motions),
           "minutes": sum(m.num_frames / m.fps for m in test_motions) / 60.0,
           "checkpoint": ckpt.name, "steps": int(trained.get("steps", 0)),
           **{key: float(s[key]) for key, _, _ in METRICS},
           "train_minutes": train_minutes}
    tmp = fold_dir / "row.json.tmp"
    tmp.write_text(json.dumps(row, indent=1))
    os.replace(tmp, fold_dir / "row.json")
    progress(_fold_line(row))
    return row


def _fold_process(i, folds, motions, cfg, runs_dir, eval_max_seconds) -> None:
    """Body of a fold trained beside others: its console goes to RUNS/foldN/console.log."""
    log_path = Path(runs_dir) / f"fold{i + 1}" / "console.log"
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with open(log_path, "w", buffering=1) as log:
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        import sys
        sys.stdout = sys.stderr = log
        try:
            score_fold(i, folds, motions, cfg, runs_dir, eval_max_seconds)
        except BaseException as e:   # the parent reads the cause from the log
            import traceback
            traceback.print_exc()
            log.flush()
            os._exit(3 if isinstance(e, (UsageError, CommandError)) else 1)
    os._exit(0)


def run_folds(motions, cfg, k: int, runs_dir: Path, eval_max_seconds=None, progress=print,
              jobs: int = 1) -> dict:
    """Trains cfg's recipe once per fold and scores each run on its held-out fold; jobs > 1 trains
    that many folds at once, each in a process of its own (a GPU that one run leaves half idle,
    or cores to spare: give each fold its own --data-workers)."""
    folds = subject_folds(motions, k)
    runs_dir = Path(runs_dir)
    if jobs <= 1:
        rows = [score_fold(i, folds, motions, cfg, runs_dir, eval_max_seconds, progress) for i in range(k)]
        return {"folds": rows, "summary": _summary(rows)}
    import multiprocessing
    import multiprocessing.connection
    # fork: the children share the loaded motions without copying them; the parent has touched
    # no GPU, so each child starts its own CUDA context
    ctx = multiprocessing.get_context("fork")
    pending, running, failed = list(range(k)), {}, []
    for i in range(k):
        stale = runs_dir / f"fold{i + 1}" / "row.json"
        if stale.exists():
            stale.unlink()
    while pending or running:
        while pending and len(running) < jobs:
            i = pending.pop(0)
            proc = ctx.Process(target=_fold_process, args=(i, folds, motions, cfg, runs_dir, eval_max_seconds))
            proc.start()
            running[i] = proc
            progress(f"cv: fold {i + 1}/{k} started (held out subjects {', '.join(map(str, folds[i]))}); "
                     f"its console: {runs_dir / f'fold{i + 1}' / 'console.log'}")
        multiprocessing.connection.wait([p.sentinel for p in running.values()])
        for i, proc in list(running.items()):
            if proc.exitcode is None:
                continue
            del running[i]
            row_path = runs_dir / f"fold{i + 1}" / "row.json"
            if proc.exitcode != 0 or not row_path.is_file():
                failed.append(i + 1)
                progress(f"cv: fold {i + 1} FAILED (exit {proc.exitcode}); see its console.log")
                continue
            row = json.loads(row_path.read_text())
            progress(_fold_line(row))
    if failed:
        tails = []
        for n in sorted(failed):
            log = runs_dir / f"fold{n}" / "console.log"
            lines = log.read_text(errors="replace").strip().splitlines() if log.is_file() else []
            tails.append(f"fold {n}: {lines[-1] if lines else 'no output'} ({log})")
        raise CommandError(f"{len(failed)} of {k} folds failed (a fold that finished left its row in "
                           f"{runs_dir}/foldN/row.json): "
                           + "; ".join(tails))
    rows = [json.loads((runs_dir / f"fold{i + 1}" / "row.json").read_text()) for i in range(k)]
    return {"folds": rows, "summary": _summary(rows)}


def write_report(out_dir: Path, result: dict, meta: dict) -> Path:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    lines = [f"# Cross-validation over subject folds: {meta['recipe']}", "",
             f"{meta['clips']} clips of {meta['subjects']} subjects (the train and validation splits; the "
             f"test split takes no part) in {len(result['folds'])} folds of whole subjects. Each row: the "
             "recipe trained on the other folds (the checkpoint best on an inner validation set of "
             "every 10th of its own subjects), scored on the fold's people, realistic sensor noise, "
             "mirror-averaged network"
             + (f", the first {meta['eval_max_seconds']} s of each clip" if meta.get("eval_max_seconds") else "")
             + ". Made by:", "", f"    {meta['command']}", "",
             "| fold | subjects | clips | minutes | steps trained | " + " | ".join(label for _, label, _ in METRICS) + " |",
             "|---|---|---|---|---|" + "---|" * len(METRICS)]
    for r in result["folds"]:
        lines.append(f"| {r['fold']} | {', '.join(map(str, r['subjects']))} | {r['clips']} | {r['minutes']:.0f} | "
                     f"{r.get('steps', '-')} | " + " | ".join(_cell(r.get(key), d) for key, _, d in METRICS) + " |")
    s = result["summary"]
    lines.append("| **mean** | | | | | " + " | ".join(f"**{_cell(s[key]['mean'], d)}**" if key in s else "-"
                                                      for key, _, d in METRICS) + " |")
    lines.append("| spread: std (min - max) | | | | | " + " | ".join(
        f"{_cell(s[key]['std'], d)} ({_cell(s[key]['min'], d)} - {_cell(s[key]['max'], d)})" if key in s else "-"
        for key, _, d in METRICS) + " |")
    jobs = meta.get("jobs") or 1
    lines += ["", f"Training took {sum(r['train_minutes'] for r in result['folds']):.0f} min in all "
              f"({meta.get('device', 'this machine')}"
              + (f"; {jobs} folds at once, so about {max(r['train_minutes'] for r in result['folds']):.0f} "
                 "min of wall clock" if jobs > 1 else "") + "). "
              "The spread between folds is mostly the people in them (folds rank alike under different "
              "recipes): compare two recipes fold by fold (`cv --compare A/cv.json B/cv.json`), where "
              "the noise is the spread of the paired differences.", ""]
    path = out_dir / "cv.md"
    path.write_text("\n".join(lines))
    (out_dir / "cv.json").write_text(json.dumps({"meta": meta, **result}, indent=1))
    return path


def add_arguments(p):
    from .train import add_arguments as train_arguments
    p.add_argument("--folds", type=number_type(int, lambda v: 2 <= v <= 20, "a whole number from 2 to 20"),
                   default=4, help="folds of whole subjects (default 4)")
    p.add_argument("--out", default=str(DEFAULT_OUT), help="report folder (default training/results/cv)")
    p.add_argument("--runs", default=str(DEFAULT_RUNS), help="one training run per fold in here "
                   "(default training/data/cv)")
    p.add_argument("--packs", default=None, help="read the people from PACKS/train.mpack and "
                   "PACKS/val.mpack (training pack) instead of the CMU cache: a GPU machine without the data")
    p.add_argument("--compare", nargs=2, metavar=("A.json", "B.json"), default=None,
                   help="no training: A minus B fold by fold, two cv.json of the same folds")
    p.add_argument("--jobs", type=POSITIVE_INT, default=1,
                   help="folds trained at once, each in its own process (default 1)")
    p.add_argument("--eval-max-seconds", dest="eval_max_seconds", type=POSITIVE_INT, default=None,
                   help="score only the first S seconds of each held-out clip (faster)")
    train_arguments(p)
    return p


def recipe_options(argv) -> list:
    """The train options of a cv command line (its own options taken out)."""
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
            continue
        name = a.split("=", 1)[0]
        if name in ("--folds", "--out", "--runs", "--packs", "--eval-max-seconds", "--jobs", "--compare"):
            skip = "=" not in a
            continue
        out.append(a)
    return out


PATH_OPTIONS = ("--runs", "--out", "--packs")


def shown_command(argv) -> str:
    """The cv command line as a committed report shows it: folder options repository-relative
    where they can be, else their last component (a lease's temporary folders name no machine)."""
    from .evaluate import _shown_path
    out, path_next = [], False
    for a in argv:
        name, eq, value = a.partition("=")
        if path_next:
            a, path_next = _shown_path(a), False
        elif name in PATH_OPTIONS:
            if eq:
                a = f"{name}={_shown_path(value)}"
            else:
                path_next = True
        out.append(a)
    return "python3 -m training cv " + " ".join(shlex.quote(a) for a in out)


def paired_differences(result: dict, baseline: dict) -> dict:
    """Fold by fold, result minus baseline (two cv.json of the same folds). Most of the spread
    between folds is the people in them (the same folds rank alike under different recipes), so
    a difference measured on the same folds is far less noisy than the spread."""
    a, b = result["folds"], baseline["folds"]
    if [r["subjects"] for r in a] != [r["subjects"] for r in b]:
        raise UsageError("the two cross-validations hold different folds (another --folds or other "
                         "people); only runs over the same folds compare fold by fold")
    out = {}
    for key, _, _ in METRICS:
        if not all(key in r for r in a + b):   # a metric one of the runs predates
            continue
        d = [float(x[key]) - float(y[key]) for x, y in zip(a, b)]
        out[key] = {"per_fold": d, **spread(d), "lower": sum(v < 0 for v in d)}
    return out


def compare_report(result: dict, baseline: dict, names=("A", "B")) -> str:
    """A markdown table of paired_differences."""
    diff = paired_differences(result, baseline)
    k = len(result["folds"])
    lines = [f"{names[0]} minus {names[1]}, fold by fold (for the errors, negative: {names[0]} is better; "
             "the travel ratio is best at 1):", "",
             "| | " + " | ".join(f"fold {r['fold']}" for r in result["folds"]) + " | mean | std | folds lower |",
             "|---|" + "---|" * (k + 3)]
    for key, label, d in METRICS:
        if key not in diff:
            continue
        v = diff[key]
        lines.append(f"| {label} | " + " | ".join(f"{x:+.{d}f}" for x in v["per_fold"])
                     + f" | {v['mean']:+.{d}f} | {v['std']:.{d}f} | {v['lower']} of {k} |")
    return "\n".join(lines)


def compare_main(paths) -> int:
    runs = []
    for path in paths:
        try:
            runs.append(json.loads(Path(path).read_text()))
        except (OSError, ValueError) as e:
            raise UsageError(f"--compare {path}: not a cv.json ({e})") from e
        if not isinstance(runs[-1], dict) or not runs[-1].get("folds"):
            raise UsageError(f"--compare {path}: not a cv.json (no folds)")
    print(compare_report(runs[0], runs[1], tuple(str(p) for p in paths)))
    return 0


def main(args=None) -> int:
    import sys
    argv = list(args) if isinstance(args, list) else sys.argv[2:]
    if args is None or isinstance(args, list):
        args = add_arguments(argparse.ArgumentParser(prog="python3 -m training cv")).parse_args(argv)
    if getattr(args, "compare", None):
        return compare_main(args.compare)
    given = [option for attr, option in REFUSED if getattr(args, attr, None) not in (None, False)]
    if given:
        raise UsageError(f"{' '.join(given)}: cv trains on folds of the train and validation people "
                         "and writes its runs under --runs; it takes recipe options only")
    if getattr(args, "budget_minutes", None) is not None or getattr(args, "steps", None) is None:
        raise UsageError("cv needs --steps N (the same training for every fold) and no --budget-minutes: "
                         "a wall-clock budget trains a fold run on a busy machine for fewer steps")
    from . import dataset
    from .train import config_from_args
    cfg = config_from_args(args)
    cfg.budget_minutes = NO_CLOCK_BUDGET
    if args.packs:
        packs = [Path(args.packs) / f"{split}.mpack" for split in ("train", "val")]
        missing = [str(p) for p in packs if not p.is_file()]
        if missing:
            raise UsageError(f"--packs {args.packs}: {', '.join(missing)} missing (python3 -m training "
                             "pack --split train|val --out ...)")
        motions = dataset.load_motions(packs[0]) + dataset.load_motions(packs[1])
    else:
        motions = dataset.load_motions("train") + dataset.load_motions("val")
    recipe = " ".join(shlex.quote(a) for a in recipe_options(argv)) or "the default recipe"
    command = shown_command(argv)
    print(f"cv: {len(motions)} clips, {len({int(m.subject) for m in motions})} subjects, "
          f"{args.folds} folds; recipe: {recipe}")
    result = run_folds(motions, cfg, args.folds, Path(args.runs), args.eval_max_seconds,
                       jobs=args.jobs)
    meta = {"recipe": recipe, "command": command, "clips": len(motions),
            "eval_max_seconds": args.eval_max_seconds, "jobs": args.jobs,
            "subjects": len({int(m.subject) for m in motions}), "device": cfg.device or "auto"}
    path = write_report(Path(args.out), result, meta)
    s = result["summary"]
    print("cv: " + "  ".join(f"{label} {_cell(s[key]['mean'], d)} +- {_cell(s[key]['std'], d)}"
                             for key, label, d in METRICS if key in s) + f"; report {path}")
    # drift has no value where no held-out clip lasts 10 s; a pose error that is not finite is a
    # broken run
    return 0 if all(math.isfinite(s[key]["mean"]) for key in ("angle_all", "pos")) else 1
