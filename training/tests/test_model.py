"""PoseNet (training/model.py): contract shapes, causality/streaming, in-graph normalisation."""
import numpy as np
import pytest
import torch

from training import procedural, sensors as se, skeleton as sk, synthesis as sy
from training.model import (MirrorEnsemble, ModelConfig, PoseNet, STATE_LAYERS,
                            STATE_SIZE, count_parameters,
                            forward_kinematics_torch, gram_schmidt, heading_rotation)

SMALL = ModelConfig(64, 64, 2, 64)


def _inputs(seconds=1.0, kinds=("walk", "turn"), seed=0):
    o, a = [], []
    for i, k in enumerate(kinds):
        s = sy.synthesize(procedural.make_motion(k, seconds=seconds, seed=seed + i))
        o.append(s.imu_orientation)
        a.append(s.imu_acceleration)
    return torch.from_numpy(np.stack(o)), torch.from_numpy(np.stack(a))


def _trained_like(cfg=SMALL, seed=0):
    """Random weights with a non-negligible output layer (the real init is near the rest pose)."""
    torch.manual_seed(seed)
    net = PoseNet(cfg).eval()
    with torch.no_grad():
        net.head[-1].weight.normal_(0, 0.3)
    return net


def test_default_size_and_state_constants():
    net = PoseNet()
    n = count_parameters(net)
    assert 1_000_000 < n <= 4_000_000
    assert (net.state_layers, net.state_size) == (STATE_LAYERS, STATE_SIZE)


def test_shapes_and_valid_rotations():
    net = _trained_like()
    o, a = _inputs()
    rot, vel, con, (h, c) = net(o, a)
    B, T = o.shape[:2]
    assert rot.shape == (B, T, 24, 3, 3) and vel.shape == (B, T, 3) and con.shape == (B, T, 2)
    assert h.shape == (SMALL.layers, B, SMALL.hidden) and c.shape == h.shape
    eye = torch.eye(3).expand_as(rot)
    assert torch.allclose(rot.transpose(-1, -2) @ rot, eye, atol=1e-5)
    assert torch.allclose(torch.det(rot), torch.ones(B, T, 24), atol=1e-5)
    assert float(con.min()) >= 0 and float(con.max()) <= 1


def test_untrained_default_outputs_rest_pose_and_measured_pelvis():
    torch.manual_seed(0)
    net = PoseNet(SMALL).eval()
    o, a = _inputs()
    rot, vel, con, _ = net(o, a)
    assert float((rot[:, :, 1:] - torch.eye(3)).abs().max()) < 0.05
    assert float((rot[:, :, 0] - o[:, :, 0]).abs().max()) < 0.05


def _streamed(net, o, a):
    """One call per frame with the state carried, as the engine runs: the (rotation, velocity,
    contact) series over the clip and the last state."""
    state, parts = None, []
    with torch.no_grad():
        for t in range(o.shape[1]):
            r, v, c, state = net(o[:, t:t + 1], a[:, t:t + 1], state)
            parts.append((r, v, c))
    return tuple(torch.cat([p[i] for p in parts], dim=1) for i in range(3)), state


def _assert_streaming_equals_whole(net, o, a):
    """Frame by frame equals the whole clip in one call: (whole clip's outputs, streamed state)."""
    with torch.no_grad():
        whole = net(o, a)
    streamed, state = _streamed(net, o, a)
    for i in range(3):
        assert torch.allclose(streamed[i], whole[i], atol=1e-5)
    return whole, state


def test_streaming_equals_whole_clip():
    o, a = _inputs(seconds=0.5)
    whole, state = _assert_streaming_equals_whole(_trained_like(), o, a)
    assert torch.allclose(state[0], whole[3][0], atol=1e-5)


def _assert_causal(net, o, a, at: int = 20):
    """A change of the input from frame `at` on leaves the output before it as it was and changes
    the output after it; returns the unchanged input's rotations."""
    a2 = a.clone()
    a2[:, at:] += 5.0
    with torch.no_grad():
        r1 = net(o, a)[0]
        r2 = net(o, a2)[0]
    assert torch.allclose(r1[:, :at], r2[:, :at])
    assert not torch.allclose(r1[:, at:], r2[:, at:])
    return r1


def test_causal_future_does_not_change_the_past():
    _assert_causal(_trained_like(), *_inputs(seconds=0.5))


def _ry(angle):
    return torch.from_numpy(sy._ry(angle).astype(np.float32))


@pytest.mark.parametrize("mirror_averaged", [False, True])
@pytest.mark.parametrize("yaw", [0.7, -2.5, 3.1])
def test_heading_equivariance(yaw, mirror_averaged):
    """Yawing the whole body: local joints unchanged, pelvis and velocity rotate with it."""
    net = MirrorEnsemble(_trained_like()).eval() if mirror_averaged else _trained_like()
    o, a = _inputs()
    ry = _ry(yaw)
    o2 = ry @ o
    a2 = (ry @ a.unsqueeze(-1)).squeeze(-1)
    with torch.no_grad():
        r1, v1, c1, _ = net(o, a)
        r2, v2, c2, _ = net(o2, a2)
    assert torch.allclose(r2[:, :, 1:], r1[:, :, 1:], atol=1e-4)
    assert torch.allclose(r2[:, :, 0], ry @ r1[:, :, 0], atol=1e-4)
    assert torch.allclose(v2, (ry @ v1.unsqueeze(-1)).squeeze(-1), atol=1e-4)
    assert torch.allclose(c2, c1, atol=1e-4)


def test_heading_rotation_matches_atan2_and_survives_lying_down():
    rng = np.random.default_rng(0)
    yaw = rng.uniform(-np.pi, np.pi, 50)
    pitch = rng.uniform(-1.2, 1.2, 50)
    mats = np.stack([sy._ry(y) @ sk.rot_axis("x", p) for y, p in zip(yaw, pitch)]).astype(np.float32)
    h = heading_rotation(torch.from_numpy(mats)).numpy()
    ref = np.stack([sy._ry(y) for y in yaw])
    assert np.allclose(h, ref, atol=1e-4)
    # lying on the back (forward axis straight up): finite and still a yaw rotation
    lying = torch.from_numpy((sy._ry(0.4) @ sk.rot_axis("x", -np.pi / 2)).astype(np.float32))
    hl = heading_rotation(lying)
    assert torch.isfinite(hl).all()
    assert torch.allclose(hl.T @ hl, torch.eye(3), atol=1e-5)
    assert abs(float(hl[1, 1]) - 1.0) < 1e-6


def test_heading_flips_only_where_the_model_card_says():
    # The model card's Limits: pitched forward or back, the heading stays put until the pelvis is
    # tipped arccos((1 - sqrt 5) / 2) = 128.2 deg, flips there, and is defined upside down.
    pitch = np.radians(np.arange(-179.5, 180.0, 0.5))
    mats = np.stack([sy._ry(0.7) @ sk.rot_axis("x", p) for p in pitch]).astype(np.float32)
    h = heading_rotation(torch.from_numpy(mats)).numpy()
    facing = h[:, 2, 2] * np.cos(0.7) + h[:, 0, 2] * np.sin(0.7)   # cos(heading - 0.7)
    singular = np.degrees(np.arccos((1 - np.sqrt(5)) / 2))
    inside = np.abs(np.degrees(pitch)) < singular
    assert np.all(facing[inside] > 0.999)
    assert np.all(facing[~inside] < -0.999)
    assert abs(singular - 128.17) < 0.01


def test_rot6d_round_trip():
    r = torch.from_numpy(sk.random_rotations(100, np.random.default_rng(1)).astype(np.float32))
    assert torch.allclose(gram_schmidt(r[..., :2]), r, atol=1e-5)
    # Gram-Schmidt turns any (non-degenerate) 6D vector, two columns, into a rotation
    m = gram_schmidt(torch.randn(100, 3, 2))
    assert torch.allclose(torch.det(m), torch.ones(100), atol=1e-5)


def test_torch_fk_matches_skeleton_fk():
    m = procedural.make_motion("mixed", seconds=1.0, seed=2)
    g, p = sk.forward_kinematics(m.local_rot, m.root_pos, m.offsets)
    gt, pt = forward_kinematics_torch(torch.from_numpy(m.local_rot), torch.from_numpy(m.offsets), sk.PARENTS)
    assert np.allclose(gt.numpy(), g, atol=1e-5)
    assert np.allclose(pt.numpy(), p - p[:, :1], atol=1e-5)


def test_dropout_acts_in_training_only_and_can_change_on_a_warm_start():
    net = _trained_like()
    o, a = _inputs(seconds=0.5)
    with torch.no_grad():
        ref = net(o, a)[0]
        net.set_dropout(0.3)
        assert net.config.dropout == 0.3 and net.lstm.dropout == 0.3
        assert SMALL.dropout == 0.0          # the shared size preset is not edited
        assert torch.equal(net(o, a)[0], ref)                 # eval: dropout is off
        net.train()
        d1, d2 = net(o, a)[0], net(o, a)[0]
        net.eval()
    assert not torch.allclose(d1, d2) and not torch.allclose(d1, ref)
    # same weights (dropout has none): state dicts load across dropout settings
    other = PoseNet(SMALL)
    other.load_state_dict(net.state_dict())
    with torch.no_grad():
        assert torch.equal(other.eval()(o, a)[0], ref)


def test_anchored_sensor_bones_start_at_their_measured_orientations():
    net = _trained_like()
    net.enable_anchoring()
    assert net.config.anchored and not SMALL.anchored
    m = procedural.make_motion("walk", seconds=1.0, seed=3)
    s = sy.synthesize(m, np.random.default_rng(0), sy.Augmentation(mirror=0.0, speed=(1.0, 1.0)))
    o, a = torch.from_numpy(s.imu_orientation[None]), torch.from_numpy(s.imu_acceleration[None])
    with torch.no_grad():
        rot = net(o, a)[0][0].double().numpy()
    g, _ = sk.forward_kinematics(rot, np.zeros((rot.shape[0], 3)), sk.DEFAULT_OFFSETS)
    assert net.anchor_joints == se.sensor_joints()
    for si, j in enumerate(se.sensor_joints()[1:], start=1):
        err = np.degrees(sk.angle_between_rots(g[:, j], s.imu_orientation[:, si].astype(np.float64)))
        assert err.max() < 1e-3, (j, err.max())
    # the residual is live: other output weights move the sensor bones off the measurement
    with torch.no_grad():
        net.head[-1].bias[15 * 6:16 * 6].add_(0.3)
        moved = net(o, a)[0][0].double().numpy()
    g2, _ = sk.forward_kinematics(moved, np.zeros((rot.shape[0], 3)), sk.DEFAULT_OFFSETS)
    assert np.degrees(sk.angle_between_rots(g2[:, 15], g[:, 15])).min() > 1.0


def _anchored_bone_by_bone(net, rot, cols, rg, mask):
    """The anchoring's definition, one bone at a time: forward kinematics of every joint, then
    each sensor bone re-predicted as its residual columns on parent_global^T R_sensor (the rest
    pose where its sensor is missing), orthonormalised by the numpy Gram-Schmidt."""
    glob = [rot[:, :, 0]]
    for j in range(1, 24):
        glob.append(glob[sk.PARENTS[j]] @ rot[:, :, j])
    out = rot.clone()
    for s, j in enumerate(net.anchor_joints):
        if j == 0:
            continue
        measured = (glob[sk.PARENTS[j]].transpose(-1, -2) @ rg[:, :, s])[..., :2]
        if mask is not None:
            present = mask[:, :, s, None, None]
            measured = measured * present + torch.eye(3)[:, :2] * (1 - present)
        c = (cols[:, :, j] + measured).double().numpy()
        out[:, :, j] = torch.from_numpy(sk.rot6d_to_matrix(np.concatenate([c[..., 0], c[..., 1]], -1)))
    return out


@pytest.mark.parametrize("sensors,wrist,masked", [(se.DEFAULT_SENSORS, "hand", False),
                                                  (se.DEFAULT_SENSORS, "forearm", False),
                                                  (se.DEFAULT_SENSORS + ("chest",), "hand", True)])
def test_batched_anchoring_equals_the_bone_by_bone_definition(sensors, wrist, masked):
    cfg = ModelConfig(64, 64, 2, 64, anchored=True, wrist_anchor=wrist, sensors=sensors,
                      optional=("chest",) if masked else (), masked=masked)
    net = PoseNet(cfg)
    g = torch.Generator().manual_seed(len(sensors))
    b, t, n = 2, 5, len(sensors)
    rot = torch.from_numpy(sk.rot6d_to_matrix(torch.randn(b, t, 24, 6, generator=g).double().numpy())).float()
    rg = torch.from_numpy(sk.rot6d_to_matrix(torch.randn(b, t, n, 6, generator=g).double().numpy())).float()
    cols = 0.3 * torch.randn(b, t, 24, 3, 2, generator=g)
    mask = (torch.rand(b, t, n, generator=g) > 0.4).float() if masked else None
    columns, joints = net._anchor_sensor_bones(rot, cols, rg, mask)
    assert sorted(joints) == sorted(j for j in net.anchor_joints if j != 0)
    assert columns.shape == (b, t, len(joints), 3, 2)     # orthonormalised once, with every joint
    anchored = gram_schmidt(columns)
    want = _anchored_bone_by_bone(net, rot, cols, rg, mask)
    assert torch.allclose(anchored, want[:, :, joints], atol=1e-5)
    assert (anchored - rot[:, :, joints]).abs().max() > 0.1     # it did re-predict them
    if masked:                                                  # and a missing sensor mattered
        assert mask.min() == 0 and mask.max() == 1


def test_hand_anchored_checkpoint_moves_its_wrist_anchoring_to_the_forearm():
    # A checkpoint config from before wrist_anchor existed means a hand-anchored network.
    assert ModelConfig.from_dict({**SMALL.to_dict(), "unknown_key": 1}) == SMALL
    legacy = {k: v for k, v in SMALL.to_dict().items() if k != "wrist_anchor"}
    assert ModelConfig.from_dict({**legacy, "anchored": True}).wrist_anchor == "hand"
    assert ModelConfig.from_dict({**legacy, "wrist_anchor": "forearm"}).wrist_anchor == "forearm"
    net = _trained_like(ModelConfig.from_dict(legacy))
    net.enable_anchoring()                               # zero residuals: hands = wrist sensors
    assert net.anchor_joints[1:3] == [20, 21]
    m = procedural.make_motion("mixed", seconds=1.0, seed=5)
    s = sy.synthesize(m, np.random.default_rng(0), sy.Augmentation(mirror=0.0, speed=(1.0, 1.0)))
    o, a = torch.from_numpy(s.imu_orientation[None]), torch.from_numpy(s.imu_acceleration[None])
    wrist_sensors = s.imu_orientation[:, 1:3].astype(np.float64)

    def globals_now():
        with torch.no_grad():
            rot = net(o, a)[0][0].double().numpy()
        return sk.forward_kinematics(rot, np.zeros((rot.shape[0], 3)), sk.DEFAULT_OFFSETS)[0]

    g = globals_now()
    assert np.degrees(sk.angle_between_rots(g[:, 20:22], wrist_sensors)).max() < 1e-3   # hands
    net.anchor_wrists_on_forearm()
    assert net.config.wrist_anchor == "forearm" and net.anchor_joints == se.sensor_bones("forearm")
    g = globals_now()
    assert np.degrees(sk.angle_between_rots(g[:, 18:20], wrist_sensors)).max() < 1e-3   # forearms
    # the wrist rows start at rest, the other joints keep their outputs
    np.testing.assert_allclose(g[:, 20:22], g[:, 18:20], atol=1e-5)
    net.anchor_wrists_on_forearm()                                  # a second call changes nothing
    np.testing.assert_allclose(globals_now(), g, atol=1e-6)


def test_anchored_network_streams_and_stays_heading_equivariant():
    net = _trained_like()
    net.enable_anchoring()
    with torch.no_grad():
        net.head[-1].weight.normal_(0, 0.3)
    o, a = _inputs(seconds=0.5)
    assert torch.allclose(_streamed(net, o, a)[0][0], net(o, a)[0].detach(), atol=1e-5)
    with torch.no_grad():
        whole = net(o, a)
        yaw = torch.from_numpy(sk.rot_axis("y", 0.8).astype(np.float32))
        turned = net(yaw @ o, (yaw @ a.unsqueeze(-1)).squeeze(-1))[0]
    assert torch.allclose(turned[:, :, 1:], whole[0][:, :, 1:], atol=1e-4)
    assert torch.allclose(turned[:, :, 0], yaw @ whole[0][:, :, 0], atol=1e-4)


def _mirrored(o, a):
    m = torch.diag(torch.tensor([-1.0, 1.0, 1.0]))
    return m, m @ o[:, :, se.mirror_indices()] @ m, a[:, :, se.mirror_indices()] @ m


def _anchored_pair():
    """An anchored network with a visible output layer, and its mirror-averaged pair."""
    net = _trained_like()
    net.enable_anchoring()
    with torch.no_grad():
        net.head[-1].weight.normal_(0, 0.3)
    return net, MirrorEnsemble(net).eval()


def test_mirror_ensemble_is_exactly_mirror_equivariant_where_the_single_network_is_not():
    """The same motion performed mirror-image must give the mirror-image pose, left and right
    swapped: this fails for a wrong sensor swap, joint swap, reflection or contact order."""
    net, ens = _anchored_pair()
    o, a = _inputs(seconds=0.5)
    m, om, am = _mirrored(o, a)
    with torch.no_grad():
        r, v, c, _ = ens(o, a)
        rm, vm, cm, _ = ens(om, am)
        single, single_m = net(o, a)[0], net(om, am)[0]
    assert torch.allclose(m @ rm[:, :, sk.MIRROR_JOINTS] @ m, r, atol=1e-5)
    assert torch.allclose(vm @ m, v, atol=1e-5)
    assert torch.allclose(cm.flip(-1), c, atol=1e-6)
    # a random single network is not symmetric: the ensemble's symmetry is its own doing
    assert (m @ single_m[:, :, sk.MIRROR_JOINTS] @ m - single).abs().max() > 1e-2
    # and its answer lies between the two branches': valid rotations, not either branch alone
    eye = torch.eye(3).expand_as(r)
    assert torch.allclose(r.transpose(-1, -2) @ r, eye, atol=1e-5)
    assert torch.allclose(torch.linalg.det(r), torch.ones(r.shape[:-2]), atol=1e-5)
    assert (r - single).abs().max() > 1e-3


def test_the_pair_averages_each_branchs_unit_columns_before_one_gram_schmidt():
    """The ensemble's rule, from its parts: each branch's answer is the Gram-Schmidt of its
    columns (forward_raw = gram_schmidt(forward_columns)); the pair sums both branches' columns
    scaled to unit length, the mirrored one reflected back with its joints swapped, and
    orthonormalises once. A rule on the branches' rotations instead (or no scaling) differs."""
    net, ens = _anchored_pair()
    o, a = _inputs(seconds=0.5)
    m, om, am = _mirrored(o, a)
    with torch.no_grad():
        r = ens(o, a)[0]
        cols, cols_m = net.forward_columns(o, a)[0], net.forward_columns(om, am)[0]
        assert torch.allclose(net(o, a)[0], gram_schmidt(cols), atol=1e-6)
    unit = cols / cols.norm(dim=-2, keepdim=True)
    back = m @ (cols_m / cols_m.norm(dim=-2, keepdim=True))[:, :, sk.MIRROR_JOINTS] @ m[:2, :2]
    assert torch.allclose(r, gram_schmidt(unit + back), atol=1e-5)
    rotations = gram_schmidt(cols) + (m @ gram_schmidt(cols_m) @ m)[:, :, sk.MIRROR_JOINTS]
    assert (r - gram_schmidt(rotations[..., :2])).abs().max() > 1e-4
    unscaled = cols + m @ cols_m[:, :, sk.MIRROR_JOINTS] @ m[:2, :2]
    assert (r - gram_schmidt(unscaled)).abs().max() > 1e-4


def test_mirror_ensemble_streams_with_a_doubled_state_and_keeps_the_weights():
    net = _trained_like()
    ens = MirrorEnsemble(net).eval()
    assert (ens.state_layers, ens.state_size) == (net.state_layers, 2 * net.state_size)
    assert count_parameters(ens) == count_parameters(net)
    o, a = _inputs(seconds=0.5)
    streamed, state = _streamed(ens, o, a)
    with torch.no_grad():
        whole = ens(o, a)
        # the state halves are the two branches' own LSTM states
        _, _, _, (h_plain, _) = net(o, a)
        _, om, am = _mirrored(o, a)
        _, _, _, (h_mirror, _) = net(om, am)
    assert state[0].shape == (net.state_layers, o.shape[0], 2 * net.state_size)
    for i in range(3):
        assert torch.allclose(streamed[i], whole[i], atol=1e-5)
    assert torch.allclose(whole[3][0][..., :net.state_size], h_plain, atol=1e-5)
    assert torch.allclose(whole[3][0][..., net.state_size:], h_mirror, atol=1e-5)
