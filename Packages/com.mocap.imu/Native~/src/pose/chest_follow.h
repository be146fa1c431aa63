/* The spine turned towards a chest sensor. A network that reads a chest sensor still leaves the
 * chest bone about 7 deg from what the sensor reports (the other sensors' bones: 3-4 deg), and
 * on the training people the positions were best with the chest turned half of that way: the
 * sensor has its own mounting error, so neither side is the truth. The turn is shared by the
 * back as the training motion bends it: spine1 takes two thirds and spine2 the rest, while
 * spine3 keeps its bend from spine2 (the motion the network learnt from has two back joints, so
 * its spine3 never bends on its own, and an even split made spine3 turn faster than any of the
 * training people's did). The same split scored best on the training people. The neck and collars
 * move with the chest, while the head and the upper arms keep the global orientation the network
 * gave them (their own sensors and the wrists' speak for them, not the chest).
 * Pure and allocation-free; unit-tested in tests/test_chest_follow.cpp; the same rule in numpy is
 * training's chest_follow.follow_chest. */
#ifndef MOCAP_CHEST_FOLLOW_H
#define MOCAP_CHEST_FOLLOW_H

#ifdef __cplusplus
extern "C" {
#endif

/* SMPL-24 joints the rule reads and writes. */
#define CHEST_FOLLOW_PELVIS 0
#define CHEST_FOLLOW_SPINE1 3
#define CHEST_FOLLOW_SPINE2 6
#define CHEST_FOLLOW_SPINE3 9

/* How much of the chest's turn spine1's and spine2's global orientations take (spine3: all). */
#define CHEST_FOLLOW_SPINE1_PART (2.0 / 3.0)
#define CHEST_FOLLOW_SPINE2_PART 1.0

/* q: the pose's rotations (w, x, y, z; joint 0 global, the others local to their parent), turned
 * in place so spine3's global orientation moves `share` (0..1) of the way to `chest` (the chest
 * sensor's bone orientation, unit quaternion, the pose's frame). Returns 0, or -1 (q untouched)
 * for a share outside 0..1 or a chest that is not a finite non-zero quaternion. */
int chest_follow_apply(double (*q)[4], const double chest[4], double share);

#ifdef __cplusplus
}
#endif
#endif
