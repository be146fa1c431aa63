import argparse
import csv
import subprocess

import numpy as np
import pytest

from training import dataset as ds
from training import skeleton as sk
from training.bvh import BvhError
from training.errors import CommandError, UsageError

# subject numbers of the 96 subjects in ../shared/data/cmu (a fact from its manifest)
CMU_SUBJECTS = [1, 2, 3, 6, 7, 8, 9, 10, 11, 12, 13, 15, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29,
                30, 31, 32, 33, 34, 35, 36, 37, 38, 39, 40, 41, 42, 43, 45, 46, 47, 49, 54, 55, 56, 60, 61, 62,
                63, 64, 69, 70, 74, 75, 76, 77, 78, 79, 80, 81, 82, 83, 84, 85, 86, 87, 88, 89, 90, 91, 93,
                103, 104, 106, 107, 108, 113, 114, 115, 120, 125, 126, 127, 128, 131, 132, 133, 134, 136,
                137, 138, 140, 142, 143, 144]


def test_split_rule():
    got = {s: ds.split_of(s) for s in CMU_SUBJECTS}
    assert [s for s in CMU_SUBJECTS if got[s] == "val"] == [1, 11, 21, 31, 41, 61, 81, 91, 131]
    assert [s for s in CMU_SUBJECTS if got[s] == "test"] == [6, 26, 36, 46, 56, 76, 86, 106, 126, 136]
    # re-published sessions stay with their first subject number
    for later, first in ds.CANONICAL_SUBJECT.items():
        assert ds.split_of(later) == ds.split_of(first)
    assert ds.split_of(141) == "test" and ds.split_of(105) == "val" and ds.split_of(121) == "train"


def test_list_clips_skips_non_ok_rows(fixture_dir):
    d, written = fixture_dir
    rows = ds.read_manifest(d / "manifest.csv")
    assert {r["status"].split(":")[0] for r in rows} == {"ok", "duplicate", "missing"}
    clips = ds.list_clips(d)
    assert [c[0] for c in clips] == list(written)
    assert [c[0] for c in clips if c[3]] == ["01_01"]                   # elbow_reversed=L, repaired
    assert "01_01" not in [c[0] for c in ds.list_clips(d, elbow="exclude")]
    assert {c[0] for c in ds.list_clips(d, "val")} == {"01_01"}
    assert {c[0] for c in ds.list_clips(d, "test")} == {"06_01"}
    with pytest.raises(ValueError):
        ds.list_clips(d, "everything")


def _world_dirs(m):
    g, p = sk.forward_kinematics(m.local_rot.astype(np.float64), m.root_pos, m.offsets)
    bones = [(c, q) for c, q in enumerate(sk.PARENTS) if q >= 0]
    v = np.stack([p[:, c] - p[:, q] for c, q in bones], 1)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def test_load_motions_end_to_end(fixture_dir, tmp_path):
    d, written = fixture_dir
    ms = ds.load_motions(d, cache_dir=tmp_path, workers=1, progress=False)
    assert [m.name for m in ms] == list(written)
    man = {r["clip"]: r for r in ds.read_manifest(d / "manifest.csv")}
    for m in ms:
        truth = written[m.name]
        assert m.fps == 60 and m.local_rot.dtype == np.float32 and m.root_pos.dtype == np.float32
        assert m.local_rot.shape == (m.num_frames, 24, 3, 3) and m.offsets.shape == (24, 3)
        assert m.subject == int(man[m.name]["subject"])
        # duration: manifest seconds (= frames x frame time) minus at most one source frame
        ft = float(man[m.name]["frame_time"])
        assert float(man[m.name]["seconds"]) - ft - 1 / 60 <= m.seconds <= float(man[m.name]["seconds"])
        # every 5th 60 Hz frame is a source sample (24 fps: every 2.5, 12 fps: every 5)
        a = _world_dirs(m)[::5]
        b = _world_dirs(truth)[::5][: len(a)]
        err = np.degrees(np.arccos(np.clip(np.sum(a * b, -1), -1, 1)))
        assert err.max() < 0.1, (m.name, err.max())          # incl. the repaired elbow of 01_01
        assert abs(np.median(m.root_pos[:, 1]) - np.median(truth.root_pos[:, 1])) < 0.03


def test_cache_reuse_and_invalidation(fixture_dir, tmp_path, monkeypatch):
    d, _ = fixture_dir
    first = ds.load_motions(d, cache_dir=tmp_path, workers=1, progress=False)
    files = sorted(tmp_path.glob("*/*.npz"))
    assert len(files) == len(first)

    def boom(item):
        raise AssertionError("should have been cached")
    monkeypatch.setattr(ds, "_convert", boom)
    again = ds.load_motions(d, cache_dir=tmp_path, workers=1, progress=False)
    for a, b in zip(first, again):
        assert a.name == b.name and np.allclose(a.local_rot, b.local_rot, atol=1e-6)
        assert np.allclose(a.root_pos, b.root_pos)
    # another code version or elbow policy -> another cache file
    c = ds.list_clips(d)[0]
    assert ds.cache_path(c[0], c[2], c[3], tmp_path, "v1") != ds.cache_path(c[0], c[2], c[3], tmp_path, "v2")
    assert ds.cache_path(c[0], c[2], "", tmp_path, "v1") != ds.cache_path(c[0], c[2], "L", tmp_path, "v1")
    with pytest.raises(AssertionError):
        ds.load_motions(d, cache_dir=tmp_path, workers=1, progress=False, force=True)


def test_plain_folder_without_manifest(tmp_path, fixture_dir):
    d, written = fixture_dir
    src = d / "bvh" / "02" / "02_01.bvh"
    (tmp_path / "clips").mkdir()
    (tmp_path / "clips" / "02_01.bvh").write_bytes(src.read_bytes())
    (tmp_path / "clips" / "walk.bvh").write_bytes(src.read_bytes())
    ms = ds.load_motions(tmp_path / "clips", cache=False, workers=1, progress=False)
    assert [(m.name, m.subject) for m in ms] == [("02_01", 2), ("walk", 0)]


def test_same_file_name_in_two_folders_is_two_clips(tmp_path, fixture_dir):
    d, _ = fixture_dir
    for sub, src in (("monday", "02_01"), ("tuesday", "03_01")):
        (tmp_path / "clips" / sub).mkdir(parents=True)
        (tmp_path / "clips" / sub / "walk.bvh").write_bytes((d / "bvh" / src[:2] / f"{src}.bvh").read_bytes())
    for cache in (False, True):
        ms = ds.load_motions(tmp_path / "clips", cache=cache, workers=1, progress=False,
                             cache_dir=tmp_path / "cache")
        assert [m.name for m in ms] == ["monday/walk", "tuesday/walk"]
        assert not np.array_equal(ms[0].local_rot[:10], ms[1].local_rot[:10])


def test_extract_failure_names_the_archive_and_what_tar_said(fixture_dir, tmp_path):
    d, _ = fixture_dir
    shared = tmp_path / "shared"
    shared.mkdir()
    subprocess.run(["tar", "cJf", str(shared / "cmu-bvh-subjects-b.tar.xz"), "-C", str(d),
                    "--exclude", "bvh/02", "bvh"], check=True)
    (shared / "cmu-bvh-subjects-a.tar.xz").write_bytes(b"not an xz archive\n" * 64)
    dest = tmp_path / "cmu"
    with pytest.raises(RuntimeError) as e:
        ds.extract_cmu(dest, shared, jobs=2)         # the other tar is stopped, not left running
    msg = str(e.value)
    assert isinstance(e.value, CommandError)                 # one line from the CLI, no traceback
    assert "cmu-bvh-subjects-a.tar.xz" in msg and "tar exit status" in msg
    assert "xz" in msg.split("tar exit status")[1]          # tar's own words come along
    assert not list(dest.glob(".extracted-cmu-bvh-subjects-a*"))
    # a good archive in its place: the next run extracts everything
    subprocess.run(["tar", "cJf", str(shared / "cmu-bvh-subjects-a.tar.xz"), "-C", str(d), "bvh/02"], check=True)
    ds.extract_cmu(dest, shared)
    assert len(list(dest.glob(".extracted-*"))) == 2 and (dest / "bvh" / "02" / "02_01.bvh").exists()


def test_extract_and_prepare(fixture_dir, tmp_path, capsys):
    d, written = fixture_dir
    shared = tmp_path / "shared"
    shared.mkdir()
    subprocess.run(["tar", "cJf", str(shared / "cmu-bvh-subjects-test.tar.xz"), "-C", str(d), "bvh"], check=True)
    (shared / "manifest.csv").write_bytes((d / "manifest.csv").read_bytes())
    dest = tmp_path / "cmu"
    ds.extract_cmu(dest, shared)
    assert (dest / "manifest.csv").exists() and (dest / "bvh" / "02" / "02_01.bvh").exists()
    (dest / "bvh" / "02" / "02_01.bvh").unlink()
    ds.extract_cmu(dest, shared)                              # idempotent: nothing re-extracted
    assert not (dest / "bvh" / "02" / "02_01.bvh").exists()
    ds.extract_cmu(dest, shared, force=True)
    assert (dest / "bvh" / "02" / "02_01.bvh").exists()
    # prepare through main(args), as `python3 -m training prepare --bvh DIR` does
    args = argparse.Namespace(bvh=str(dest), force=False, workers=2, cache_dir=str(tmp_path / "cache"))
    assert ds.main(args) == 0
    out = capsys.readouterr().out
    assert "train:     4 clips" in out and "val  :     1 clips" in out and "test :     1 clips" in out
    assert (tmp_path / "cache" / "prepare_report.json").exists()
    assert len(list((tmp_path / "cache" / ds.code_version()).glob("*.npz"))) == len(written)
    stale = tmp_path / "cache" / "0123456789ab"
    stale.mkdir()
    ds.main(args)
    assert not stale.exists()                                  # older code versions are pruned


@pytest.mark.parametrize("damage, problem", [
    (lambda t: t.replace(",status,", ",state,").encode(), r"manifest\.csv: no status column"),
    (lambda t: t.replace("\n02_01,2,", "\n02_01,two,").encode(), r"manifest\.csv line 2: subject 'two' is not"),
    (lambda t: b"\xff\xff" + t.encode(), r"manifest\.csv: not UTF-8 text"),
    (lambda t: (t + "03_05\n").encode(), r"manifest\.csv line \d+: subject '' is not"),
])
def test_a_malformed_manifest_is_one_usage_error_naming_it(tmp_path, fixture_dir, damage, problem):
    d, _ = fixture_dir
    man = tmp_path / "manifest.csv"
    man.write_bytes(damage((d / "manifest.csv").read_text()))
    with pytest.raises(UsageError, match=problem):
        ds.list_clips(tmp_path)


def test_a_manifest_with_a_byte_order_mark_is_read(tmp_path, fixture_dir):
    d, _ = fixture_dir
    (tmp_path / "manifest.csv").write_bytes(b"\xef\xbb\xbf" + (d / "manifest.csv").read_bytes())
    assert [r["clip"] for r in ds.read_manifest(tmp_path / "manifest.csv")] == \
        [r["clip"] for r in ds.read_manifest(d / "manifest.csv")]


def test_a_zero_frame_clip_beside_good_ones_is_refused_naming_it(tmp_path, fixture_dir):
    """As a damaged clip is: the folder is refused with the file's name, not np.pad's
    "can't extend empty axis" later."""
    d, _ = fixture_dir
    (tmp_path / "clips").mkdir()
    good = (d / "bvh" / "02" / "02_01.bvh").read_text()
    (tmp_path / "clips" / "02_01.bvh").write_text(good)
    (tmp_path / "clips" / "empty.bvh").write_text(good[:good.index("Frames:")] + "Frames: 0\nFrame Time: 0.0416667\n")
    with pytest.raises(BvhError, match=r"empty\.bvh: the clip has no frames"):
        ds.load_motions(tmp_path / "clips", cache=False, workers=1, progress=False)
