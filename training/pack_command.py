"""python3 -m training pack: retargeted clips of the CMU data or a BVH folder into one motion pack
(motion_pack.py holds the format). A command of its own so that the pack format does not depend on
where clips are listed (dataset.py), which itself reads packs."""
from __future__ import annotations

from pathlib import Path

from . import dataset
from .motion_pack import write_pack


def main(args) -> int:
    if args.bvh:
        clips = dataset.list_clips(Path(args.bvh), args.split)
    else:
        clips = dataset.list_clips(dataset.extracted_cmu(), args.split)
    s = write_pack(clips, args.out, workers=args.workers)
    print(f"pack: {s['clips']} clips, {s['source_frames']} source frames -> {args.out} "
          f"({s['bytes'] / 1e6:.1f} MB)")
    return 0


def add_arguments(parser) -> None:
    parser.add_argument("--out", required=True, help="the pack file to write")
    parser.add_argument("--split", default=None, choices=["train", "val", "test"],
                        help="only this split's subjects (default: every clip)")
    parser.add_argument("--bvh", default=None, help="a BVH folder instead of the extracted CMU data")
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
