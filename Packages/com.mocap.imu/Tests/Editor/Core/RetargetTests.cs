using System;
using System.Collections.Generic;
using System.Linq;
using Mocap.Imu.Maths;
using Mocap.Imu.Retarget;
using Mocap.Imu.Skeleton;
using Mocap.Imu.Tests.Maths;
using NUnit.Framework;

namespace Mocap.Imu.Tests.Retarget
{
    /// <summary>
    /// A synthetic Unity-style transform hierarchy (Unity frame, avatar root = identity) with its
    /// own forward kinematics, so retargeting results are checked by posing real transforms rather
    /// than by re-running the retargeter's formulas.
    /// </summary>
    internal sealed class TestRig
    {
        public sealed class Node
        {
            public string Name;
            public int Parent;
            public HumanBone Bone = HumanBone.LastBone;
            public Quat Local;
            public Vec3 LocalPosition;
            public Quat World;
            public Vec3 WorldPosition;
        }

        public readonly List<Node> Nodes = new List<Node>();
        public readonly Dictionary<HumanBone, int> NodeOf = new Dictionary<HumanBone, int>();
        public readonly Dictionary<HumanBone, Quat> TPoseWorld = new Dictionary<HumanBone, Quat>();
        public readonly Dictionary<HumanBone, Vec3> TPosePosition = new Dictionary<HumanBone, Vec3>();

        public bool Has(HumanBone b) => NodeOf.ContainsKey(b);
        public Node this[HumanBone b] => Nodes[NodeOf[b]];

        public void UpdateWorld()
        {
            foreach (Node n in Nodes)
            {
                if (n.Parent < 0)
                {
                    n.World = n.Local;
                    n.WorldPosition = n.LocalPosition;
                }
                else
                {
                    Node p = Nodes[n.Parent];
                    n.World = (p.World * n.Local).Normalized;
                    n.WorldPosition = p.WorldPosition + p.World * n.LocalPosition;
                }
            }
        }

        /// <summary>Turns a node (and with it its subtree) by <paramref name="q"/> in world space.</summary>
        public void RotateWorld(HumanBone bone, Quat q)
        {
            Node n = this[bone];
            Quat parentWorld = Nodes[n.Parent].World;
            n.Local = (parentWorld.Inverse * q * n.World).Normalized;
            UpdateWorld();
        }

        /// <summary>What the Unity glue would read from this rig's current (bind) pose.</summary>
        public HumanoidRig Describe()
        {
            var bones = new List<RigBone>();
            foreach (Node n in Nodes.Where(n => n.Bone != HumanBone.LastBone))
            {
                HumanBone parent = HumanBone.LastBone;
                for (int p = n.Parent; p >= 0; p = Nodes[p].Parent)
                    if (Nodes[p].Bone != HumanBone.LastBone) { parent = Nodes[p].Bone; break; }
                bones.Add(new RigBone(n.Bone, parent, n.Local, n.World, n.WorldPosition));
            }
            // Shuffled on purpose: the description must not depend on the caller's order.
            bones.Reverse();
            return new HumanoidRig(bones);
        }

        public void Apply(RestPoseRetargeter r)
        {
            for (int i = 0; i < r.Rig.Count; i++) Nodes[NodeOf[r.Rig[i].Bone]].Local = r.LocalRotations[i];
            UpdateWorld();
        }
    }

    public enum RigKind
    {
        IdentityTPose,
        RandomRest,
        APose,
        APoseRandomRest,
        MissingUpperChestNeckToes,
        MissingAllOptionalAPose,
    }

    internal static class TestRigs
    {
        public static readonly HumanBone[][] Chains =
        {
            new[] { HumanBone.Hips, HumanBone.Spine, HumanBone.Chest, HumanBone.UpperChest, HumanBone.Neck, HumanBone.Head },
            new[] { HumanBone.LeftShoulder, HumanBone.LeftUpperArm, HumanBone.LeftLowerArm, HumanBone.LeftHand },
            new[] { HumanBone.RightShoulder, HumanBone.RightUpperArm, HumanBone.RightLowerArm, HumanBone.RightHand },
            new[] { HumanBone.LeftUpperLeg, HumanBone.LeftLowerLeg, HumanBone.LeftFoot, HumanBone.LeftToes },
            new[] { HumanBone.RightUpperLeg, HumanBone.RightLowerLeg, HumanBone.RightFoot, HumanBone.RightToes },
        };

        /// <summary>The next bone the rig has along <paramref name="b"/>'s chain, or null.</summary>
        public static HumanBone? ChainEnd(TestRig rig, HumanBone b)
        {
            foreach (HumanBone[] chain in Chains)
            {
                int i = Array.IndexOf(chain, b);
                if (i < 0) continue;
                for (int k = i + 1; k < chain.Length; k++)
                    if (rig.Has(chain[k])) return chain[k];
                return null;
            }
            return null;
        }

        public static TestRig Build(RigKind kind, int seed = 7)
        {
            bool randomFrames = kind == RigKind.RandomRest || kind == RigKind.APoseRandomRest ||
                                kind == RigKind.MissingUpperChestNeckToes || kind == RigKind.MissingAllOptionalAPose;
            bool aPose = kind == RigKind.APose || kind == RigKind.APoseRandomRest || kind == RigKind.MissingAllOptionalAPose;
            bool intermediate = kind == RigKind.RandomRest || kind == RigKind.MissingAllOptionalAPose;
            var missing = new HashSet<HumanBone>();
            if (kind == RigKind.MissingUpperChestNeckToes)
                missing.UnionWith(new[] { HumanBone.UpperChest, HumanBone.Neck, HumanBone.LeftToes, HumanBone.RightToes });
            if (kind == RigKind.MissingAllOptionalAPose)
                missing.UnionWith(HumanoidBoneMap.MappedBones.Where(HumanoidBoneMap.IsOptional));
            return Build(seed, randomFrames, aPose, intermediate, missing);
        }

        public static TestRig Build(int seed, bool randomFrames, bool aPose, bool intermediate, ISet<HumanBone> missing)
        {
            var rng = new Random(seed);
            SmplSkeleton s = SmplSkeleton.Default;

            // T-pose joint positions with SMPL's directions but the rig's own bone lengths (the same
            // on both sides: a lopsided pelvis would be a tilted T-pose).
            var pos = new Vec3[24];
            var lengthScale = new Dictionary<string, float>();
            pos[0] = CoordinateConversion.ModelToUnity(s.RestOffset(0)) * 1.05f;
            for (int j = 1; j < 24; j++)
            {
                string side = SmplSkeleton.NameOf(j).Replace("left_", "").Replace("right_", "");
                if (!lengthScale.TryGetValue(side, out float len)) lengthScale[side] = len = 0.85f + 0.3f * (float)rng.NextDouble();
                pos[j] = pos[SmplSkeleton.ParentOf(j)] + len * CoordinateConversion.ModelToUnity(s.RestOffset(j));
            }

            var rig = new TestRig();
            var world = new List<(Quat rot, Vec3 pos)>();
            // The armature: FBX exports often carry a rotated root that the bones compensate.
            Quat armature = randomFrames ? Quat.AxisAngle(Vec3.UnitX, -90f * TestMaths.Deg) * TestMaths.RandomRotation(rng, 20f) : Quat.Identity;
            rig.Nodes.Add(new TestRig.Node { Name = "Armature", Parent = -1 });
            world.Add((armature, Vec3.Zero));

            int spineChildParent = -1;
            foreach (HumanBone b in HumanoidBoneMap.MappedBones)
            {
                if (missing.Contains(b)) continue;
                int j = HumanoidBoneMap.ToSmplJoint(b);
                int parentNode = 0;
                for (int a = SmplSkeleton.ParentOf(j); a >= 0; a = SmplSkeleton.ParentOf(a))
                {
                    HumanBone ab = HumanoidBoneMap.ToHumanBone((SmplJoint)a);
                    if (!rig.Has(ab)) continue;
                    parentNode = ab == HumanBone.Spine && spineChildParent >= 0 ? spineChildParent : rig.NodeOf[ab];
                    break;
                }
                Quat rot = randomFrames ? TestMaths.RandomRotation(rng) : Quat.Identity;
                rig.NodeOf[b] = rig.Nodes.Count;
                rig.Nodes.Add(new TestRig.Node { Name = b.ToString(), Parent = parentNode, Bone = b });
                world.Add((rot, pos[j]));

                if (b == HumanBone.Spine && intermediate)
                {
                    // A non-humanoid transform between Spine and the next spine bone (e.g. a twist helper).
                    spineChildParent = rig.Nodes.Count;
                    rig.Nodes.Add(new TestRig.Node { Name = "SpineHelper", Parent = rig.NodeOf[b] });
                    world.Add((TestMaths.RandomRotation(rng), pos[j] + new Vec3(0f, 0.05f, 0.01f)));
                }
            }

            for (int i = 0; i < rig.Nodes.Count; i++)
            {
                TestRig.Node n = rig.Nodes[i];
                if (n.Parent < 0)
                {
                    n.Local = world[i].rot;
                    n.LocalPosition = world[i].pos;
                    continue;
                }
                var (prot, ppos) = world[n.Parent];
                n.Local = (prot.Inverse * world[i].rot).Normalized;
                n.LocalPosition = prot.Inverse * (world[i].pos - ppos);
            }
            rig.UpdateWorld();
            foreach (var kv in rig.NodeOf)
            {
                rig.TPoseWorld[kv.Key] = rig.Nodes[kv.Value].World;
                rig.TPosePosition[kv.Key] = rig.Nodes[kv.Value].WorldPosition;
            }

            if (aPose)
            {
                // Arms 45 deg down, legs 10 deg apart (Unity frame: the character's left is -X).
                float c45 = MathF.Cos(45f * TestMaths.Deg), s10 = MathF.Sin(10f * TestMaths.Deg), c10 = MathF.Cos(10f * TestMaths.Deg);
                rig.RotateWorld(HumanBone.LeftUpperArm, Quat.FromToRotation(new Vec3(-1f, 0f, 0f), new Vec3(-c45, -c45, 0f)));
                rig.RotateWorld(HumanBone.RightUpperArm, Quat.FromToRotation(new Vec3(1f, 0f, 0f), new Vec3(c45, -c45, 0f)));
                rig.RotateWorld(HumanBone.LeftUpperLeg, Quat.FromToRotation(new Vec3(0f, -1f, 0f), new Vec3(-s10, -c10, 0f)));
                rig.RotateWorld(HumanBone.RightUpperLeg, Quat.FromToRotation(new Vec3(0f, -1f, 0f), new Vec3(s10, -c10, 0f)));
            }
            return rig;
        }

        public static SmplPose RandomPose(Random rng, bool wild)
        {
            var pose = new SmplPose();
            pose.Rotations[0] = TestMaths.RandomRotation(rng);
            for (int j = 1; j < 24; j++)
                pose.Rotations[j] = wild ? TestMaths.RandomRotation(rng) : TestMaths.RandomRotation(rng, 100f);
            pose.RootPosition = new Vec3((float)rng.NextDouble() - 0.5f, 0.6f + 0.4f * (float)rng.NextDouble(), (float)rng.NextDouble() * 3f);
            return pose;
        }
    }

    public class RetargetTests
    {
        private const float DirTolerance = 1e-4f;
        private const float RotTolerance = 2e-4f; // radians

        private static IEnumerable<TestCaseData> Cases()
        {
            yield return new TestCaseData(RigKind.IdentityTPose, RigRestPose.TPose);
            yield return new TestCaseData(RigKind.IdentityTPose, RigRestPose.AlignToSmplTPose);
            yield return new TestCaseData(RigKind.RandomRest, RigRestPose.TPose);
            yield return new TestCaseData(RigKind.RandomRest, RigRestPose.AlignToSmplTPose);
            yield return new TestCaseData(RigKind.APose, RigRestPose.AlignToSmplTPose);
            yield return new TestCaseData(RigKind.APoseRandomRest, RigRestPose.AlignToSmplTPose);
            yield return new TestCaseData(RigKind.MissingUpperChestNeckToes, RigRestPose.TPose);
            yield return new TestCaseData(RigKind.MissingUpperChestNeckToes, RigRestPose.AlignToSmplTPose);
            yield return new TestCaseData(RigKind.MissingAllOptionalAPose, RigRestPose.AlignToSmplTPose);
        }

        private static (TestRig rig, RestPoseRetargeter retargeter) Setup(RigKind kind, RigRestPose mode)
        {
            TestRig rig = TestRigs.Build(kind);
            return (rig, new RestPoseRetargeter(SmplSkeleton.Default, rig.Describe(), mode));
        }

        [TestCaseSource(nameof(Cases))]
        public void RestPoseReproducesTheRigsOwnTPose(RigKind kind, RigRestPose mode)
        {
            var (rig, r) = Setup(kind, mode);
            var pose = new SmplPose();
            pose.SetRest(SmplSkeleton.Default.RestOffset(0));
            r.Retarget(pose);
            rig.Apply(r);
            foreach (var kv in rig.NodeOf)
            {
                TestRig.Node n = rig.Nodes[kv.Value];
                TestMaths.AssertRotation(rig.TPoseWorld[kv.Key], n.World, RotTolerance, kv.Key.ToString());
                HumanBone? end = TestRigs.ChainEnd(rig, kv.Key);
                if (end == null) continue;
                Vec3 expected = (rig.TPosePosition[end.Value] - rig.TPosePosition[kv.Key]).Normalized;
                TestMaths.AssertVec(expected, (rig[end.Value].WorldPosition - n.WorldPosition).Normalized, DirTolerance, $"{kv.Key}->{end}");
            }
            TestMaths.AssertVec(rig[HumanBone.Hips].WorldPosition, r.HipsPosition, 1e-5f, "hips stay put");
        }

        [Test]
        public void APoseRigIsStraightenedToATPoseNotKeptInItsAPose()
        {
            var (rig, r) = Setup(RigKind.APose, RigRestPose.AlignToSmplTPose);
            Vec3 bindArm = (rig[HumanBone.LeftLowerArm].WorldPosition - rig[HumanBone.LeftUpperArm].WorldPosition).Normalized;
            Vec3 bindLeg = (rig[HumanBone.RightLowerLeg].WorldPosition - rig[HumanBone.RightUpperLeg].WorldPosition).Normalized;
            Assert.That(bindArm.Y, Is.LessThan(-0.7f), "the bind pose is an A-pose");
            Assert.That(bindLeg.X, Is.GreaterThan(0.15f), "legs apart at bind");

            var pose = new SmplPose();
            r.Retarget(pose);
            rig.Apply(r);
            Vec3 arm = (rig[HumanBone.LeftLowerArm].WorldPosition - rig[HumanBone.LeftUpperArm].WorldPosition).Normalized;
            Vec3 leg = (rig[HumanBone.RightLowerLeg].WorldPosition - rig[HumanBone.RightUpperLeg].WorldPosition).Normalized;
            TestMaths.AssertVec(new Vec3(-1f, 0f, 0f), arm, DirTolerance, "left arm out to the character's left (Unity -X)");
            TestMaths.AssertVec(new Vec3(0f, -1f, 0f), leg, DirTolerance, "leg straight down");

            // The same rig described as if its A-pose were a T-pose keeps the A-pose: the mode matters.
            TestRig fresh = TestRigs.Build(RigKind.APose);
            var naive = new RestPoseRetargeter(SmplSkeleton.Default, fresh.Describe(), RigRestPose.TPose);
            naive.Retarget(pose);
            fresh.Apply(naive);
            Vec3 naiveArm = (fresh[HumanBone.LeftLowerArm].WorldPosition - fresh[HumanBone.LeftUpperArm].WorldPosition).Normalized;
            Assert.That(naiveArm.Y, Is.LessThan(-0.7f));
        }

        [TestCaseSource(nameof(Cases))]
        public void RandomPosesReproduceSmplBoneDirections(RigKind kind, RigRestPose mode)
        {
            var (rig, r) = Setup(kind, mode);
            SmplSkeleton s = SmplSkeleton.Default;
            var rng = new Random(100 + (int)kind);
            var global = new Quat[24];
            var pos = new Vec3[24];
            int checkedDirections = 0;
            for (int trial = 0; trial < 40; trial++)
            {
                SmplPose pose = TestRigs.RandomPose(rng, wild: trial % 4 == 0);
                r.Retarget(pose);
                rig.Apply(r);
                s.ForwardKinematics(pose.Rotations, pose.RootPosition, global, pos);

                for (int i = 0; i < r.Rig.Count; i++)
                {
                    HumanBone b = r.Rig[i].Bone;
                    TestRig.Node n = rig[b];
                    int j = HumanoidBoneMap.ToSmplJoint(b);
                    TestMaths.AssertRotation(n.World, r.Rotations[i], RotTolerance, $"reported rotation of {b}");

                    // Every rig child that sits rigidly on this SMPL joint, and the bone's chain end
                    // (which may lie past missing bones), must point where the SMPL joints do.
                    var ends = rig.NodeOf.Keys.Where(c => rig.Nodes[rig.Nodes[rig.NodeOf[c]].Parent].Bone == b ||
                                                          IsParentThroughHelpers(rig, c, b))
                        .Where(c => SmplSkeleton.ParentOf(HumanoidBoneMap.ToSmplJoint(c)) == j).ToList();
                    HumanBone? chainEnd = TestRigs.ChainEnd(rig, b);
                    if (chainEnd != null && !ends.Contains(chainEnd.Value)) ends.Add(chainEnd.Value);
                    foreach (HumanBone c in ends)
                    {
                        int jc = HumanoidBoneMap.ToSmplJoint(c);
                        Vec3 expected = CoordinateConversion.ModelToUnity(pos[jc] - pos[j]).Normalized;
                        Vec3 actual = (rig[c].WorldPosition - n.WorldPosition).Normalized;
                        TestMaths.AssertVec(expected, actual, DirTolerance, $"{kind}/{mode} trial {trial}: {b}->{c}");
                        checkedDirections++;
                    }

                    // A bone that spans no missing joint turns exactly as its SMPL joint from the T-pose.
                    bool spansMissing = chainEnd != null && SmplSkeleton.ParentOf(HumanoidBoneMap.ToSmplJoint(chainEnd.Value)) != j;
                    if (!spansMissing)
                        TestMaths.AssertRotation(CoordinateConversion.ModelToUnity(global[j]) * rig.TPoseWorld[b], n.World,
                            RotTolerance, $"{kind}/{mode} trial {trial}: {b} as world delta");
                }
            }
            // Guard against a vacuous pass: even the sparsest rig has 12 chain directions per frame.
            Assert.That(checkedDirections, Is.GreaterThanOrEqualTo(40 * 12));
        }

        private static bool IsParentThroughHelpers(TestRig rig, HumanBone child, HumanBone parent)
        {
            for (int p = rig.Nodes[rig.NodeOf[child]].Parent; p >= 0; p = rig.Nodes[p].Parent)
                if (rig.Nodes[p].Bone != HumanBone.LastBone) return rig.Nodes[p].Bone == parent;
            return false;
        }

        [Test]
        public void MissingBonesFoldIntoTheirParents()
        {
            // Bend only spine3 and neck: a rig without UpperChest and Neck must still put its head where SMPL's is.
            var (rig, r) = Setup(RigKind.MissingUpperChestNeckToes, RigRestPose.TPose);
            Assert.That(r.Rig.Has(HumanBone.UpperChest) || r.Rig.Has(HumanBone.Neck) || r.Rig.Has(HumanBone.LeftToes), Is.False);
            var pose = new SmplPose();
            pose.Rotations[(int)SmplJoint.Spine3] = Quat.AxisAngle(Vec3.UnitX, 40f * TestMaths.Deg);
            pose.Rotations[(int)SmplJoint.Neck] = Quat.AxisAngle(Vec3.UnitZ, 30f * TestMaths.Deg);
            r.Retarget(pose);
            rig.Apply(r);
            var global = new Quat[24];
            var pos = new Vec3[24];
            SmplSkeleton.Default.ForwardKinematics(pose.Rotations, pose.RootPosition, global, pos);

            Vec3 chestToHeadBefore = (rig.TPosePosition[HumanBone.Head] - rig.TPosePosition[HumanBone.Chest]).Normalized;
            Vec3 chestToHead = (rig[HumanBone.Head].WorldPosition - rig[HumanBone.Chest].WorldPosition).Normalized;
            Assert.That(Vec3.Dot(chestToHeadBefore, chestToHead), Is.LessThan(0.95f), "the chest bends although its SMPL joint did not turn");
            // The head's orientation is the full chain's.
            TestMaths.AssertRotation(CoordinateConversion.ModelToUnity(global[(int)SmplJoint.Head]) * rig.TPoseWorld[HumanBone.Head],
                rig[HumanBone.Head].World, RotTolerance);
            // The arms hang off the chest: with spine3's bend folded into the chest they follow it.
            TestMaths.AssertRotation(CoordinateConversion.ModelToUnity(global[(int)SmplJoint.LeftShoulder]) * rig.TPoseWorld[HumanBone.LeftUpperArm],
                rig[HumanBone.LeftUpperArm].World, RotTolerance);
        }

        [Test]
        public void RootMotionIsConvertedAndScaled()
        {
            var (rig, r) = Setup(RigKind.RandomRest, RigRestPose.TPose);
            Vec3 restHips = rig[HumanBone.Hips].WorldPosition;
            float scale = restHips.Y / 0.93f;
            Assert.That(r.RootScale, Is.EqualTo(scale).Within(1e-5f));
            var pose = new SmplPose();
            // Half a metre to the character's left, 20 cm forward, 10 cm down (model frame).
            pose.SetRest(new Vec3(0.5f, 0.83f, 0.2f));
            r.Retarget(pose);
            Vec3 moved = r.HipsPosition - restHips;
            TestMaths.AssertVec(new Vec3(-0.5f, -0.1f, 0.2f) * scale, moved, 1e-5f);
            float leftSide = rig[HumanBone.LeftUpperLeg].WorldPosition.X - restHips.X;
            Assert.That(Math.Sign(moved.X), Is.EqualTo(Math.Sign(leftSide)), "moves towards the rig's own left leg");

            r.RootScale = 2f;
            r.Retarget(pose);
            TestMaths.AssertVec(new Vec3(-1f, -0.2f, 0.4f), r.HipsPosition - restHips, 1e-5f);
        }

        [Test]
        public void HipsRotationIsTheRootRotationInUnity()
        {
            var (rig, r) = Setup(RigKind.IdentityTPose, RigRestPose.TPose);
            var pose = new SmplPose();
            pose.Rotations[0] = Quat.AxisAngle(Vec3.UnitY, 90f * TestMaths.Deg); // turn to the character's left
            r.Retarget(pose);
            rig.Apply(r);
            Vec3 facing = rig[HumanBone.Hips].World * Vec3.UnitZ;
            TestMaths.AssertVec(new Vec3(-1f, 0f, 0f), facing, 1e-5f, "faces Unity's -X, the character's former left");
            Assert.That(r.TryGetLocalRotation(HumanBone.Hips, out Quat hips), Is.True);
            TestMaths.AssertRotation(Quat.AxisAngle(Vec3.UnitY, -90f * TestMaths.Deg), hips, RotTolerance);
            Assert.That(r.TryGetLocalRotation(HumanBone.Jaw, out _), Is.False);
        }

        [Test]
        public void RetargetingAllocatesNothingPerFrame()
        {
            var (_, r) = Setup(RigKind.MissingAllOptionalAPose, RigRestPose.AlignToSmplTPose);
            var (_, r2) = Setup(RigKind.MissingUpperChestNeckToes, RigRestPose.TPose);
            var rng = new Random(5);
            const int frames = 64;
            var matrices = new float[frames * 216];
            var roots = new Vec3[frames];
            for (int f = 0; f < frames; f++)
            {
                SmplPose p = TestRigs.RandomPose(rng, wild: false);
                for (int j = 0; j < 24; j++) Mat3.FromQuat(p.Rotations[j]).CopyToRowMajor(matrices.AsSpan(f * 216 + 9 * j, 9));
                roots[f] = p.RootPosition;
            }
            var pose = new SmplPose();
            float sink = 0f;
            void Frame(int f)
            {
                pose.SetFromRowMajorMatrices(matrices.AsSpan(f * 216, 216), roots[f]);
                r.Retarget(pose);
                r2.Retarget(pose);
                sink += r.LocalRotations[3].W + r2.Rotations[5].X + r.HipsPosition.Y;
            }
            for (int f = 0; f < frames; f++) Frame(f); // warm-up (JIT, tiering)
            long before = GC.GetAllocatedBytesForCurrentThread();
            for (int k = 0; k < 2000; k++) Frame(k % frames);
            long allocated = GC.GetAllocatedBytesForCurrentThread() - before;
            Assert.That(allocated, Is.EqualTo(0), "bytes allocated over 2000 frames");
            Assert.That(float.IsFinite(sink), Is.True);
        }

        [Test]
        public void RigDescriptionIsValidated()
        {
            TestRig rig = TestRigs.Build(RigKind.IdentityTPose);
            List<RigBone> Bones() => Enumerable.Range(0, rig.Describe().Count).Select(i => rig.Describe()[i]).ToList();

            var noHand = Bones().Where(b => b.Bone != HumanBone.LeftHand).ToList();
            StringAssert.Contains("LeftHand", Assert.Throws<ArgumentException>(() => new HumanoidRig(noHand)).Message);

            var twice = Bones();
            twice.Add(twice[3]);
            StringAssert.Contains("twice", Assert.Throws<ArgumentException>(() => new HumanoidRig(twice)).Message);

            var jaw = Bones();
            jaw.Add(new RigBone(HumanBone.Jaw, HumanBone.Head, Quat.Identity, Quat.Identity, Vec3.Zero));
            StringAssert.Contains("Jaw", Assert.Throws<ArgumentException>(() => new HumanoidRig(jaw)).Message);

            var wrongParent = Bones().Select(b => b.Bone == HumanBone.LeftLowerArm
                ? new RigBone(b.Bone, HumanBone.RightUpperArm, b.RestLocalRotation, b.RestRotation, b.RestPosition) : b).ToList();
            StringAssert.Contains("not above it", Assert.Throws<ArgumentException>(() => new HumanoidRig(wrongParent)).Message);

            var nan = Bones().Select(b => b.Bone == HumanBone.Spine
                ? new RigBone(b.Bone, b.Parent, b.RestLocalRotation, b.RestRotation, new Vec3(float.NaN, 0f, 0f)) : b).ToList();
            StringAssert.Contains("non-finite", Assert.Throws<ArgumentException>(() => new HumanoidRig(nan)).Message);

            // A parent further up the hierarchy is fine (shoulders hung directly on the chest).
            var skip = Bones().Select(b => b.Bone == HumanBone.LeftShoulder
                ? new RigBone(b.Bone, HumanBone.Chest, b.RestLocalRotation, b.RestRotation, b.RestPosition) : b).ToList();
            Assert.That(new HumanoidRig(skip).Count, Is.EqualTo(22));
            HumanoidRig described = rig.Describe();
            Assert.That(described[0].Bone, Is.EqualTo(HumanBone.Hips), "ordered parents first whatever the input order");
            for (int i = 1; i < described.Count; i++) Assert.That(described.ParentIndex(i), Is.LessThan(i));
        }

        [Test]
        public void AlignModeLeavesATruePoseRigAlone()
        {
            TestRig rig = TestRigs.Build(RigKind.RandomRest);
            HumanoidRig d = rig.Describe();
            var aligned = new RestPoseRetargeter(SmplSkeleton.Default, d, RigRestPose.AlignToSmplTPose);
            for (int i = 0; i < d.Count; i++)
                TestMaths.AssertRotation(d[i].RestRotation, aligned.TPoseRotation(i), RotTolerance, d[i].Bone.ToString());
        }
    }
}
