"""Motion packs: what `prepare` would load, in one small file, and errors for damaged packs."""
import json
import struct

import numpy as np
import pytest

from training import dataset as ds, motion_pack as mp, train as tr
from training.__main__ import main as cli_main


def _angle_deg(a, b):
    r = np.einsum("...ji,...jk->...ik", a.astype(np.float64), b.astype(np.float64))
    return np.degrees(np.arccos(np.clip((np.trace(r, axis1=-2, axis2=-1) - 1) / 2, -1, 1)))


@pytest.fixture(scope="module")
def packed(fixture_dir, tmp_path_factory):
    d, _ = fixture_dir
    out = tmp_path_factory.mktemp("pack") / "all.mpack"
    summary = mp.write_pack(ds.list_clips(d), out, workers=1, progress=False)
    return d, out, summary


def test_a_pack_loads_as_the_prepared_clips_within_its_quantisation(packed, tmp_path):
    d, out, summary = packed
    prepared = ds.load_motions(d, cache_dir=tmp_path, workers=1, progress=False)
    loaded = ds.load_motions(out)
    assert summary["clips"] == len(prepared) and mp.is_pack(out) and not mp.is_pack(d)
    assert [m.name for m in loaded] == [m.name for m in prepared]
    for a, b in zip(loaded, prepared):
        assert (a.subject, a.fps, a.num_frames) == (b.subject, b.fps, b.num_frames)
        assert a.local_rot.dtype == np.float32 and a.root_pos.dtype == np.float32
        np.testing.assert_array_equal(a.offsets, b.offsets)
        assert _angle_deg(a.local_rot, b.local_rot).max() < 0.1
        assert np.abs(a.root_pos - b.root_pos).max() < 1e-4
    # one split of a pack: the subject rule of the CMU split
    val = ds.load_motions(out, split="val")
    assert [m.name for m in val] == [m.name for m in prepared if ds.split_of(m.subject) == "val"]


def test_quaternion_sign_flips_and_fast_turns_survive_packing():
    # a whole turn about Y every 1.5 s: the w >= 0 quaternions flip sign twice per turn
    t = np.arange(90) / 60.0
    ang = 2 * np.pi * t / 1.5
    local = np.tile(np.eye(3), (90, 24, 1, 1))
    c, s = np.cos(ang), np.sin(ang)
    local[:, 0] = np.stack([np.stack([c, 0 * c, s], -1), np.stack([0 * c, 1 + 0 * c, 0 * c], -1),
                            np.stack([-s, 0 * c, c], -1)], -2)
    root = np.stack([np.sin(ang), 0.9 + 0 * ang, 30.0 * t], -1)
    rot, rootc = mp._encode_clip(local, root)
    back_rot, back_root = mp._decode_clip(rot, rootc, 90)
    assert _angle_deg(back_rot, local).max() < 0.1
    assert np.abs(back_root - root).max() < 1e-4


def test_damaged_packs_are_clear_errors(packed, tmp_path):
    _, out, _ = packed
    data = out.read_bytes()
    truncated = tmp_path / "truncated.mpack"
    truncated.write_bytes(data[:len(data) // 2])
    with pytest.raises(tr.UsageError, match="damaged|truncated"):
        mp.read_pack(truncated)
    (n,) = struct.unpack_from("<I", data, len(mp.MAGIC))
    header = json.loads(data[len(mp.MAGIC) + 4:len(mp.MAGIC) + 4 + n])
    header["clips"][0]["frames"] += 1   # the header asks for more data than there is
    head = json.dumps(header).encode()
    wrong = tmp_path / "wrong.mpack"
    wrong.write_bytes(mp.MAGIC + struct.pack("<I", len(head)) + head + data[len(mp.MAGIC) + 4 + n:])
    with pytest.raises(tr.UsageError, match="header needs"):
        mp.read_pack(wrong)
    header["format"] = 99
    head = json.dumps(header).encode()
    future = tmp_path / "future.mpack"
    future.write_bytes(mp.MAGIC + struct.pack("<I", len(head)) + head)
    with pytest.raises(tr.UsageError, match="format 99"):
        mp.read_pack(future)
    other = tmp_path / "other.mpack"
    other.write_bytes(b"PK\x03\x04 not a pack")
    with pytest.raises(tr.UsageError, match="not a motion pack"):
        mp.read_pack(other)


def test_pack_command_and_training_options_take_packs(fixture_dir, tmp_path, capsys):
    d, _ = fixture_dir
    out = tmp_path / "val.mpack"
    assert cli_main(["pack", "--bvh", str(d), "--split", "val", "--out", str(out), "--workers", "1"]) == 0
    assert "-> " in capsys.readouterr().out and [m.name for m in ds.load_motions(out)] == ["01_01"]
    cfg = tr.config_from_args(_train_args(["--bvh", str(out), "--val-bvh", str(out)]))
    assert cfg.train_source == str(out) and cfg.val_source == str(out)
    from argparse import Namespace
    from training.cli import check_inputs
    check_inputs("evaluate", Namespace(bvh=str(out)))   # evaluate --bvh takes a pack too
    # a file that is not a pack is refused before any data loads
    junk = tmp_path / "junk.mpack"
    junk.write_text("hello")
    assert cli_main(["train", "--bvh", str(junk), "--steps", "1"]) == 1
    assert "not a folder or a motion pack" in capsys.readouterr().err
    with pytest.raises(tr.UsageError, match="not a folder or a motion pack"):
        check_inputs("evaluate", Namespace(bvh=str(junk)))
    assert cli_main(["pack", "--bvh", str(tmp_path / "none"), "--out", str(tmp_path / "x.mpack")]) == 1
    assert not (tmp_path / "x.mpack").exists()


def _train_args(argv):
    import argparse
    p = argparse.ArgumentParser()
    tr.add_arguments(p)
    return p.parse_args(argv)


def test_train_on_gpu_script_dry_run_on_cpu(fixture_dir, tmp_path):
    """scripts/train_on_gpu.sh end to end with DEVICE=cpu: smoke check, training from packs with
    data workers, weights-only checkpoints and logs in the output folder."""
    import os
    import subprocess
    import sys
    from pathlib import Path
    d, _ = fixture_dir
    packs = tmp_path / "packs"
    for split in ("train", "val"):
        mp.write_pack(ds.list_clips(d, split), packs / f"{split}.mpack", workers=1, progress=False)
    repo = Path(__file__).resolve().parents[2]
    out = tmp_path / "out"
    env = dict(os.environ, DEVICE="cpu", PYTHON=sys.executable)
    r = subprocess.run(["bash", str(repo / "scripts" / "train_on_gpu.sh"), str(packs), str(out), "1",
                        "--size", "tiny", "--steps", "4", "--batch", "3", "--window", "30", "--data-workers", "2"],
                       env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    for name in ("best.pt", "last.pt", "train_log.json", "loss.png", "console.log"):
        assert (out / name).is_file(), name
    ck = tr.load_checkpoint_file(out / "best.pt")
    assert set(ck) == {"model", "config", "step", "best"}   # the committed, weights-only form
    log = json.loads((out / "train_log.json").read_text())
    assert log["summary"]["steps"] == 4 and log["train_config"]["data_workers"] == 2
    assert "cuda False" in (out / "console.log").read_text()
    bad = subprocess.run(["bash", str(repo / "scripts" / "train_on_gpu.sh"), str(packs)], env=env,
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "usage" in bad.stderr
