"""Reads a BVH with the independent Python reader (training/bvh.py) and prints what it found, for
tests/test_bvh_writer.cpp:

    python3 bvh_read_check.py FILE.bvh

Output lines:
    frames N
    frame_time DT
    joints name0 name1 ...          (file order)
    parents p0 p1 ...               (file order, -1 for the root)
    offset NAME x y z               (per joint)
    root F x y z                    (per frame)
    rot F NAME m00 m01 ... m22      (per frame and joint: local rotation matrix, row-major)
"""
import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))  # the repository root

from training.bvh import read_bvh  # noqa: E402


def main(path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # "declares more frames than it holds" fails the check
        clip = read_bvh(path)
    out = [f"frames {clip.num_frames}", f"frame_time {clip.frame_time!r}",
           "joints " + " ".join(clip.joints), "parents " + " ".join(str(p) for p in clip.parents)]
    for j, name in enumerate(clip.joints):
        out.append(f"offset {name} " + " ".join(f"{v:.9g}" for v in clip.offsets[j]))
    for f in range(clip.num_frames):
        out.append(f"root {f} " + " ".join(f"{v:.9g}" for v in clip.root_pos[f]))
        for j, name in enumerate(clip.joints):
            out.append(f"rot {f} {name} " + " ".join(f"{v:.9g}" for v in clip.rotations[f, j].ravel()))
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main(sys.argv[1])
