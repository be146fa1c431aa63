"""CMU motion data for training: extraction, manifest, subject split, cached loading into Motions.

Layout (all under training/data/, ignored by git):
  training/data/cmu/bvh/NN/NN_MM.bvh   extracted from ../shared/data/cmu/*.tar.xz (+ manifest.csv)
  training/data/cache/<version>/<clip>-<key>.npz  one retargeted 60 Hz clip (quaternions, root,
  offsets). <version> hashes the source text of skeleton.py, bvh.py, retarget.py and this file (any
  code change rebuilds the cache; `prepare` deletes other versions), <key> hashes the BVH file
  (path, size, mtime) and the elbow repair applied.

Split (by subject, never by clip; see training/README.md): a subject's "canonical" number is the
lowest number of the CMU sessions re-published under several subject numbers (README of the data);
val = canonical subject % 10 == 1, test = canonical subject % 10 == 6, train = the rest.
Elbow-reversed clips (manifest column elbow_reversed) are REPAIRED by default (the elbow's source
local rotation is inverted); elbow="exclude" drops them instead.
"""
from __future__ import annotations

import csv
import hashlib
import json
import os
import re
import shutil
import subprocess
import tempfile
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from . import skeleton as sk
from .errors import CommandError, UsageError
from .progress import progress_bar

REPO = Path(__file__).resolve().parents[1]
DATA_DIR = REPO / "training" / "data"
CMU_DIR = DATA_DIR / "cmu"
CACHE_DIR = DATA_DIR / "cache"
SHARED_CMU = REPO.parent / "shared" / "data" / "cmu"

SPLITS = ("train", "val", "test")
VAL_RESIDUE, TEST_RESIDUE = 1, 6
# CMU sessions published under several subject numbers (data README, "Duplicates"): later number ->
# first number. Their clips always land in the split of the first number.
CANONICAL_SUBJECT = {122: 83, 105: 91, 139: 77, 121: 90, 141: 106, 102: 78, 64: 63, 84: 74, 117: 85,
                     73: 70, 123: 70, 103: 93}


def split_of(subject: int) -> str:
    s = CANONICAL_SUBJECT.get(int(subject), int(subject))
    if s % 10 == VAL_RESIDUE:
        return "val"
    if s % 10 == TEST_RESIDUE:
        return "test"
    return "train"


SPLIT = {"rule": f"canonical subject % 10 == {VAL_RESIDUE} -> val, == {TEST_RESIDUE} -> test, else train",
         "canonical": CANONICAL_SUBJECT, "split_of": split_of}


# ------------------------------------------------------------------------------ extraction
def extract_cmu(dest=None, src=None, force: bool = False, jobs: int = 1) -> Path:
    """Extract ../shared/data/cmu/*.tar.xz into dest (idempotent: a marker per archive).
    One archive at a time by default: two tars creating the same folders at once can fail
    ("Cannot open: File exists"), and the four archives take seconds either way."""
    dest = Path(CMU_DIR if dest is None else dest)
    src = Path(SHARED_CMU if src is None else src)
    archives = sorted(src.glob("*.tar.xz"))
    if not archives:
        if (dest / "manifest.csv").exists():
            return dest
        raise FileNotFoundError(f"no CMU archives in {src}")
    dest.mkdir(parents=True, exist_ok=True)
    todo = []
    for a in archives:
        marker = dest / f".extracted-{a.name}-{a.stat().st_size}"
        if force or not marker.exists():
            todo.append((a, marker))
    procs = []
    try:
        for a, marker in todo:
            while len(procs) >= max(1, jobs):
                _wait_first(procs)
            print(f"extracting {a.name} ...", flush=True)
            # tar's complaints go to a file, so that a failure can say what tar said about which
            # archive (two tars print interleaved, and a progress bar may follow).
            err = tempfile.TemporaryFile()
            procs.append((subprocess.Popen(["tar", "xJf", str(a), "-C", str(dest)], stderr=err),
                          a, marker, err))
        while procs:
            _wait_first(procs)
    finally:
        for p, _, _, err in procs:      # after a failure: stop the other extractions
            p.kill()
            p.wait()
            err.close()
    for name in ("manifest.csv", "README.md"):
        if (src / name).exists() and (force or not (dest / name).exists()):
            shutil.copyfile(src / name, dest / name)
    return dest


class ExtractionError(CommandError, RuntimeError):
    """An archive that tar could not extract (damaged, truncated, disk full): a message."""


def _wait_first(procs):
    p, archive, marker, err = procs.pop(0)
    with err:
        if p.wait() != 0:
            err.seek(0)
            said = err.read().decode("utf-8", "replace").strip().splitlines()
            detail = ": " + " / ".join(said[-3:]) if said else ""
            raise ExtractionError(f"extracting {archive} failed (tar exit status {p.returncode}){detail}; "
                               "run prepare again (archives already extracted are kept)")
    marker.write_text("ok\n")


# ------------------------------------------------------------------------------ manifest
MANIFEST_NEEDS = ("clip", "subject", "status")


def read_manifest(path) -> list:
    """The rows of a manifest.csv (dicts, subject as int, missing cells ""). A manifest that cannot
    be used is a UsageError naming it and the problem, with the line of the first bad row."""
    rows = []
    try:
        # utf-8-sig: a spreadsheet's byte-order mark must not hide the first column's name
        with open(path, newline="", encoding="utf-8-sig") as f:
            reader = csv.DictReader(f)
            header = reader.fieldnames or []
            for r in reader:
                rows.append((reader.line_num, r))
    except UnicodeDecodeError as e:
        raise UsageError(f"{path}: not UTF-8 text (byte {e.start}: {e.reason})") from None
    except csv.Error as e:
        raise UsageError(f"{path}: not a readable CSV file ({e})") from None
    missing = [c for c in MANIFEST_NEEDS if c not in header]
    if missing:
        raise UsageError(f"{path}: no {', '.join(missing)} column (its header: "
                         f"{', '.join(str(h) for h in header) or 'none'})")
    out = []
    for line, r in rows:
        r.pop(None, None)                       # cells beyond the header
        for k, v in r.items():
            if v is None:                       # a short row
                r[k] = ""
        if not r["clip"].strip():
            raise UsageError(f"{path} line {line}: no clip name")
        subject = r["subject"].strip()
        if not re.fullmatch(r"[0-9]+", subject):
            raise UsageError(f"{path} line {line}: subject {r['subject']!r} is not a subject number")
        r["subject"] = int(subject)
        out.append(r)
    return out


def clip_path(root, clip: str, subject: int) -> Path:
    return Path(root) / "bvh" / f"{int(subject):02d}" / f"{clip}.bvh"


_CLIP_RE = re.compile(r"^(\d+)_\d+$")


def list_clips(root, split=None, elbow: str = "repair") -> list:
    """(clip, subject, path, elbow_reversed) for the usable clips under root.
    With root/manifest.csv: rows with status == ok (missing files are an error). Without: every
    *.bvh below root (subject from an NN_MM name, else 0)."""
    root = Path(root)
    out = []
    man = root / "manifest.csv"
    if man.exists():
        for r in read_manifest(man):
            if r["status"].strip() != "ok":
                continue
            if elbow == "exclude" and r.get("elbow_reversed", "").strip():
                continue
            p = clip_path(root, r["clip"], r["subject"])
            if not p.exists():
                raise FileNotFoundError(f"{p} (listed ok in {man})")
            out.append((r["clip"], r["subject"], p, r.get("elbow_reversed", "").strip()
                        if elbow == "repair" else ""))
    else:
        paths = sorted(root.rglob("*.bvh"))
        stems = Counter(p.stem for p in paths)
        for p in paths:
            m = _CLIP_RE.match(p.stem)
            # Clips are keyed by name: two "walk.bvh" in different folders keep their folders.
            name = p.stem if stems[p.stem] == 1 else p.relative_to(root).with_suffix("").as_posix()
            out.append((name, int(m.group(1)) if m else 0, p, ""))
    if split is not None:
        if split not in SPLITS:
            raise ValueError(f"split must be one of {SPLITS}")
        out = [c for c in out if split_of(c[1]) == split]
    return out


# ------------------------------------------------------------------------------ cache
def code_version() -> str:
    h = hashlib.sha1()
    here = Path(__file__).resolve().parent
    for name in ("skeleton.py", "bvh.py", "retarget.py", "dataset.py"):
        h.update((here / name).read_bytes())
    return h.hexdigest()[:12]


def cache_path(clip: str, path: Path, elbow_reversed: str, cache_dir=None, version=None) -> Path:
    st = Path(path).stat()
    key = f"{Path(path).resolve()}|{st.st_size}|{st.st_mtime_ns}|{elbow_reversed}"
    root = Path(CACHE_DIR if cache_dir is None else cache_dir)
    safe = clip.replace("/", "__")
    return root / (version or code_version()) / f"{safe}-{hashlib.sha1(key.encode()).hexdigest()[:16]}.npz"


def prune_cache(cache_dir=None) -> list:
    """Remove cache folders of other code versions; returns what was removed."""
    root = Path(CACHE_DIR if cache_dir is None else cache_dir)
    keep = code_version()
    gone = []
    if root.is_dir():
        for d in root.iterdir():
            if d.is_dir() and re.fullmatch(r"[0-9a-f]{12}", d.name) and d.name != keep:
                shutil.rmtree(d)
                gone.append(d.name)
    return gone


def _save(path: Path, m: sk.Motion):
    tmp = path.with_name(path.name + f".tmp{os.getpid()}.npz")
    np.savez(tmp, quat=sk.quat_from_rot(m.local_rot).astype(np.float32), root_pos=m.root_pos,
             offsets=m.offsets, fps=np.float64(m.fps), name=np.array(m.name), subject=np.int64(m.subject))
    os.replace(tmp, path)


def _load(path: Path) -> sk.Motion:
    with np.load(path) as z:
        return sk.Motion(name=str(z["name"]), subject=int(z["subject"]), fps=float(z["fps"]),
                         local_rot=sk.rot_from_quat(z["quat"]).astype(np.float32),
                         root_pos=z["root_pos"].astype(np.float32), offsets=z["offsets"].astype(np.float32))


def _convert(item):
    """Worker: read + retarget one clip (writing its cache file). Returns (clip, frames, seconds,
    file frame time, motion or None)."""
    clip, subject, path, elbow, cpath, keep = item
    from .bvh import read_bvh
    from .retarget import to_smpl_motion
    c = read_bvh(path)
    m = to_smpl_motion(c, clip, subject, elbow_reversed=elbow)
    if cpath is not None:
        Path(cpath).parent.mkdir(parents=True, exist_ok=True)
        _save(Path(cpath), m)
    return clip, m.num_frames, m.num_frames / m.fps, c.frame_time, (m if keep else None)


def _run(clips, cache, force, workers, progress, keep, cache_dir, desc):
    version = code_version()
    results = {}
    todo = []
    for clip, subject, path, elbow in clips:
        cp = cache_path(clip, path, elbow, cache_dir, version) if cache else None
        if cp is not None and cp.exists() and not force:
            results[clip] = ("cached", cp)
        else:
            todo.append((clip, subject, str(path), elbow, str(cp) if cp else None, keep or not cache))
    if todo:
        workers = max(1, min(workers or os.cpu_count() or 1, len(todo)))
        if workers == 1:
            it = map(_convert, todo)
            for r in progress_bar(it, len(todo), desc, progress):
                results[r[0]] = ("new", r)
        else:
            with ProcessPoolExecutor(workers) as ex:
                it = ex.map(_convert, todo, chunksize=4)
                for r in progress_bar(it, len(todo), desc, progress):
                    results[r[0]] = ("new", r)
    return results


def extracted_cmu() -> Path:
    """The extracted CMU folder, extracting ../shared/data/cmu first when it is not there yet."""
    if not (CMU_DIR / "manifest.csv").exists():
        extract_cmu(CMU_DIR)
    return CMU_DIR


def load_motions(source="train", cache: bool = True, elbow: str = "repair", workers=None,
                 progress: bool = True, force: bool = False, cache_dir=None, split=None,
                 every: int = 1) -> list:
    """Motions (60 Hz, our skeleton) of a split of the extracted CMU data ("train", "val",
    "test"), or of a BVH folder (a path: with manifest.csv, its ok rows; else every *.bvh), or of
    a motion pack file (motion_pack.py), in clip order; every: only every Nth clip (the others are
    neither read nor converted). Converted clips are cached as npz under training/data/cache."""
    if every < 1:
        raise ValueError("every must be 1 or more")
    if elbow not in ("repair", "exclude"):
        raise ValueError("elbow must be 'repair' or 'exclude'")
    if isinstance(source, str) and source in SPLITS:
        root, split = extracted_cmu(), source
    else:
        root = Path(source)
        from .motion_pack import is_pack, read_pack
        if is_pack(root):   # already retargeted (motion_pack.py): nothing to convert or cache
            motions = read_pack(root)
            return [m for m in motions if split is None or split_of(m.subject) == split][::every]
    clips = list_clips(root, split, elbow)[::every]
    res = _run(clips, cache, force, workers, progress, True, cache_dir, "loading")
    out = []
    for clip, *_ in clips:
        kind, val = res[clip]
        out.append(_load(val) if kind == "cached" else val[4])
    return out


# ------------------------------------------------------------------------------ CLI
def summarize(motions_or_rows) -> dict:
    n = len(motions_or_rows)
    frames = sum(r[1] for r in motions_or_rows)
    secs = sum(r[2] for r in motions_or_rows)
    return {"clips": n, "frames_60hz": int(frames), "hours": round(secs / 3600, 3)}


def prepare(root=None, force=False, workers=None, progress=True, elbow="repair", cache_dir=None) -> dict:
    """Extract (if needed) and convert every usable clip into the cache; return counts per split."""
    t0 = time.time()
    if root is None:
        root = extract_cmu(CMU_DIR, force=force)
    t_extract = time.time() - t0
    clips = list_clips(root, None, elbow)
    pruned = prune_cache(cache_dir)
    if pruned:
        print(f"removed cache of older code versions: {', '.join(pruned)}")
    res = _run(clips, True, force, workers, progress, False, cache_dir, "preparing")
    t_convert = time.time() - t0 - t_extract
    stats = {s: [] for s in SPLITS}
    subjects = {s: set() for s in SPLITS}
    for clip, subject, path, _ in clips:
        kind, val = res[clip]
        if kind == "cached":
            with np.load(val) as z:
                fr = z["quat"].shape[0]
                fps = float(z["fps"])
        else:
            fr, fps = val[1], sk.MODEL_FPS
        stats[split_of(subject)].append((clip, fr, fr / fps))
        subjects[split_of(subject)].add(subject)
    report = {"root": str(root), "extract_s": round(t_extract, 1), "convert_s": round(t_convert, 1),
              "converted": sum(1 for v in res.values() if v[0] == "new"),
              "splits": {s: dict(summarize(stats[s]), subjects=sorted(subjects[s])) for s in SPLITS}}
    return report


def main(args) -> int:
    bvh_dir = getattr(args, "bvh", None)
    force = bool(getattr(args, "force", False))
    report = prepare(root=bvh_dir, force=force, workers=getattr(args, "workers", None),
                     cache_dir=getattr(args, "cache_dir", None))
    for s in SPLITS:
        r = report["splits"][s]
        print(f"{s:5s}: {r['clips']:5d} clips {r['frames_60hz']:9d} frames (60 Hz) {r['hours']:7.3f} h "
              f"subjects {','.join(str(x) for x in r['subjects'])}")
    print(f"extract {report['extract_s']} s, convert {report['convert_s']} s ({report['converted']} clips converted)")
    out = Path(getattr(args, "cache_dir", None) or CACHE_DIR) / "prepare_report.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=1))
    return 0


def add_arguments(parser) -> None:
    """Options of `python3 -m training prepare` (for __main__.py)."""
    parser.add_argument("--bvh", default=None, help="folder of BVH files (with optional manifest.csv) "
                        "instead of the CMU archives in ../shared/data/cmu")
    parser.add_argument("--force", action="store_true", help="re-extract and re-convert everything")
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    parser.add_argument("--cache-dir", dest="cache_dir", default=None, help="cache folder (default training/data/cache)")
