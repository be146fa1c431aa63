"""python3 -m training (training.__main__.main): bad input is one line `training <command>:
<message>` with exit status 1, never a traceback; real bugs keep their traceback."""
import pytest
import torch

from training import bvh, ort, procedural
from training.__main__ import main


def _run(capsys, *argv):
    capsys.readouterr()
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err.strip()
    return code, err


def _fails(capsys, command, *rest, says):
    code, err = _run(capsys, command, *rest)
    assert code == 1, err
    last = err.splitlines()[-1] if err else ""   # (progress bars may come before it)
    assert last.startswith(f"training {command}: ") and "Traceback" not in err, err
    assert says in last, err
    return last


@pytest.fixture
def files(tmp_path):
    """An empty folder, a folder with one short BVH clip, a BVH without frames, a text file."""
    (tmp_path / "empty").mkdir()
    clips = tmp_path / "clips"
    clips.mkdir()
    bvh.write_bvh(clips / "walk.bvh", procedural.motion_to_daz(procedural.make_motion("walk", 1.0, seed=1)))
    text = (clips / "walk.bvh").read_text()
    (tmp_path / "zero.bvh").write_text(text[:text.index("MOTION")] + "MOTION\nFrames: 0\nFrame Time: 0.0416667\n")
    (tmp_path / "notes.txt").write_text("not a checkpoint\n")
    torch.save({"anything": torch.ones(2)}, tmp_path / "other.pt")
    return tmp_path


def test_evaluate_rejects_bad_folders_splits_checkpoints_and_models(files, capsys):
    t = files
    common = ["--no-latency", "--no-cache", "--out", t / "res"]
    _fails(capsys, "evaluate", "--bvh", t / "missing", *common, says=f"--bvh {t / 'missing'}: no such folder")
    _fails(capsys, "evaluate", "--bvh", t / "empty", *common, says=f"--bvh {t / 'empty'}: no BVH clips")
    with pytest.raises(SystemExit) as e:
        main(["evaluate", "--split", "vall"])
    assert e.value.code == 2 and "invalid choice: 'vall'" in capsys.readouterr().err
    _fails(capsys, "evaluate", "--bvh", t / "clips", "--checkpoint", t / "nope.pt", *common,
           says=f"--checkpoint {t / 'nope.pt'}: no such file")
    _fails(capsys, "evaluate", "--bvh", t / "clips", "--checkpoint", t / "notes.txt", *common,
           says=f"{t / 'notes.txt'} is not a PyTorch checkpoint")
    _fails(capsys, "evaluate", "--bvh", t / "clips", "--checkpoint", t / "other.pt", *common,
           says=f"{t / 'other.pt'} does not hold the weights of its pose network")
    _fails(capsys, "evaluate", "--bvh", t / "clips", "--no-torch", "--models", t / "gone.onnx", *common,
           says=f"--models {t / 'gone.onnx'}: no such file")
    assert not (t / "res").exists()


def test_evaluate_reports_a_model_onnx_runtime_refuses(files, capsys):
    if not ort.onnx_runtime_available():
        pytest.skip("ONNX Runtime not available (scripts/fetch_onnxruntime.sh)")
    (files / "bad.onnx").write_text("not a model\n")
    _fails(capsys, "evaluate", "--bvh", files / "clips", "--no-torch", "--models", files / "bad.onnx",
           "--no-latency", "--no-cache", "--out", files / "res", says="bad.onnx")


def test_train_rejects_empty_folders_and_bad_init_weights(files, capsys):
    t = files
    dirs = ["--ckpt-dir", t / "ck", "--results-dir", t / "res"]
    _fails(capsys, "train", "--bvh", t / "empty", *dirs, says=f"--bvh {t / 'empty'}: no BVH clips")
    _fails(capsys, "train", "--bvh", t / "clips", "--val-bvh", t / "missing", *dirs,
           says=f"--val-bvh {t / 'missing'}: no such folder")
    _fails(capsys, "train", "--smoke", "--init-from", t / "nope.pt", *dirs, says="--init-from")
    _fails(capsys, "train", "--smoke", "--init-from", t / "notes.txt", *dirs, says="is not a PyTorch checkpoint")
    _fails(capsys, "train", "--smoke", "--init-from", t / "other.pt", *dirs, says="is not a pose model checkpoint")
    assert not (t / "ck").exists()


def test_export_average_and_synth_capture_reject_bad_files(files, capsys):
    t = files
    _fails(capsys, "export", "--checkpoint", t / "notes.txt", "--out", t / "m", says="is not a PyTorch checkpoint")
    _fails(capsys, "export", "--checkpoint", t / "nope.pt", "--out", t / "m", says="no such file")
    _fails(capsys, "average", t / "nope.pt", t / "other.pt", "--out", t / "s.pt", says="no such file")
    _fails(capsys, "synth-capture", t / "missing.bvh", "--out", t / "c.cap", says=f"BVH {t / 'missing.bvh'}: no such file")
    _fails(capsys, "synth-capture", t / "zero.bvh", "--out", t / "c.cap", says="has no frames")
    assert not (t / "m").exists() and not (t / "c.cap").exists()


def test_prepare_rejects_a_missing_or_empty_folder(files, capsys):
    t = files
    _fails(capsys, "prepare", "--bvh", t / "missing", "--cache-dir", t / "cache", says="no such folder")
    _fails(capsys, "prepare", "--bvh", t / "empty", "--cache-dir", t / "cache", says="no BVH clips")
    assert not (t / "cache").exists()


def test_unexpected_errors_keep_their_traceback(files, monkeypatch):
    from training import average

    def bug(args):
        raise KeyError("a bug")
    monkeypatch.setattr(average, "main", bug)
    with pytest.raises(KeyError):
        main(["average", str(files / "other.pt"), "--out", str(files / "b.pt")])


def test_average_errors_are_one_line_on_stderr(files, capsys):
    t = files
    torch.manual_seed(0)
    from training.model import ModelConfig, PoseNet
    net = PoseNet(ModelConfig(16, 8, 1, 16))
    for name in ("a.pt", "b.pt"):
        torch.save({"model": net.state_dict(), "config": net.config.to_dict()}, t / name)
    last = _fails(capsys, "average", t / "a.pt", t / "b.pt", "--weights", "1", "--out", t / "s.pt",
                  says="--weights: 1 weights for 2 checkpoints")
    assert "average: average:" not in last
    main(["average", str(t / "a.pt"), str(t / "b.pt"), "--weights", "inf", "1", "--out", str(t / "s.pt")])
    assert capsys.readouterr().out == ""     # the message went to stderr, not stdout
    _fails(capsys, "average", t / "a.pt", t / "b.pt", "--weights", "inf", "1", "--out", t / "s.pt",
           says="--weights inf 1: weights must be finite")
    _fails(capsys, "average", t / "a.pt", t / "b.pt", "--out", t / "b.pt", says="is one of the checkpoints")
    assert not (t / "s.pt").exists()


def test_export_refuses_non_finite_weights_and_a_bad_config_even_unchecked(files, capsys):
    from training.model import ModelConfig, PoseNet
    t = files
    torch.manual_seed(0)
    net = PoseNet(ModelConfig(16, 8, 1, 16))
    state = {k: v.clone() for k, v in net.state_dict().items()}
    state["head.2.bias"][0] = float("nan")
    torch.save({"model": state, "config": net.config.to_dict()}, t / "nan.pt")
    config = dict(net.config.to_dict(), hidden=-5)
    torch.save({"model": net.state_dict(), "config": config}, t / "negative.pt")
    _fails(capsys, "export", "--checkpoint", t / "nan.pt", "--no-check", "--out", t / "m",
           says=f"{t / 'nan.pt'}: the weights hold NaN or inf (head.2.bias)")
    _fails(capsys, "export", "--checkpoint", t / "negative.pt", "--no-check", "--out", t / "m",
           says=f"{t / 'negative.pt'}: invalid network config (hidden -5: expected a positive integer)")
    _fails(capsys, "average", t / "negative.pt", t / "negative.pt", "--out", t / "s.pt",
           says=f"{t / 'negative.pt'}: invalid network config")
    assert not (t / "m").exists()


def test_train_smoke_refuses_a_data_folder(files, capsys):
    t = files
    _fails(capsys, "train", "--smoke", "--bvh", t / "clips", "--ckpt-dir", t / "ck", "--results-dir", t / "res",
           says="--smoke trains on procedural motions and cannot be combined with --bvh")
    assert not (t / "ck").exists() and not (t / "res").exists()


FULL_DISK = """
import resource, signal, sys
from training.__main__ import main
# files larger than 20 kB cannot be written: what a full disk does to a checkpoint (EFBIG instead
# of ENOSPC; torch's own file writer aborted the process on either)
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))
sys.exit(main(sys.argv[1:]))
"""


def test_a_full_disk_while_saving_a_checkpoint_is_one_line_not_an_abort(files):
    import os
    import subprocess
    import sys
    from pathlib import Path
    from training.model import ModelConfig, PoseNet
    t = files
    net = PoseNet(ModelConfig(32, 32, 1, 32))   # ~80 kB
    for name in ("a.pt", "b.pt"):
        torch.save({"model": net.state_dict(), "config": net.config.to_dict()}, t / name)
    repo = Path(__file__).resolve().parents[2]
    env = dict(os.environ, PYTHONPATH=str(repo))
    runs = {"average": ([t / "a.pt", t / "b.pt", "--out", t / "soup" / "s.pt"], t / "soup" / "s.pt"),
            "train": (["--smoke", "--steps", "2", "--ckpt-dir", t / "ck", "--results-dir", t / "res"], t / "ck")}
    for command, (rest, target) in runs.items():
        r = subprocess.run([sys.executable, "-c", FULL_DISK, command] + [str(a) for a in rest], env=env,
                           cwd=repo, capture_output=True, text=True, timeout=300)
        last = r.stderr.replace("\r", "\n").strip().splitlines()[-1]
        assert r.returncode == 1 and "Traceback" not in r.stderr and "terminate" not in r.stderr, r.stderr
        assert last.startswith(f"training {command}: {target}") and "cannot write the checkpoint" in last, r.stderr
    assert os.listdir(t / "soup") == [] and os.listdir(t / "ck") == []   # no partial file, no temporary
