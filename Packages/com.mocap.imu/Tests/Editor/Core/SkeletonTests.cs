using System;
using System.Collections.Generic;
using System.Globalization;
using System.Linq;
using System.Threading;
using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;
using Mocap.Imu.Tests.Maths;
using NUnit.Framework;

namespace Mocap.Imu.Tests.Skeleton
{
    public class SkeletonTests
    {
        private const string Names =
            "pelvis,left_hip,right_hip,spine1,left_knee,right_knee,spine2,left_ankle,right_ankle,spine3," +
            "left_foot,right_foot,neck,left_collar,right_collar,head,left_shoulder,right_shoulder," +
            "left_elbow,right_elbow,left_wrist,right_wrist,left_hand,right_hand";
        private const string Parents = "-1,0,0,0,1,2,3,4,5,6,7,8,9,9,9,12,13,14,16,17,18,19,20,21";

        private static string Offsets(SmplSkeleton s) => string.Join(",",
            Enumerable.Range(0, 24).SelectMany(j => new[] { s.RestOffset(j).X, s.RestOffset(j).Y, s.RestOffset(j).Z })
                .Select(v => v.ToString("R", CultureInfo.InvariantCulture)));

        private static Dictionary<string, string> ValidMetadata() => new Dictionary<string, string>
        {
            ["mocap.contract_version"] = "1",
            ["mocap.joint_names"] = Names,
            ["mocap.joint_parents"] = Parents,
            ["mocap.rest_offsets"] = Offsets(SmplSkeleton.Default),
        };

        [Test]
        public void SameProportionsMeansEqualRestOffsets()
        {
            var offsets = new Vec3[SmplSkeleton.JointCount];
            for (int j = 0; j < offsets.Length; j++) offsets[j] = SmplSkeleton.Default.RestOffset(j);
            var copy = SmplSkeleton.FromRestOffsets(offsets);
            Assert.IsTrue(SmplSkeleton.Default.HasSameProportions(copy));
            Assert.IsTrue(copy.HasSameProportions(SmplSkeleton.Default));
            var o = offsets[18];
            offsets[18] = new Vec3(o.X * 1.01f + 0.001f, o.Y, o.Z);  // a longer upper arm
            Assert.IsFalse(SmplSkeleton.Default.HasSameProportions(SmplSkeleton.FromRestOffsets(offsets)));
            Assert.IsFalse(SmplSkeleton.Default.HasSameProportions(null));
        }

        [Test]
        public void ContractNamesAndParents()
        {
            Assert.That(string.Join(",", SmplSkeleton.JointNames), Is.EqualTo(Names));
            Assert.That(string.Join(",", SmplSkeleton.Parents), Is.EqualTo(Parents));
            Assert.That(SmplSkeleton.IndexOf("left_wrist"), Is.EqualTo((int)SmplJoint.LeftWrist));
            Assert.That(SmplSkeleton.IndexOf("nose"), Is.EqualTo(-1));
            for (int j = 0; j < 24; j++)
                Assert.That(((SmplJoint)j).ToString().ToLowerInvariant(), Is.EqualTo(SmplSkeleton.NameOf(j).Replace("_", "")));
        }

        [Test]
        public void DefaultRestPositionsMatchTrainingSkeleton()
        {
            SmplSkeleton s = SmplSkeleton.Default;
            // Values from training/skeleton.py: pelvis 0.93 m, hips at 0.87 m, 8.5 cm either side of the middle.
            TestMaths.AssertVec(new Vec3(0f, 0.93f, 0f), s.RestPosition(0), 1e-6f);
            TestMaths.AssertVec(new Vec3(0.085f, 0.87f, 0f), s.RestPosition((int)SmplJoint.LeftHip), 1e-6f);
            // Left wrist: collar 0.07 + shoulder 0.11 + upper arm 0.3255 + forearm 0.2555 along +X (the character's left).
            TestMaths.AssertVec(new Vec3(0.761f, 0.818f * 1.75f, 0f), s.RestPosition((int)SmplJoint.LeftWrist), 1e-5f);
            TestMaths.AssertVec(new Vec3(0f, 1.55f, 0f), s.RestPosition((int)SmplJoint.Head), 1e-5f);
            Assert.That(s.RestPosition((int)SmplJoint.LeftFoot).Z, Is.GreaterThan(0.1f), "toes point forward (+Z)");
            Assert.That(s.RestPosition((int)SmplJoint.LeftFoot).Y, Is.EqualTo(0.02f).Within(1e-6f));
        }

        [Test]
        public void FromMetadataReadsOffsets()
        {
            Dictionary<string, string> md = ValidMetadata();
            md["mocap.rest_offsets"] = md["mocap.rest_offsets"].Replace("0.93", "1.01");
            SmplSkeleton s = SmplSkeleton.FromMetadata(md);
            Assert.That(s.RestOffset(0).Y, Is.EqualTo(1.01f));
            for (int j = 1; j < 24; j++)
                Assert.That(s.RestOffset(j), Is.EqualTo(SmplSkeleton.Default.RestOffset(j)), $"joint {j}");
        }

        [Test]
        public void FromMetadataToleratesSpacesAndIgnoresCulture()
        {
            Dictionary<string, string> md = ValidMetadata();
            md["mocap.joint_names"] = string.Join(", ", Names.Split(','));
            md["mocap.joint_parents"] = string.Join(" , ", Parents.Split(','));
            CultureInfo saved = Thread.CurrentThread.CurrentCulture;
            try
            {
                // A comma-decimal culture must not change how "0.93" parses.
                Thread.CurrentThread.CurrentCulture = new CultureInfo("de-DE");
                Assert.That(SmplSkeleton.FromMetadata(md).RestOffset(0).Y, Is.EqualTo(0.93f));
            }
            finally
            {
                Thread.CurrentThread.CurrentCulture = saved;
            }
        }

        private static void AssertRejected(Action<Dictionary<string, string>> corrupt, params string[] messageParts)
        {
            Dictionary<string, string> md = ValidMetadata();
            corrupt(md);
            var ex = Assert.Throws<FormatException>(() => SmplSkeleton.FromMetadata(md));
            foreach (string part in messageParts) StringAssert.Contains(part, ex.Message);
        }

        [Test]
        public void FromMetadataRejectsMissingKeys()
        {
            AssertRejected(md => md.Remove("mocap.joint_names"), "mocap.joint_names", "missing");
            AssertRejected(md => md.Remove("mocap.joint_parents"), "mocap.joint_parents", "missing");
            AssertRejected(md => md.Remove("mocap.rest_offsets"), "mocap.rest_offsets", "missing");
        }

        [Test]
        public void FromMetadataRejectsWrongNames()
        {
            AssertRejected(md => md["mocap.joint_names"] = Names.Replace("spine3", "chest"), "joint 9", "'chest'", "'spine3'");
            AssertRejected(md => md["mocap.joint_names"] = Names + ",extra", "expected 24", "got 25");
            // Swapped sides are a real risk with mirrored exports; the order must be the contract's.
            AssertRejected(md => md["mocap.joint_names"] = Names.Replace("left_hip,right_hip", "right_hip,left_hip"), "joint 1");
        }

        [Test]
        public void FromMetadataRejectsWrongParents()
        {
            AssertRejected(md => md["mocap.joint_parents"] = Parents.Replace("12,13,14", "9,13,14"), "joint 15", "head", "parent 9", "expects 12");
            AssertRejected(md => md["mocap.joint_parents"] = Parents.Replace("-1,", "root,"), "item 0", "'root'");
            AssertRejected(md => md["mocap.joint_parents"] = "-1,0", "expected 24", "got 2");
        }

        [Test]
        public void FromMetadataRejectsBadOffsets()
        {
            AssertRejected(md => md["mocap.rest_offsets"] = string.Join(",", md["mocap.rest_offsets"].Split(',').Take(71)), "expected 72", "got 71");
            AssertRejected(md => md["mocap.rest_offsets"] = ReplaceItem(md["mocap.rest_offsets"], 4, "abc"), "item 4", "left_hip", "'abc'");
            AssertRejected(md => md["mocap.rest_offsets"] = ReplaceItem(md["mocap.rest_offsets"], 5, "NaN"), "item 5", "not a finite");
            AssertRejected(md => md["mocap.rest_offsets"] = ReplaceItem(md["mocap.rest_offsets"], 1, "0"), "pelvis", "height");
            AssertRejected(md =>
            {
                string v = md["mocap.rest_offsets"];
                for (int i = 3 * 18; i < 3 * 18 + 3; i++) v = ReplaceItem(v, i, "0");
                md["mocap.rest_offsets"] = v;
            }, "joint 18", "left_elbow", "shorter");
        }

        private static string ReplaceItem(string list, int index, string value)
        {
            string[] items = list.Split(',');
            items[index] = value;
            return string.Join(",", items);
        }

        [Test]
        public void FromRestOffsetsValidatesToo()
        {
            var offsets = Enumerable.Range(0, 24).Select(j => SmplSkeleton.Default.RestOffset(j)).ToArray();
            Assert.That(SmplSkeleton.FromRestOffsets(offsets).RestPosition(23), Is.EqualTo(SmplSkeleton.Default.RestPosition(23)));
            offsets[7] = new Vec3(float.PositiveInfinity, 0f, 0f);
            Assert.Throws<ArgumentException>(() => SmplSkeleton.FromRestOffsets(offsets));
            Assert.Throws<ArgumentException>(() => SmplSkeleton.FromRestOffsets(offsets.Take(23).ToArray()));
        }

        [Test]
        public void ForwardKinematicsOfRestPoseGivesRestPositions()
        {
            SmplSkeleton s = SmplSkeleton.Default;
            var local = Enumerable.Repeat(Quat.Identity, 24).ToArray();
            var global = new Quat[24];
            var pos = new Vec3[24];
            s.ForwardKinematics(local, s.RestPosition(0), global, pos);
            for (int j = 0; j < 24; j++)
            {
                TestMaths.AssertVec(s.RestPosition(j), pos[j], 1e-6f, $"joint {j}");
                Assert.That(global[j], Is.EqualTo(Quat.Identity));
            }
        }

        [Test]
        public void ForwardKinematicsKnownRotations()
        {
            SmplSkeleton s = SmplSkeleton.Default;
            var local = Enumerable.Repeat(Quat.Identity, 24).ToArray();
            var global = new Quat[24];
            var pos = new Vec3[24];
            var root = new Vec3(0.5f, 0.93f, -1f);

            // Raise the left arm: +90 deg about +Z turns +X (the arm) into +Y.
            local[(int)SmplJoint.LeftShoulder] = Quat.AxisAngle(Vec3.UnitZ, 90f * TestMaths.Deg);
            s.ForwardKinematics(local, root, global, pos);
            Vec3 shoulder = pos[(int)SmplJoint.LeftShoulder];
            float arm = 0.186f * 1.75f + 0.146f * 1.75f;
            TestMaths.AssertVec(shoulder + new Vec3(0f, arm, 0f), pos[(int)SmplJoint.LeftWrist], 1e-5f);
            TestMaths.AssertVec(root + s.RestPosition((int)SmplJoint.LeftShoulder) - s.RestPosition(0), shoulder, 1e-5f);
            // The right arm is untouched.
            TestMaths.AssertVec(root + s.RestPosition((int)SmplJoint.RightWrist) - s.RestPosition(0), pos[(int)SmplJoint.RightWrist], 1e-5f);

            // Turn the whole body round (joint 0 is global): the left hand ends up on -X.
            local[(int)SmplJoint.LeftShoulder] = Quat.Identity;
            local[0] = Quat.AxisAngle(Vec3.UnitY, 180f * TestMaths.Deg);
            s.ForwardKinematics(local, root, global, pos);
            Vec3 restWrist = s.RestPosition((int)SmplJoint.LeftWrist) - s.RestPosition(0);
            TestMaths.AssertVec(root + new Vec3(-restWrist.X, restWrist.Y, -restWrist.Z), pos[(int)SmplJoint.LeftWrist], 1e-5f);
            TestMaths.AssertRotation(local[0], global[(int)SmplJoint.LeftWrist], 1e-4f);
        }

        [Test]
        public void ForwardKinematicsMatchesMatrixChain()
        {
            // Independent reference: rotation matrices multiplied down the chain, as training/skeleton.py does.
            SmplSkeleton s = SmplSkeleton.Default;
            var rng = new Random(11);
            var local = new Quat[24];
            var global = new Quat[24];
            var pos = new Vec3[24];
            for (int trial = 0; trial < 20; trial++)
            {
                for (int j = 0; j < 24; j++) local[j] = TestMaths.RandomRotation(rng);
                var root = new Vec3(0.1f * trial, 0.9f, -0.2f);
                s.ForwardKinematics(local, root, global, pos);
                var g = new Mat3[24];
                var p = new Vec3[24];
                g[0] = Mat3.FromQuat(local[0]);
                p[0] = root;
                for (int j = 1; j < 24; j++)
                {
                    int parent = SmplSkeleton.ParentOf(j);
                    g[j] = g[parent] * Mat3.FromQuat(local[j]);
                    p[j] = p[parent] + g[parent] * s.RestOffset(j);
                    TestMaths.AssertVec(p[j], pos[j], 1e-5f, $"trial {trial} joint {j}");
                    Assert.That(Mat3.FromQuat(global[j]).ApproximatelyEquals(g[j], 1e-4f), Is.True, $"trial {trial} joint {j}");
                }
            }
        }

        [Test]
        public void ForwardKinematicsRejectsShortSpans()
        {
            Assert.Throws<ArgumentException>(() =>
                SmplSkeleton.Default.ForwardKinematics(new Quat[23], Vec3.Zero, new Quat[24], new Vec3[24]));
        }

        [Test]
        public void PoseReadsContractMatrices()
        {
            var pose = new SmplPose();
            var rng = new Random(12);
            var expected = new Quat[24];
            var floats = new float[216];
            for (int j = 0; j < 24; j++)
            {
                expected[j] = TestMaths.RandomRotation(rng);
                Mat3.FromQuat(expected[j]).CopyToRowMajor(floats.AsSpan(9 * j, 9));
            }
            pose.SetFromRowMajorMatrices(floats, new Vec3(1f, 2f, 3f));
            for (int j = 0; j < 24; j++) TestMaths.AssertRotation(expected[j], pose.Rotations[j], 1e-3f, $"joint {j}");
            Assert.That(pose.RootPosition, Is.EqualTo(new Vec3(1f, 2f, 3f)));
            Assert.Throws<ArgumentException>(() => pose.SetFromRowMajorMatrices(new float[215], Vec3.Zero));

            var copy = new SmplPose();
            copy.CopyFrom(pose);
            Assert.That(copy.Rotations[7], Is.EqualTo(pose.Rotations[7]));
            copy.SetRest(Vec3.Zero);
            Assert.That(copy.Rotations[7], Is.EqualTo(Quat.Identity));
        }
    }

    public class HumanoidBoneMapTests
    {
        [Test]
        public void HumanBoneValuesAreUnitysHumanBodyBones()
        {
            // UnityEngine.HumanBodyBones values (Unity 2022.3 scripting reference); the glue casts.
            var expected = new (HumanBone bone, int value)[]
            {
                (HumanBone.Hips, 0), (HumanBone.LeftUpperLeg, 1), (HumanBone.RightUpperLeg, 2), (HumanBone.LeftLowerLeg, 3),
                (HumanBone.RightLowerLeg, 4), (HumanBone.LeftFoot, 5), (HumanBone.RightFoot, 6), (HumanBone.Spine, 7),
                (HumanBone.Chest, 8), (HumanBone.Neck, 9), (HumanBone.Head, 10), (HumanBone.LeftShoulder, 11),
                (HumanBone.RightShoulder, 12), (HumanBone.LeftUpperArm, 13), (HumanBone.RightUpperArm, 14),
                (HumanBone.LeftLowerArm, 15), (HumanBone.RightLowerArm, 16), (HumanBone.LeftHand, 17), (HumanBone.RightHand, 18),
                (HumanBone.LeftToes, 19), (HumanBone.RightToes, 20), (HumanBone.LeftEye, 21), (HumanBone.RightEye, 22),
                (HumanBone.Jaw, 23), (HumanBone.LeftThumbProximal, 24), (HumanBone.LeftLittleDistal, 38),
                (HumanBone.RightThumbProximal, 39), (HumanBone.RightLittleDistal, 53), (HumanBone.UpperChest, 54),
                (HumanBone.LastBone, 55),
            };
            foreach (var (bone, value) in expected) Assert.That((int)bone, Is.EqualTo(value), bone.ToString());
            Assert.That(Enum.GetValues(typeof(HumanBone)).Length, Is.EqualTo(56));
        }

        [Test]
        public void SmplJointsMapToTheirUnityBones()
        {
            var expected = new Dictionary<SmplJoint, HumanBone>
            {
                [SmplJoint.Pelvis] = HumanBone.Hips, [SmplJoint.Spine1] = HumanBone.Spine, [SmplJoint.Spine2] = HumanBone.Chest,
                [SmplJoint.Spine3] = HumanBone.UpperChest, [SmplJoint.Neck] = HumanBone.Neck, [SmplJoint.Head] = HumanBone.Head,
                [SmplJoint.LeftCollar] = HumanBone.LeftShoulder, [SmplJoint.RightCollar] = HumanBone.RightShoulder,
                [SmplJoint.LeftShoulder] = HumanBone.LeftUpperArm, [SmplJoint.RightShoulder] = HumanBone.RightUpperArm,
                [SmplJoint.LeftElbow] = HumanBone.LeftLowerArm, [SmplJoint.RightElbow] = HumanBone.RightLowerArm,
                [SmplJoint.LeftWrist] = HumanBone.LeftHand, [SmplJoint.RightWrist] = HumanBone.RightHand,
                [SmplJoint.LeftHip] = HumanBone.LeftUpperLeg, [SmplJoint.RightHip] = HumanBone.RightUpperLeg,
                [SmplJoint.LeftKnee] = HumanBone.LeftLowerLeg, [SmplJoint.RightKnee] = HumanBone.RightLowerLeg,
                [SmplJoint.LeftAnkle] = HumanBone.LeftFoot, [SmplJoint.RightAnkle] = HumanBone.RightFoot,
                [SmplJoint.LeftFoot] = HumanBone.LeftToes, [SmplJoint.RightFoot] = HumanBone.RightToes,
            };
            foreach (var kv in expected)
            {
                Assert.That(HumanoidBoneMap.ToHumanBone(kv.Key), Is.EqualTo(kv.Value), kv.Key.ToString());
                Assert.That(HumanoidBoneMap.ToSmplJoint(kv.Value), Is.EqualTo((int)kv.Key), kv.Value.ToString());
                Assert.That(HumanoidBoneMap.IsMapped(kv.Key), Is.True);
            }
            Assert.That(HumanoidBoneMap.IsMapped(SmplJoint.LeftHand), Is.False);
            Assert.That(HumanoidBoneMap.IsMapped(SmplJoint.RightHand), Is.False);
            Assert.That(HumanoidBoneMap.ToSmplJoint(HumanBone.Jaw), Is.EqualTo(-1));
            Assert.That(HumanoidBoneMap.ToSmplJoint(HumanBone.LeftIndexProximal), Is.EqualTo(-1));
            Assert.That(HumanoidBoneMap.ToSmplJoint(HumanBone.LastBone), Is.EqualTo(-1));
            Assert.That(HumanoidBoneMap.MappedBones.Count, Is.EqualTo(HumanoidBoneMap.MappedJointCount));
            Assert.That(HumanoidBoneMap.MappedBones.Distinct().Count(), Is.EqualTo(22));
        }

        [Test]
        public void SidesAreKept()
        {
            // The model's "left" and Unity's "Left" are both the character's left, whatever the axes.
            for (int j = 0; j < 22; j++)
            {
                string smpl = SmplSkeleton.NameOf(j);
                string unity = HumanoidBoneMap.Name(HumanoidBoneMap.ToHumanBone((SmplJoint)j));
                Assert.That(unity.StartsWith("Left"), Is.EqualTo(smpl.StartsWith("left_")), $"{smpl} -> {unity}");
                Assert.That(unity.StartsWith("Right"), Is.EqualTo(smpl.StartsWith("right_")), $"{smpl} -> {unity}");
            }
        }

        [Test]
        public void MappedBonesListParentsFirstAndFollowTheUnityHierarchy()
        {
            var seen = new HashSet<HumanBone>();
            foreach (HumanBone b in HumanoidBoneMap.MappedBones)
            {
                int j = HumanoidBoneMap.ToSmplJoint(b);
                int p = SmplSkeleton.ParentOf(j);
                if (p >= 0) Assert.That(seen.Contains(HumanoidBoneMap.ToHumanBone((SmplJoint)p)), Is.True, b.ToString());
                seen.Add(b);
            }
            Assert.That(HumanoidBoneMap.ToHumanBone((SmplJoint)SmplSkeleton.ParentOf((int)SmplJoint.LeftCollar)), Is.EqualTo(HumanBone.UpperChest));
            Assert.That(HumanoidBoneMap.ToHumanBone((SmplJoint)SmplSkeleton.ParentOf((int)SmplJoint.LeftHip)), Is.EqualTo(HumanBone.Hips));
        }

        [Test]
        public void OptionalBonesAreUnitysOptionalOnes()
        {
            var optional = HumanoidBoneMap.MappedBones.Where(HumanoidBoneMap.IsOptional).OrderBy(b => (int)b).ToArray();
            Assert.That(optional, Is.EqualTo(new[]
            {
                HumanBone.Chest, HumanBone.Neck, HumanBone.LeftShoulder, HumanBone.RightShoulder,
                HumanBone.LeftToes, HumanBone.RightToes, HumanBone.UpperChest,
            }));
            Assert.That(HumanoidBoneMap.MappedBones.Count(b => !HumanoidBoneMap.IsOptional(b)), Is.EqualTo(15));
        }

        [Test]
        public void ChainChildFollowsTheBody()
        {
            Assert.That(HumanoidBoneMap.ChainChild(SmplJoint.Spine3), Is.EqualTo((int)SmplJoint.Neck));
            Assert.That(HumanoidBoneMap.ChainChild(SmplJoint.Pelvis), Is.EqualTo((int)SmplJoint.Spine1));
            Assert.That(HumanoidBoneMap.ChainChild(SmplJoint.LeftWrist), Is.EqualTo((int)SmplJoint.LeftHand));
            Assert.That(HumanoidBoneMap.ChainChild(SmplJoint.Head), Is.EqualTo(-1));
            Assert.That(HumanoidBoneMap.ChainChild(SmplJoint.RightFoot), Is.EqualTo(-1));
            for (int j = 0; j < 24; j++)
            {
                int c = HumanoidBoneMap.ChainChild((SmplJoint)j);
                if (c >= 0) Assert.That(SmplSkeleton.ParentOf(c), Is.EqualTo(j), $"chain child of {j} is a real child");
            }
        }

        [Test]
        public void NamesParseExactly()
        {
            Assert.That(HumanoidBoneMap.TryParse("LeftUpperArm", out HumanBone b), Is.True);
            Assert.That(b, Is.EqualTo(HumanBone.LeftUpperArm));
            Assert.That(HumanoidBoneMap.TryParse("UpperChest", out b), Is.True);
            Assert.That(b, Is.EqualTo(HumanBone.UpperChest));
            Assert.That(HumanoidBoneMap.TryParse("leftupperarm", out _), Is.False);
            Assert.That(HumanoidBoneMap.TryParse("13", out _), Is.False);
            Assert.That(HumanoidBoneMap.TryParse("LastBone", out _), Is.False);
            Assert.That(HumanoidBoneMap.Name(HumanBone.Hips), Is.EqualTo("Hips"));
        }
    }
}
