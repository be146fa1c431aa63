"""How rare each training clip's poses are, so training can show the rare ones more often.

The validation error is highest on kinds of motion the training subjects hold little of
(climbing, bending over heavy objects, moving on all fours), while thousands of frames of
walking and standing teach the network little more. Sampling clips in proportion to their
length repeats that imbalance. `clip_rarity` scores each clip without labels:

  1. every few frames, a pose descriptor that ignores heading and position: the pelvis's up
     axis, and the head, hands and feet relative to the pelvis in the body's heading frame
     (metres divided by the skeleton's leg height). Not the pelvis height: a few CMU clips
     have their floor far off (a jog 2 m up in the air), and boosting those would teach errors;
     lying, crawling and bending show in the limbs around the pelvis anyway;
  2. k-means on those descriptors (standardised) over all clips, with k = 2, 4, 8, ... 64;
  3. a frame's rarity is 1 / (its cluster's share of the frames x k), averaged over the k: 1
     when every cluster is equally common, large for poses few frames share; a clip's rarity is
     the mean over its frames, scaled so that the frame-weighted mean over all clips is 1.

`train --rare-boost A` then draws clips with probability proportional to length x rarity^A
(A = 0: by length alone). Deterministic: the same motions give the same rarities, whatever the
training run's random state (so a resumed run draws as the uninterrupted one).
"""
from __future__ import annotations

import numpy as np

from . import skeleton as sk

DESCRIPTOR_JOINTS = (15, 22, 23, 10, 11)   # head, hands, feet
RARITY_CAP = 10.0                          # no clip is boosted by more than this
MAX_CLUSTERS = 64                          # the CMU training set: ~140,000 descriptors
DESCRIPTORS_PER_CLUSTER = 20


def pose_descriptors(motion: sk.Motion, stride: int = 10) -> np.ndarray:
    """(frames / stride, 18): pelvis up axis (3), head, hands and feet relative to the pelvis in
    the heading frame (15); lengths over the skeleton's leg height (skeleton.leg_height, the
    length skeletons are scaled by)."""
    rot = np.asarray(motion.local_rot[::stride], np.float64)
    g, p = sk.forward_kinematics(rot, np.zeros((len(rot), 3)), np.asarray(motion.offsets, np.float64))
    pelvis = g[:, 0]
    forward = pelvis[:, :, 2]                        # the pelvis's +Z in the world
    heading_inv = sk.rot_axis("y", -np.arctan2(forward[:, 0], forward[:, 2]))
    limbs = np.einsum("tij,tkj->tki", heading_inv, p[:, list(DESCRIPTOR_JOINTS)]) / sk.leg_height(motion.offsets)
    up = np.einsum("tij,tj->ti", heading_inv, pelvis[:, :, 1])
    return np.concatenate([up, limbs.reshape(len(rot), -1)], axis=1)


def kmeans(x: np.ndarray, k: int, rng: np.random.Generator, iterations: int = 25) -> np.ndarray:
    """Cluster labels of the rows of x (k-means++ start, Lloyd iterations)."""
    n = len(x)
    k = min(k, n)
    centres = [x[int(rng.integers(n))]]
    d2 = ((x - centres[0]) ** 2).sum(1)
    for _ in range(1, k):
        total = d2.sum()
        i = int(rng.choice(n, p=d2 / total)) if total > 0 else int(rng.integers(n))
        centres.append(x[i])
        d2 = np.minimum(d2, ((x - x[i]) ** 2).sum(1))
    centres = np.array(centres)
    labels = np.zeros(n, dtype=np.int64)
    x_norm2 = (x * x).sum(1)[:, None]
    for it in range(iterations):
        dist = x_norm2 - 2.0 * x @ centres.T + (centres * centres).sum(1)[None]
        new = dist.argmin(1)
        if it > 0 and np.array_equal(new, labels):
            break
        labels = new
        for c in range(k):
            members = x[labels == c]
            if len(members):
                centres[c] = members.mean(0)
    return labels


def clip_rarity(motions, max_k: int | None = None, stride: int = 10, seed: int = 0) -> np.ndarray:
    """Per clip: the mean rarity of its poses (module docstring), frame-weighted mean 1 over
    the clips; none above RARITY_CAP times that mean before the final rescale.
    A frame's rarity is averaged over clusterings with k = 2, 4, 8, ... max_k (default: one
    cluster per DESCRIPTORS_PER_CLUSTER descriptors, at most MAX_CLUSTERS): one k alone either
    lumps the rare poses in with common ones (small k) or splits everything into clusters that
    are all about as common (large k)."""
    if not motions:
        return np.zeros(0)
    per_clip = [pose_descriptors(m, stride) for m in motions]
    x = np.concatenate(per_clip)
    x = (x - x.mean(0)) / np.maximum(x.std(0), 1e-9)
    if max_k is None:
        max_k = int(np.clip(len(x) // DESCRIPTORS_PER_CLUSTER, 2, MAX_CLUSTERS))
    rng = np.random.default_rng(seed)
    scales = [2 ** e for e in range(1, int(np.log2(max(max_k, 2))) + 1)]
    frame_rarity = np.zeros(len(x))
    for k in scales:
        labels = kmeans(x, k, rng)
        share = np.bincount(labels) / len(labels)
        used = np.count_nonzero(share)
        frame_rarity += 1.0 / (share[labels] * used)
    frame_rarity /= len(scales)
    bounds = np.cumsum([0] + [len(d) for d in per_clip])
    rarity = np.array([frame_rarity[a:b].mean() for a, b in zip(bounds[:-1], bounds[1:])])
    lengths = np.array([m.num_frames for m in motions], np.float64)
    rarity = np.minimum(rarity / (rarity * lengths).sum() * lengths.sum(), RARITY_CAP)
    return rarity / (rarity * lengths).sum() * lengths.sum()
