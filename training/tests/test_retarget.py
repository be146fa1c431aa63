import re

import numpy as np
import pytest

from training import bvh
from training import retarget as rt
from training import sensors as se
from training import skeleton as sk
from training.procedural import KINDS, daz_template, make_motion, motion_to_daz, resample_motion

BONES = [(c, p) for c, p in enumerate(sk.PARENTS) if p >= 0]


def bone_dirs(m):
    g, p = sk.forward_kinematics(m.local_rot.astype(np.float64), m.root_pos.astype(np.float64), m.offsets)
    d = np.stack([p[:, c] - p[:, q] for c, q in BONES], 1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True), g, p


def angle_deg(a, b):
    return np.degrees(np.arccos(np.clip(np.sum(a * b, -1), -1, 1)))


@pytest.mark.parametrize("kind", KINDS)
def test_daz_bvh_roundtrip_reproduces_world_directions(kind):
    m = make_motion(kind, 2.0, seed=11)
    text = bvh.format_bvh(motion_to_daz(m), order="ZXY", decimals=4)   # CMU precision
    m2 = rt.to_smpl_motion(bvh.parse_bvh(text), "x", 1)
    assert m2.fps == 60 and m2.num_frames == m.num_frames
    d1, g1, p1 = bone_dirs(m)
    d2, g2, p2 = bone_dirs(m2)
    assert angle_deg(d1, d2).max() < 0.05
    # sensor bones: the full orientation, not only the direction
    assert np.degrees(sk.angle_between_rots(g1[:, se.sensor_joints()], g2[:, se.sensor_joints()])).max() < 0.05
    # positions: same shape up to the uniform scale of the skeleton
    s = m2.offsets[4, 1] / m.offsets[4, 1]
    rel1 = p1 - p1[:, :1]
    rel2 = (p2 - p2[:, :1]) / s
    assert np.abs(rel1 - rel2).max() < 1e-3


def test_24fps_and_12fps_clips_resample_to_60hz_keeping_duration():
    m = make_motion("walk", 3.0, seed=2)
    for fps in (24.0, 12.0):
        low = resample_motion(m, fps)
        clip = bvh.parse_bvh(bvh.format_bvh(motion_to_daz(low)))
        assert clip.frame_time == pytest.approx(1 / fps, abs=1e-6)
        out = rt.to_smpl_motion(clip)
        src_dur = (clip.num_frames - 1) * clip.frame_time
        assert abs((out.num_frames - 1) / 60 - src_dur) < 1 / 60
        # frames at common instants (every 5 / 2.5 frames) equal the source
        d1, _, _ = bone_dirs(m)
        d2, _, _ = bone_dirs(out)
        k = 5
        assert angle_deg(d1[::k][: len(d2[::k])], d2[::k]).max() < 0.05
        # in between, slerp stays close to the true motion (smooth input)
        n = out.num_frames
        assert np.median(angle_deg(d1[:n], d2)) < 1.5


def test_resample_slerps_constant_rotation():
    dt = 1 / 24
    t = np.arange(25) * dt
    rot = sk.rot_axis("y", 2.0 * t)[:, None]                 # 2 rad/s, one joint
    root = np.stack([t, np.zeros_like(t), np.zeros_like(t)], -1)
    r, p = rt.resample(rot, root, dt, 60)
    assert r.shape[0] == 61
    tt = np.arange(61) / 60
    assert np.allclose(r[:, 0], sk.rot_axis("y", 2.0 * tt), atol=1e-9)
    assert np.allclose(p[:, 0], tt)


def test_tpose_maps_to_identity():
    # a Daz-named skeleton whose bones lie exactly along our T-pose directions: its rest pose is a
    # true T-pose and must give identity everywhere
    t = daz_template()
    o = sk.DEFAULT_OFFSETS * 100
    name_to_ours = {"abdomen": 3, "chest": 6, "neck": 12, "head": 15, "lShldr": 16, "lForeArm": 18,
                    "lHand": 20, "rShldr": 17, "rForeArm": 19, "rHand": 21, "lShin": 4, "lFoot": 7,
                    "rShin": 5, "rFoot": 8}
    for n, j in name_to_ours.items():
        t.offsets[t.index(n)] = o[j]
    t.offsets[t.index("neck")] = o[9] + o[12]
    t.offsets[t.index("lCollar")] = o[9] + o[13]
    t.offsets[t.index("rCollar")] = o[9] + o[14]
    t.offsets[t.index("lThigh")] = (0, 0, 0)
    t.offsets[t.index("lButtock")] = o[1]
    t.offsets[t.index("rThigh")] = (0, 0, 0)
    t.offsets[t.index("rButtock")] = o[2]
    t.end_sites[t.index("lFoot")] = o[10]
    t.end_sites[t.index("rFoot")] = o[11]
    t.end_sites[t.index("lHand")] = o[22]
    t.end_sites[t.index("rHand")] = o[23]
    t.rotations = np.tile(np.eye(3), (3, len(t.joints), 1, 1))
    t.root_pos = np.tile([0, 93.0, 0], (3, 1))
    m = rt.to_smpl_motion(t)
    assert np.degrees(sk.angle_between_rots(m.local_rot, np.eye(3))).max() < 1e-4
    # leg height = hip joints above the lowest foot point (the ball joint, 2 cm above our sole)
    scale = (0.87 - sk.BALL_HEIGHT) / 0.87
    assert m.offsets[0, 1] == pytest.approx(0.93 * scale, abs=1e-5)
    assert m.root_pos[0, 1] == pytest.approx(0.93 * scale, abs=1e-5)         # soles on the floor


def test_cmu_rest_pose_keeps_its_arm_directions():
    # the Daz rest pose (all zero) has arms a few degrees forward and elbows bent ~17 deg: our
    # skeleton must reproduce those world directions, and joints with no direction stay identity
    t = daz_template()
    t.rotations = np.tile(np.eye(3), (1, len(t.joints), 1, 1))
    t.root_pos = np.array([[0.0, 90.0, 0.0]])
    m = rt.to_smpl_motion(t)
    d, g, p = bone_dirs(m)
    rest = t.rest_positions()
    want = rest[t.index("lHand")] - rest[t.index("lForeArm")]
    got = p[0, 20] - p[0, 18]
    assert angle_deg(got / np.linalg.norm(got), want / np.linalg.norm(want)) < 1e-4
    assert angle_deg(got / np.linalg.norm(got), np.array([1.0, 0, 0])) > 10
    for j in (0, 15):                                            # pelvis, head: global copies
        assert np.allclose(g[0, j], np.eye(3), atol=1e-6)
    for j in (9, 10, 11, 13, 14, 22, 23):                        # identity locals
        assert np.allclose(m.local_rot[0, j], np.eye(3), atol=1e-6)


def test_units_scale_and_floor():
    m = make_motion("squat", 2.0, seed=3)
    clip = motion_to_daz(m)
    leg_cm = rt.source_leg_height(clip, rt.SOURCES["daz"])
    out = rt.to_smpl_motion(clip)
    assert out.offsets[0, 1] == pytest.approx(sk.DEFAULT_OFFSETS[0, 1] * leg_cm / 100 / 0.87, rel=1e-5)
    g, p = sk.forward_kinematics(out.local_rot.astype(np.float64), out.root_pos, out.offsets)
    assert rt.sole_points(g, p, out.offsets)[..., 1].min() == pytest.approx(0, abs=1e-5)
    lifted = motion_to_daz(m)
    lifted.root_pos = lifted.root_pos + [0, 50, 0]             # a clip whose floor is not at 0
    out2 = rt.to_smpl_motion(lifted)
    assert np.allclose(out2.root_pos, out.root_pos, atol=1e-5)
    assert 0.85 < np.median(out.root_pos[:5, 1]) < 0.95          # standing start, metres


def test_elbow_reversed_repair():
    m = make_motion("arm_swing", 2.0, seed=4)
    clip = motion_to_daz(m)
    for side, name, j in (("L", "lForeArm", 20), ("R", "rForeArm", 21)):
        rev = motion_to_daz(m)
        e = rev.index(name)
        rev.rotations[:, e] = np.swapaxes(rev.rotations[:, e], -1, -2)
        good = rt.to_smpl_motion(clip)
        bad = rt.to_smpl_motion(rev)
        fixed = rt.to_smpl_motion(rev, elbow_reversed=side)
        _, _, pg = bone_dirs(good)
        _, _, pb = bone_dirs(bad)
        _, _, pf = bone_dirs(fixed)
        assert np.abs(pf - pg).max() < 1e-5
        assert np.linalg.norm(pb[:, j] - pg[:, j], axis=-1).max() > 0.05      # wrist moved > 5 cm
    with pytest.raises(ValueError):
        rt.to_smpl_motion(clip, elbow_reversed="X")


def _cgspeed_template():
    # cgspeed-style names, ZYX channels, CMU ASF units (~1/0.45 inch), legs splayed at rest
    J = [("Hips", None, (0, 0, 0), None),
         ("LHipJoint", "Hips", (0, 0, 0), None), ("LeftUpLeg", "LHipJoint", (1.6, -1.8, 0.7), None),
         ("LeftLeg", "LeftUpLeg", (2.4, -6.6, 0)), ("LeftFoot", "LeftLeg", (2.5, -7.0, 0)),
         ("LeftToeBase", "LeftFoot", (0.15, -0.4, 1.9), (0, 0, 1.0)),
         ("RHipJoint", "Hips", (0, 0, 0), None), ("RightUpLeg", "RHipJoint", (-1.6, -1.8, 0.7), None),
         ("RightLeg", "RightUpLeg", (-2.4, -6.6, 0)), ("RightFoot", "RightLeg", (-2.5, -7.0, 0)),
         ("RightToeBase", "RightFoot", (-0.15, -0.4, 1.9), (0, 0, 1.0)),
         ("LowerBack", "Hips", (0, 0.05, -0.2)), ("Spine", "LowerBack", (0, 2.0, 0.05)),
         ("Spine1", "Spine", (0, 2.0, 0.0)), ("Neck", "Spine1", (0, 1.7, 0)), ("Neck1", "Neck", (0, 1.6, 0)),
         ("Head", "Neck1", (0, 1.6, 0), (0, 1.5, 0)),
         ("LeftShoulder", "Spine1", (0, 0, 0)), ("LeftArm", "LeftShoulder", (3.0, 0.5, 0)),
         ("LeftForeArm", "LeftArm", (5.0, 0, 0)), ("LeftHand", "LeftForeArm", (3.5, 0, 0)),
         ("LeftFingerBase", "LeftHand", (0.7, 0, 0), (0.5, 0, 0)),
         ("RightShoulder", "Spine1", (0, 0, 0)), ("RightArm", "RightShoulder", (-3.0, 0.5, 0)),
         ("RightForeArm", "RightArm", (-5.0, 0, 0)), ("RightHand", "RightForeArm", (-3.5, 0, 0)),
         ("RightFingerBase", "RightHand", (-0.7, 0, 0), (-0.5, 0, 0))]
    J = [j + (None,) * (4 - len(j)) for j in J]
    names = [j[0] for j in J]
    parents = [-1 if j[1] is None else names.index(j[1]) for j in J]
    # fix the shoulder offsets so the collar bones have a direction (Spine1 -> LeftShoulder)
    offs = np.array([j[2] for j in J], dtype=np.float64)
    offs[names.index("LeftShoulder")] = (0.5, 1.2, 0)
    offs[names.index("RightShoulder")] = (-0.5, 1.2, 0)
    ends = {i: np.array(j[3], dtype=np.float64) for i, j in enumerate(J) if j[3] is not None}
    ch = [["Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation"]] + \
        [["Zrotation", "Yrotation", "Xrotation"]] * (len(J) - 1)
    return bvh.BvhClip(names, parents, offs, ch, 1 / 120, np.tile(np.eye(3), (1, len(J), 1, 1)),
                       np.zeros((1, 3)), ends, None)


def test_cgspeed_naming_roundtrip():
    m = make_motion("walk", 2.0, seed=6)
    tpl = _cgspeed_template()
    assert rt.detect_source(tpl.joints).kind == "cgspeed"
    src = rt.to_source_clip(m, tpl)
    back = rt.to_smpl_motion(bvh.parse_bvh(bvh.format_bvh(src, order="ZYX")))
    plan = rt._plan(tpl)
    assert plan.unit == pytest.approx(0.0254 / 0.45)
    d1, g1, _ = bone_dirs(m)
    d2, g2, _ = bone_dirs(back)
    assert angle_deg(d1, d2).max() < 0.05
    assert 0.8 < back.offsets[0, 1] / sk.DEFAULT_OFFSETS[0, 1] < 1.0


def test_smpl_bvh_roundtrip():
    m = make_motion("mixed", 2.0, seed=8)
    clip = rt.from_smpl_motion(m)
    assert clip.joints[0] == "pelvis" and set(clip.joints) == set(sk.JOINT_NAMES)
    back = rt.to_smpl_motion(bvh.parse_bvh(bvh.format_bvh(clip)), floor=False)
    assert np.degrees(sk.angle_between_rots(back.local_rot, m.local_rot)).max() < 0.01
    assert np.abs(back.root_pos - m.root_pos).max() < 1e-4
    assert np.allclose(back.offsets, m.offsets, atol=1e-5)


def test_unknown_skeleton_rejected():
    with pytest.raises(ValueError):
        rt.detect_source(["root", "a", "b"])


def _scaled_offsets(text, factor):
    return re.sub(r"OFFSET ([^\n]*)",
                  lambda m: "OFFSET " + " ".join(f"{float(v) * factor:g}" for v in m.group(1).split()), text)


def _root_x_of_frame(text, frame, value):
    lines = text.split("\n")
    k = lines.index("MOTION") + 3 + frame
    lines[k] = " ".join([value] + lines[k].split()[1:])
    return "\n".join(lines)


_DAZ_TEXT = bvh.format_bvh(motion_to_daz(make_motion("walk", 1.0, seed=4)), order="ZXY", decimals=4)

UNUSABLE = {
    "no_left_foot": (_DAZ_TEXT.replace("lFoot", "lFootX"), "the daz skeleton lacks lFoot"),
    "unknown_names": (_DAZ_TEXT.replace("lThigh", "leftThigh"), "unknown source skeleton"),
    "offsets_x1000": (_scaled_offsets(_DAZ_TEXT, 1000), "cannot infer units from a leg height of 8"),
    "offsets_zero": (_scaled_offsets(_DAZ_TEXT, 0), "cannot infer units from a leg height of 0.000"),
    "end_site_zero": (re.sub(r"(End Site\s*\{\s*OFFSET)[^\n]*", r"\1 0 0 0", _DAZ_TEXT),
                      r"the bone \w+ -> End Site has zero length"),
    "no_frames": (_DAZ_TEXT[:_DAZ_TEXT.index("Frames:")] + "Frames: 0\nFrame Time: 0.0416667\n",
                  r"the clip has no frames"),
    "root_1e300": (_root_x_of_frame(_DAZ_TEXT, 3, "1e300"), r"frame 4: the hips are 1e\+298 m from the origin"),
}


@pytest.mark.parametrize("case", sorted(UNUSABLE))
def test_a_clip_retargeting_cannot_use_is_refused_naming_the_file(tmp_path, case):
    """A BvhError (one line from the CLI) naming the file and the problem: never a bare
    ValueError from deep inside, and never NaN or inf motion."""
    text, problem = UNUSABLE[case]
    path = tmp_path / f"{case}.bvh"
    path.write_text(text)
    clip = bvh.read_bvh(path)
    with pytest.raises(bvh.BvhError, match=rf"^{re.escape(str(path))}: {problem}"):
        rt.to_smpl_motion(clip)


def test_resampling_refuses_an_implausible_frame_time():
    m = make_motion("walk", 1.0, seed=4)
    # 60 s per source frame would be 3600 output frames per frame: refused before allocating
    with pytest.raises(ValueError, match="frame time 60.0 s"):
        rt.resample(m.local_rot[:3], m.root_pos[:3], 60.0)
