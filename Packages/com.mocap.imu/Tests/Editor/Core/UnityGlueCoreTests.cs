// The decisions the Unity components delegate to the core (the calibration sequence is tested in
// CalibrationFlowTests):
// the procedural humanoid layout, root motion split, joint drive targets, and the avatar checks
// the PlayMode tests make, run here on the committed PlayMode fixture through the real engine.

using System;
using System.IO;
using Mocap.Imu.Maths;
using Mocap.Imu.Retarget;
using Mocap.Imu.Skeleton;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class UnityGlueCoreTests
    {
        [Test]
        public void TheProceduralHumanoidIsTheModelSkeletonInUnityFrame()
        {
            var layout = HumanoidLayout.FromSkeleton(SmplSkeleton.Default);
            Assert.AreEqual(22, layout.Length);
            Assert.AreEqual(HumanBone.Hips, layout[0].Id);
            Assert.AreEqual(HumanBone.LastBone, layout[0].Parent);
            var rig = HumanoidLayout.ToRig(layout);
            Assert.AreEqual(22, rig.Count);
            foreach (var b in layout)
            {
                int j = HumanoidBoneMap.ToSmplJoint(b.Id);
                var model = SmplSkeleton.Default.RestPosition(j);
                Assert.IsTrue(new Vec3(-model.X, model.Y, model.Z).ApproximatelyEquals(b.RootPosition, 1e-6f), b.Id.ToString());
            }
            // Unity's +X is the character's right: the right hip lies at positive X.
            Assert.Greater(layout[Array.FindIndex(layout, b => b.Id == HumanBone.RightUpperLeg)].RootPosition.X, 0f);
            Assert.Greater(layout[0].RootPosition.Y, 0.7f, "the hips stand above the floor");
        }

        [Test]
        public void RootMotionGoesToTheHipsOrTheRoot()
        {
            var rest = new Vec3(0.01f, 0.9f, 0.02f);
            var hips = new Vec3(1f, 0.8f, 2f);
            RootMotion.Split(RootMotionMode.MoveHips, hips, rest, out var h, out var r);
            Assert.AreEqual(hips, h);
            Assert.AreEqual(Vec3.Zero, r);
            RootMotion.Split(RootMotionMode.MoveRoot, hips, rest, out h, out r);
            Assert.IsTrue(new Vec3(0.01f, 0.8f, 0.02f).ApproximatelyEquals(h, 1e-6f));
            Assert.IsTrue(new Vec3(0.99f, 0f, 1.98f).ApproximatelyEquals(r, 1e-6f));
            Assert.IsTrue((h + r).ApproximatelyEquals(hips, 1e-6f), "hips + root translation = the pose's hips");
            RootMotion.Split(RootMotionMode.InPlace, hips, rest, out h, out r);
            Assert.IsTrue(new Vec3(0.01f, 0.8f, 0.02f).ApproximatelyEquals(h, 1e-6f));
            Assert.AreEqual(Vec3.Zero, r);
        }

        [Test]
        public void DriveTargetsAreRotationVectorsInDegrees()
        {
            var v = DriveTargets.RotationVectorDegrees(Quat.AxisAngle(new Vec3(0, 0, 1), MathF.PI / 2));
            Assert.IsTrue(new Vec3(0, 0, 90).ApproximatelyEquals(v, 1e-3f), v.ToString());
            // -q is the same rotation: the same targets, the short way round.
            var q = Quat.AxisAngle(new Vec3(1, 0, 0), -MathF.PI / 3);
            var negated = new Quat(-q.X, -q.Y, -q.Z, -q.W);
            Assert.IsTrue(new Vec3(-60, 0, 0).ApproximatelyEquals(DriveTargets.RotationVectorDegrees(negated), 1e-3f));
            Assert.AreEqual(Vec3.Zero, DriveTargets.RotationVectorDegrees(Quat.Identity));
        }

        /// <summary>
        /// The PlayMode tests' avatar checks on the same fixture and the same procedural rig, with
        /// the rig's pose computed here by forward kinematics of the retargeter's rig-space rotations.
        /// </summary>
        [Test]
        public void TheCommittedFixtureDrivesTheProceduralAvatarWithinThePlayModeBands()
        {
            TestPaths.RequireEngine();
            var fixture = Path.Combine(TestPaths.RequireRepoRoot(), "Packages", "com.mocap.imu", "Tests", "Runtime", "Fixtures", "walk.cap");
            Assert.IsTrue(File.Exists(fixture), "the PlayMode fixture is missing: scripts/make_test_fixtures.sh");
            using var model = MocapModel.Open(TestPaths.ModelPath);
            var capture = new SynthCapture { CapturePath = fixture };
            using var session = SolverReplay.OpenCalibratedReplay(capture, model.Info.FrameRate);
            using var solver = MocapSolver.Open(model);
            solver.AddCharacter(session);
            solver.Start();
            session.Start();
            var poses = SolverReplay.DrainAll(solver)[0];
            Assert.Greater(poses.Count, 120);

            var layout = HumanoidLayout.FromSkeleton(model.Info.Skeleton);
            var rig = HumanoidLayout.ToRig(layout);
            var retargeter = new RestPoseRetargeter(model.Info.Skeleton, rig);
            var smpl = new SmplPose();
            float restHips = layout[0].RootPosition.Y;
            var world = new Vec3[rig.Count];
            Vec3 firstHips = default;
            float moved = 0f;
            for (int i = 0; i < poses.Count; i++)
            {
                poses[i].CopyTo(smpl);
                retargeter.Retarget(smpl);
                var rotations = retargeter.Rotations;
                for (int b = 0; b < rig.Count; b++)
                {
                    Assert.IsTrue(retargeter.LocalRotations[b].IsFinite, $"pose {i}: {rig[b].Bone} not finite");
                    int p = rig.ParentIndex(b);
                    world[b] = p < 0 ? retargeter.HipsPosition
                        : world[p] + rotations[p] * (rig[b].RestPosition - rig[p].RestPosition);
                }
                float hipsY = world[0].Y;
                Assert.That(hipsY, Is.InRange(0.75f * restHips, 1.15f * restHips), $"pose {i}: hips height");
                foreach (var foot in new[] { HumanBone.LeftFoot, HumanBone.RightFoot, HumanBone.LeftToes, HumanBone.RightToes })
                    Assert.GreaterOrEqual(world[rig.IndexOf(foot)].Y, -0.03f, $"pose {i}: {foot} below the floor");
                if (i == 0) firstHips = world[0];
                moved = Math.Max(moved, Vec3.Distance(firstHips, world[0]));
            }
            TestContext.WriteLine($"{poses.Count} poses; hips moved up to {moved:F3} m");
            Assert.Greater(moved, 0.001f, "the avatar did not move");
        }
    }
}
