import math
import time
import warnings

import numpy as np
import pytest

from training import bvh
from training import skeleton as sk
from training.procedural import daz_template, make_motion, motion_to_daz

SAMPLE = (
    "HIERARCHY\r\n"
    "ROOT Hips\r\n{\r\n\tOFFSET 1 2 3\r\n"
    "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\r\n"
    "\tJOINT Arm\r\n\t{\r\n\t\tOFFSET 0 0 1\r\n\t\tCHANNELS 3 Xrotation Yrotation Zrotation\r\n"
    "\t\tJOINT Slider\r\n\t\t{\r\n\t\t\tOFFSET 5 6 7\r\n"
    "\t\t\tCHANNELS 4 Yrotation Xposition Zposition Xrotation\r\n"
    "\t\t\tEnd Site\r\n\t\t\t{\r\n\t\t\t\tOFFSET 0 1 0\r\n\t\t\t}\r\n\t\t}\r\n\t}\r\n"
    "\tJOINT Leg\r\n\t{\r\n\t\tOFFSET 0 -1 0\r\n\t\tEnd Site\r\n\t\t{\r\n\t\t\tOFFSET 0 -1 0\r\n\t\t}\r\n\t}\r\n"
    "}\r\n"
    "MOTION\r\nFrames:\t2\r\nFrame Time: 0.0833333\r\n"
    "10 20 30 90 90 0\t0 0 0\t0 0.5 -0.5 0\r\n"
    "0 0 0 0 0 0 30 -20 10 45 1 2 15\r\n"
)


def test_parse_structure_crlf_tabs_mixed_channels():
    c = bvh.parse_bvh(SAMPLE)
    assert c.joints == ["Hips", "Arm", "Slider", "Leg"]
    assert c.parents == [-1, 0, 1, 0]
    assert c.frame_time == pytest.approx(0.0833333)
    assert c.num_frames == 2
    assert c.channels[2] == ["Yrotation", "Xposition", "Zposition", "Xrotation"]
    assert c.channels[3] == []
    assert np.allclose(c.end_sites[2], [0, 1, 0]) and np.allclose(c.end_sites[3], [0, -1, 0])
    assert np.allclose(c.offsets[0], [1, 2, 3])
    # root position channels replace the OFFSET
    assert np.allclose(c.root_pos[0], [10, 20, 30]) and np.allclose(c.root_pos[1], 0)
    # position channels on a non-root joint: X and Z replaced, Y keeps the OFFSET
    assert c.translations is not None
    assert np.allclose(c.translations[0, 2], [0.5, 6, -0.5]) and np.allclose(c.translations[1, 2], [1, 6, 2])
    assert np.allclose(c.rotations[:, 3], np.eye(3))           # joint without channels


def test_intrinsic_rotation_order():
    c = bvh.parse_bvh(SAMPLE)
    # root Z=90 then X=90, intrinsic: R = Rz(90) Rx(90); child offset (0,0,1) -> (1,0,0).
    # (the extrinsic reading Rx(90) Rz(90) would give (0,-1,0))
    assert np.allclose(c.rotations[0, 0] @ [0, 0, 1], [1, 0, 0], atol=1e-12)
    assert np.allclose(c.rotations[1, 1], sk.euler_to_rot([30, -20, 10], "XYZ"))
    assert np.allclose(c.rotations[1, 2], sk.euler_to_rot([45, 15], "YX") if False else
                       sk.rot_axis("y", np.radians(45)) @ sk.rot_axis("x", np.radians(15)))
    g, p = c.global_transforms()
    assert np.allclose(p[0, 1], [10, 20, 30] + c.rotations[0, 0] @ [0, 0, 1])


@pytest.mark.parametrize("order", ["ZXY", "XYZ"])
def test_write_read_roundtrip(tmp_path, order):
    m = make_motion("mixed", 2.0, seed=5)
    clip = motion_to_daz(m)
    path = tmp_path / f"rt_{order}.bvh"
    bvh.write_bvh(path, clip, order=order, decimals=6)
    text = path.read_text()
    assert f"CHANNELS 3 {order[0]}rotation {order[1]}rotation {order[2]}rotation" in text
    assert "End Site" in text and "\r" not in text
    back = bvh.read_bvh(path)
    assert back.joints == clip.joints and back.parents == clip.parents
    assert back.num_frames == clip.num_frames and back.frame_time == pytest.approx(clip.frame_time, abs=1e-7)
    assert np.allclose(back.offsets, clip.offsets)
    assert set(back.end_sites) == set(clip.end_sites)
    assert np.degrees(sk.angle_between_rots(back.rotations, clip.rotations)).max() < 1e-3
    assert np.abs(back.root_pos - clip.root_pos).max() < 1e-5


def test_writer_keeps_nonroot_position_channels():
    c = bvh.parse_bvh(SAMPLE)
    back = bvh.parse_bvh(bvh.format_bvh(c, order="XYZ"))
    assert back.translations is not None
    assert np.allclose(back.translations, c.translations, atol=1e-6)
    assert np.allclose(back.rotations, c.rotations, atol=1e-6)


def test_errors():
    with pytest.raises(bvh.BvhError):
        bvh.parse_bvh("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\n}\n")            # no MOTION
    with pytest.raises(bvh.BvhError):
        bvh.parse_bvh(SAMPLE.replace("15\r\n", "abc\r\n"))                   # bad number
    with pytest.raises(bvh.BvhError):
        bvh.parse_bvh(SAMPLE.replace("CHANNELS 3 X", "CHANNELS 3 Q"))        # bad channel
    with pytest.warns(UserWarning):
        short = bvh.parse_bvh(SAMPLE.replace("Frames:\t2", "Frames: 3"))
    assert short.num_frames == 2


def test_read_speed(tmp_path):
    # ~1/60 of the CMU set's text in one file: must parse well under a second
    m = make_motion("walk", 70.0, seed=1)
    clip = motion_to_daz(m)
    text = bvh.format_bvh(clip, decimals=4)
    t = time.perf_counter()
    c = bvh.parse_bvh(text)
    dt = time.perf_counter() - t
    assert c.num_frames == clip.num_frames
    assert dt < 1.0, f"{len(text) / 1e6:.1f} MB parsed in {dt:.2f} s"


def test_daz_template_is_tpose_like():
    t = daz_template()
    rest = t.rest_positions()
    assert rest[t.index("lHand"), 0] > 50 and rest[t.index("rHand"), 0] < -50     # left = +X
    low = min(rest[t.index(f), 1] + t.end_sites[t.index(f)][1] for f in ("lFoot", "rFoot"))
    assert 80 < -low < 86                                                        # hip ~83 cm above toes


ODD_NUMBERS = ["1e39", "1e999", "nan", "-inf", "inf", "-0", "", "e", "-", ".", "0x10", "1,5", "-5",
               "99999999999999999999", "0"]


def _damaged_copies(text: str, count: int, seed: int):
    """Seeded damage of a BVH text: odd numbers, removed/repeated lines, cuts and junk."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        lines = text.split("\n")
        i = int(rng.integers(len(lines)))
        kind = int(rng.integers(4))
        if kind == 0:
            tokens = lines[i].split()
            if tokens:
                t = tokens[int(rng.integers(len(tokens)))]
                odd = ODD_NUMBERS[int(rng.integers(len(ODD_NUMBERS)))]
                lines[i] = lines[i].replace(t, odd, 1)
                yield f"line {i + 1}: {t!r} -> {odd!r}", "\n".join(lines)
                continue
            kind = 1
        if kind == 1:
            del lines[i]
            yield f"line {i + 1} removed", "\n".join(lines)
        elif kind == 2:
            lines.insert(i, lines[i])
            yield f"line {i + 1} repeated", "\n".join(lines)
        else:
            cut = int(rng.integers(len(text)))
            yield f"cut at {cut}", text[:cut]


def test_damaged_files_are_refused_or_read_into_finite_clips():
    """`evaluate --bvh DIR` takes any folder: a damaged file must raise BvhError (a message),
    never another exception, and what is read must be finite with a positive frame time."""
    text = bvh.format_bvh(motion_to_daz(make_motion("mixed", 1.0, seed=2)), order="ZXY", decimals=4)
    refused = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)     # "declares more frames than it holds"
        for what, damaged in _damaged_copies(text, 300, seed=20261122):
            try:
                clip = bvh.parse_bvh(damaged)
            except bvh.BvhError:
                refused += 1
                continue
            except Exception as e:      # noqa: BLE001 - any other exception is the bug looked for
                pytest.fail(f"{what}: {type(e).__name__} instead of BvhError: {e}")
            assert math.isfinite(clip.frame_time) and clip.frame_time > 0, what
            assert np.isfinite(clip.rotations).all() and np.isfinite(clip.root_pos).all(), what
            assert np.isfinite(clip.offsets).all(), what
    assert refused > 0


def _daz_text(seconds=1.0):
    return bvh.format_bvh(motion_to_daz(make_motion("walk", seconds, seed=2)), order="ZXY", decimals=4)


def _edit_motion_lines(text, edit):
    lines = text.split("\n")
    first = lines.index("MOTION") + 3
    lines[first:] = [edit(line) if line.strip() else line for line in lines[first:]]
    return "\n".join(lines)


@pytest.mark.parametrize("edit, held", [(lambda line: " ".join(line.split()[:-3]), "63"),
                                        (lambda line: line + " 0 0 0", "69")])
def test_motion_lines_must_hold_one_value_per_channel(tmp_path, edit, held):
    """Read as one flat array, 3 values missing or extra per line shift every later frame onto
    the wrong channels: refused with the file and line, not read misaligned."""
    text = _daz_text()
    first_data_line = text.split("\n").index("MOTION") + 4
    path = tmp_path / "shifted.bvh"
    path.write_text(_edit_motion_lines(text, edit))
    with pytest.raises(bvh.BvhError, match=rf"shifted\.bvh: line {first_data_line} holds {held} values, "
                                           r"but the HIERARCHY declares 66 channels"):
        bvh.read_bvh(path)


def test_a_short_file_warns_naming_the_file(tmp_path):
    path = tmp_path / "cut.bvh"
    path.write_text(SAMPLE.replace("Frames:\t2", "Frames: 3"))
    with pytest.warns(UserWarning, match=r"cut\.bvh: declares 3 frames but holds 2"):
        assert bvh.read_bvh(path).num_frames == 2
    path.write_text(SAMPLE.replace("Frames:\t2", "Frames: 1"))
    with pytest.warns(UserWarning, match=r"cut\.bvh: holds 2 frames but declares 1"):
        assert bvh.read_bvh(path).num_frames == 1


def test_a_file_cut_inside_its_last_line_keeps_its_whole_frames(tmp_path):
    """A writer stopped mid-line (a crash) leaves a short last line: its whole frames are read,
    the cut one is left out with a warning, instead of refusing the clip."""
    whole = SAMPLE.rstrip("\n")
    cut = whole[:whole.rindex(" ", 0, len(whole) - 5)]     # a few values short on the last line
    path = tmp_path / "crashed.bvh"
    path.write_text(cut)
    with pytest.warns(UserWarning) as caught:
        clip = bvh.read_bvh(path)
    assert clip.num_frames == 1
    assert any("crashed.bvh: the last motion line" in str(w.message) for w in caught)
    np.testing.assert_array_equal(clip.rotations[0], bvh.parse_bvh(SAMPLE).rotations[0])


@pytest.mark.parametrize("value, problem", [("nan", "is not a positive finite number of seconds"),
                                            ("-0.01", "is not a positive finite number of seconds"),
                                            ("1e6", "is implausible"), ("abc", "is not a number")])
def test_frame_time_must_be_a_plausible_number_of_seconds(tmp_path, value, problem):
    path = tmp_path / "slow.bvh"
    path.write_text(SAMPLE.replace("Frame Time: 0.0833333", f"Frame Time: {value}"))
    with pytest.raises(bvh.BvhError, match=rf"slow\.bvh: Frame Time '?{value}'? (s )?{problem}"):
        bvh.read_bvh(path)
