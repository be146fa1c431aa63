// EditMode: the capture fixture shipped in the package (Tests/Runtime/Fixtures/walk.cap, generated
// by `mocapctl synth`) is replayed through the core (session + model + solver), its poses drive a
// humanoid-like transform hierarchy built here, and TakeRecorder records N frames: the clip must
// last (N-1) frames of the model's rate and hold rotation curves for every driven bone; the saved
// take must also export to BVH.

using System.Collections.Generic;
using System.IO;
using System.Linq;
using System.Threading;
using Mocap.Imu.Editor;
using Mocap.Imu.Recording;
using Mocap.Imu.Retarget;
using Mocap.Imu.Skeleton;
using NUnit.Framework;
using UnityEditor;
using UnityEngine;

namespace Mocap.Imu.Tests
{
    public sealed class TakeRecorderTests
    {
        const string Fixture = "Packages/com.mocap.imu/Tests/Runtime/Fixtures/walk.cap";
        const string TestFolder = "Assets/Mocap Takes (test)";
        const int Frames = 90;

        static List<MocapPose> _poses;
        static float _frameRate;
        static ModelInfo _info;
        GameObject _avatar;
        Transform[] _bones;

        [OneTimeSetUp]
        public void ReplayTheFixture()
        {
            var capture = Path.GetFullPath(Fixture);
            if (!File.Exists(capture)) Assert.Inconclusive($"the capture fixture {Fixture} is missing");
            using var model = MocapModel.Open(Path.GetFullPath("Packages/com.mocap.imu/Runtime/Models/mocap_pose_fp32.onnx"),
                                              new ModelOptions { OnnxRuntimePath = OnnxRuntimeLocator.Find() });
            _info = model.Info;
            _frameRate = model.Info.FrameRate;
            var config = SessionConfig.Replay(capture);
            config.OutputRateHz = _frameRate;
            using var session = MocapSession.Open(config);
            // The fixture's prelude (mocapctl synth): sensors still 0-3 s, T-pose 5-8 s after the first record.
            double t0 = FirstReceiveSeconds(capture);
            session.ScheduleCalibration(CalibrationStep.Heading, t0 + 0.5, 2f);
            session.ScheduleCalibration(CalibrationStep.TPose, t0 + 5.5, 2f);
            using var solver = MocapSolver.Open(model);
            solver.AddCharacter(session);
            solver.Start();
            session.Start();
            _poses = new List<MocapPose>();
            var buffer = new MocapPose[64];
            var watch = System.Diagnostics.Stopwatch.StartNew();
            while (!solver.IsEndOfStream(0))
            {
                solver.Drain(0, buffer, out int n);
                for (int i = 0; i < n; i++) _poses.Add(buffer[i]);
                if (n == 0) Thread.Sleep(1);
                Assert.Less(watch.Elapsed.TotalSeconds, 60, "the fixture replay did not end");
            }
            Assert.Greater(_poses.Count, Frames, "the fixture gives enough poses");
        }

        // First record's receive time, seconds on the session clock (the core's capture reader).
        static double FirstReceiveSeconds(string capture)
        {
            using var reader = new Mocap.Imu.Capture.CaptureReader(capture);
            Assert.IsTrue(reader.TryReadNext(out var record), "the capture holds no records");
            return record.ReceiveNs * 1e-9;
        }

        [SetUp]
        public void BuildAvatar()
        {
            // A humanoid-like hierarchy mirroring the SMPL skeleton, named after HumanBodyBones,
            // identity rotations at rest (a T-pose rig), rest offsets converted to Unity's frame.
            _avatar = new GameObject("Test Avatar");
            _bones = new Transform[SmplSkeleton.JointCount];
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
            {
                if (!HumanoidBoneMap.IsMapped((SmplJoint)j)) continue;
                var bone = new GameObject(HumanoidBoneMap.Name(HumanoidBoneMap.ToHumanBone((SmplJoint)j))).transform;
                int parent = SmplSkeleton.ParentOf(j);
                bone.SetParent(parent < 0 ? _avatar.transform : _bones[parent], false);
                bone.localPosition = CoordinateConversion.ModelToUnity(_info.Skeleton.RestOffset(j)).ToUnity();
                _bones[j] = bone;
            }
        }

        [TearDown]
        public void Cleanup()
        {
            foreach (var running in TakeRecorder.Running.ToList()) running.Dispose();
            Object.DestroyImmediate(_avatar);
            if (AssetDatabase.IsValidFolder(TestFolder)) AssetDatabase.DeleteAsset(TestFolder);
        }

        void Apply(in MocapPose pose)
        {
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
            {
                if (_bones[j] == null) continue;
                _bones[j].localRotation = CoordinateConversion.ModelToUnity(pose.GetJointRotation(j)).ToUnity();
            }
            _bones[0].localPosition = CoordinateConversion.ModelToUnity(pose.RootPosition).ToUnity();
        }

        [Test]
        public void RecordingProducesAClipOfTheExpectedLengthWithRotationCurves()
        {
            var take = new PoseTake(_info);
            int index = 0;
            TakeRecorder.PoseSource source = (out MocapPose pose) => { pose = _poses[index]; return true; };
            var recorder = new TakeRecorder(_avatar, source, take, manualCapture: true);
            float dt = 1f / _frameRate;
            for (index = 0; index < Frames; index++)
            {
                Apply(_poses[index]);
                recorder.Capture(dt);
            }
            Assert.AreEqual(Frames, recorder.Frames);
            var result = recorder.Stop(TestFolder);

            Assert.AreEqual((Frames - 1) * dt, result.Clip.length, 0.5f * dt, "N snapshots span N-1 frames");
            var bindings = AnimationUtility.GetCurveBindings(result.Clip);
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
            {
                if (_bones[j] == null) continue;
                var path = AnimationUtility.CalculateTransformPath(_bones[j], _avatar.transform);
                var rotation = bindings.Where(b => b.path == path && b.propertyName.StartsWith("m_LocalRotation")).ToArray();
                Assert.AreEqual(4, rotation.Length, $"{path}: x, y, z, w rotation curves");
                var w = AnimationUtility.GetEditorCurve(result.Clip, rotation.First(b => b.propertyName == "m_LocalRotation.w"));
                Assert.GreaterOrEqual(w.length, 2, $"{path}: keys across the take");
            }
            var hips = AnimationUtility.CalculateTransformPath(_bones[0], _avatar.transform);
            Assert.IsTrue(bindings.Any(b => b.path == hips && b.propertyName == "m_LocalPosition.y"), "the hips move");

            Assert.IsTrue(result.ClipPath.StartsWith(TestFolder + "/") && result.ClipPath.EndsWith(".anim"), result.ClipPath);
            Assert.IsNotNull(AssetDatabase.LoadAssetAtPath<AnimationClip>(result.ClipPath), "the clip is an asset");
            Assert.AreEqual(Frames, result.Poses.Poses.Length, "one pose per snapshot");
            Assert.IsTrue(File.Exists(Path.GetFullPath(result.PosesPath)));

            var bvh = Path.Combine(Path.GetTempPath(), $"mocap-take-{System.Guid.NewGuid():N}.bvh");
            try
            {
                Assert.AreEqual(Frames, BvhExportMenu.Export(result.PosesPath, bvh));
                var file = BvhFile.Load(bvh);
                Assert.AreEqual(Frames, file.FrameCount);
                Assert.AreEqual(1.0 / _frameRate, file.FrameTime, 1e-6);
            }
            finally
            {
                File.Delete(bvh);
            }
        }

        [Test]
        public void TakesAreNumberedAndDisposingSavesNothing()
        {
            var first = new TakeRecorder(_avatar, manualCapture: true);
            first.Capture(0.1f);
            first.Capture(0.1f);
            var a = first.Stop(TestFolder, "Same");
            var second = new TakeRecorder(_avatar, manualCapture: true);
            second.Capture(0.1f);
            second.Capture(0.1f);
            var b = second.Stop(TestFolder, "Same");
            Assert.AreNotEqual(a.ClipPath, b.ClipPath, "a second take in the same second gets its own name");
            Assert.IsNull(a.Poses, "no pose source, no poses");
            Assert.AreEqual(0.1f, a.Clip.length, 1e-4f);

            var dropped = new TakeRecorder(_avatar, manualCapture: true);
            dropped.Capture(0.1f);
            dropped.Dispose();
            Assert.IsFalse(dropped.IsRecording);
            Assert.IsNull(TakeRecorder.For(_avatar));
            Assert.Throws<System.InvalidOperationException>(() => dropped.Capture(0.1f));
        }
    }
}
