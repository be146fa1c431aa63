// BVH export from C# through the engine's writer (BvhExporter over mocap_bvh_open/append/close):
// poses solved from a replay are exported, then read back with the package's own BVH reader
// (Recording/BvhFile.cs, written independently of the engine's writer) and compared with the
// poses; the file must also have the hierarchy `mocapctl replay --out` writes for the same capture.
// Also the editor take's engine-side half (PoseTake, TakeNaming).

using System;
using System.Collections.Generic;
using System.IO;
using System.Linq;
using Mocap.Imu.Maths;
using Mocap.Imu.Recording;
using Mocap.Imu.Skeleton;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class BvhExporterTests
    {
        SynthCapture _capture;
        MocapModel _model;
        List<MocapPose> _poses;

        [OneTimeSetUp]
        public void ReplayThroughTheSolver()
        {
            TestPaths.RequireEngine();
            _capture = TestPaths.Synth("walk", seconds: 6, seed: 3);
            _model = MocapModel.Open(TestPaths.ModelPath);
            _poses = SolverReplay.SolveOneCharacter(_capture, _model);
            Assert.Greater(_poses.Count, 100, "the replay produced poses");
        }

        [OneTimeTearDown]
        public void CloseModel() => _model?.Dispose();

        [TestCase(BvhRotationOrder.Zxy, "ZrotationXrotationYrotation")]
        [TestCase(BvhRotationOrder.Xyz, "XrotationYrotationZrotation")]
        public void ExportedPosesReadBackWithTheIndependentReader(BvhRotationOrder order, string channels)
        {
            var path = Path.Combine(TestPaths.NewTempDirectory("bvhexp"), "take.bvh");
            long frames;
            using (var exporter = BvhExporter.Create(path, _model.Info, new BvhExportOptions { RotationOrder = order }))
            {
                foreach (var pose in _poses) exporter.Append(pose);
                Assert.AreEqual(_poses.Count, exporter.FrameCount, "frames counted while writing");
                frames = exporter.Close();
            }
            Assert.AreEqual(_poses.Count, frames, "Close returns the frame count");

            var bvh = BvhFile.Load(path);
            Assert.AreEqual(_poses.Count, bvh.FrameCount, "one frame per pose");
            Assert.AreEqual(1.0 / _model.Info.FrameRate, bvh.FrameTime, 1e-8, "frame time = 1 / model rate");
            Assert.AreEqual(SmplSkeleton.JointCount, bvh.Joints.Count);
            Assert.AreEqual(6 + 23 * 3, bvh.ChannelCount, "root: position + rotation; others: rotation");
            Assert.AreEqual(channels, string.Concat(bvh.Joints[1].Channels));

            var map = bvh.SmplJointMap();
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
                SolverReplay.AssertVec(_model.Info.RestOffsets[j], bvh.Joints[map[j]].Offset, 1e-6f, $"{SmplSkeleton.NameOf(j)} offset");

            double worst = SolverReplay.AssertBvhMatchesPoses(bvh, map, _poses, "exported and solved");
            // The motion must not be trivially the rest pose, or the comparison proves nothing (the
            // shipped model may be untrained: any joint turning counts).
            double moved = 0;
            for (int f = 0; f < _poses.Count; f++)
                for (int j = 0; j < SmplSkeleton.JointCount; j++)
                    moved = Math.Max(moved, Quat.Angle(Quat.Identity, _poses[f].GetJointRotation(j)));
            Assert.Greater(moved * 180.0 / Math.PI, 1.0, "some joint turns by more than a degree");
            TestContext.WriteLine($"largest joint rotation {moved * 180.0 / Math.PI:0.0} deg");
            TestContext.WriteLine($"{bvh.FrameCount} frames, worst rotation difference {worst:G3} deg");
        }

        [Test]
        public void SameHierarchyAndFrameCountAsMocapctlReplayOut()
        {
            var replay = TestPaths.ReplayPoses(_capture, "zxy");
            var path = Path.Combine(TestPaths.NewTempDirectory("bvhexp"), "take.bvh");
            using (var exporter = BvhExporter.Create(path, _model.Info))
                exporter.Append(_poses.ToArray());

            string Hierarchy(string file) => File.ReadAllText(file).Split(new[] { "MOTION" }, StringSplitOptions.None)[0];
            Assert.AreEqual(Hierarchy(replay.BvhPath), Hierarchy(path), "the HIERARCHY section is the writer's, byte for byte");
            var ours = BvhFile.Load(path);
            var theirs = BvhFile.Load(replay.BvhPath);
            Assert.AreEqual(theirs.FrameCount, ours.FrameCount, "same poses, same frame count");
            Assert.AreEqual(theirs.FrameTime, ours.FrameTime);
            for (int f = 0; f < ours.FrameCount; f += 7)
                for (int j = 0; j < ours.Joints.Count; j++)
                {
                    double deg = Quat.Angle(theirs.GetLocalRotation(f, j), ours.GetLocalRotation(f, j)) * 180.0 / Math.PI;
                    Assert.Less(deg, 0.01, $"frame {f} joint {ours.Joints[j].Name}");
                }
        }

        [Test]
        public void ExportOfAPoseRecordingUsesItsRateUnlessOverridden()
        {
            var dir = TestPaths.NewTempDirectory("bvhexp");
            var recording = new PoseRecording(_model.Info.FrameRate, _model.Info.Skeleton, _poses.Take(50).ToArray(),
                                              _model.Info.ContractVersion);
            var recordingPath = Path.Combine(dir, "take.mcpose");
            recording.Save(recordingPath);
            var loaded = PoseRecording.Load(recordingPath);

            var own = Path.Combine(dir, "own.bvh");
            Assert.AreEqual(50, BvhExporter.Export(loaded, own));
            Assert.AreEqual(1.0 / _model.Info.FrameRate, BvhFile.Load(own).FrameTime, 1e-8);

            var slow = Path.Combine(dir, "slow.bvh");
            Assert.AreEqual(50, BvhExporter.Export(loaded, slow, new BvhExportOptions { FrameRate = 30, FlushEvery = 16 }));
            var bvh = BvhFile.Load(slow);
            Assert.AreEqual(50, bvh.FrameCount, "the header count is final after close even with flush_every 16");
            Assert.AreEqual(1.0 / 30, bvh.FrameTime, 1e-8);
        }

        [Test]
        public void AppendAllocatesNothing()
        {
            var path = Path.Combine(TestPaths.NewTempDirectory("bvhexp"), "alloc.bvh");
            using var exporter = BvhExporter.Create(path, _model.Info, new BvhExportOptions { FlushEvery = 64 });
            var poses = _poses.ToArray();
            exporter.Append(poses[0]);
            exporter.Append(poses.AsSpan(0, 1));
            long before = GC.GetAllocatedBytesForCurrentThread();
            for (int i = 0; i < 1000; i++)
            {
                exporter.Append(in poses[i % poses.Length]);
                if (i % 100 == 0) exporter.Append(poses.AsSpan(0, 4));
            }
            long allocated = GC.GetAllocatedBytesForCurrentThread() - before;
            Assert.AreEqual(0, allocated, "bytes allocated by 1,000 Append calls");
            Assert.AreEqual(2 + 1000 + 40, exporter.FrameCount);
        }

        [Test]
        public void ErrorsNameTheFileAndClosedExportersRefuse()
        {
            var dir = TestPaths.NewTempDirectory("bvhexp");
            var missing = Path.Combine(dir, "no such folder", "x.bvh");
            var e = Assert.Throws<MocapException>(() => BvhExporter.Create(missing, _model.Info));
            StringAssert.Contains("x.bvh", e.Message, "the engine's error names the file");

            Assert.Throws<ArgumentOutOfRangeException>(() => BvhExporter.Create(Path.Combine(dir, "a.bvh"), 0f, SmplSkeleton.Default));
            Assert.Throws<ArgumentOutOfRangeException>(() =>
                BvhExporter.Create(Path.Combine(dir, "b.bvh"), _model.Info, new BvhExportOptions { FrameRate = -1 }));

            var exporter = BvhExporter.Create(Path.Combine(dir, "c.bvh"), _model.Info);
            exporter.Append(_poses[0]);
            Assert.AreEqual(1, exporter.Close());
            Assert.IsTrue(exporter.IsClosed);
            Assert.AreEqual(1, exporter.Close(), "a second close returns the same count");
            Assert.AreEqual(1, exporter.FrameCount);
            Assert.Throws<ObjectDisposedException>(() => exporter.Append(_poses[1]));
            Assert.AreEqual(1, BvhFile.Load(Path.Combine(dir, "c.bvh")).FrameCount);
        }

        [Test]
        public void PoseTakeKeepsEachPoseOnceAndExports()
        {
            var take = new PoseTake(_model.Info);
            // An editor polls the latest pose every frame: the same pose comes back several times.
            foreach (var pose in _poses.Take(40))
            {
                Assert.IsTrue(take.Add(pose));
                Assert.IsFalse(take.Add(pose), "the same pose twice is kept once");
            }
            Assert.IsFalse(take.Add(_poses[10]), "an older pose is ignored");
            Assert.AreEqual(40, take.Count);
            Assert.AreEqual(_poses[39].TimeSeconds - _poses[0].TimeSeconds, take.DurationSeconds, 1e-9);
            Assert.AreEqual(39 / _model.Info.FrameRate, take.DurationSeconds, 0.5 / _model.Info.FrameRate,
                            "consecutive poses are one model frame apart");

            var recording = take.ToRecording();
            Assert.AreEqual(40, recording.Poses.Length);
            Assert.AreEqual(_model.Info.FrameRate, recording.FrameRate);
            var path = Path.Combine(TestPaths.NewTempDirectory("bvhexp"), "take.bvh");
            Assert.AreEqual(40, BvhExporter.Export(recording, path));
            Assert.AreEqual(40, BvhFile.Load(path).FrameCount);

            take.Clear();
            Assert.AreEqual(0, take.Count);
            Assert.IsTrue(take.Add(_poses[0]), "after Clear any pose is new again");
        }

        [Test]
        public void PoseTakeKeepsThePosesOfARestartedEngine()
        {
            // Loop playback and a recording restart open a new engine, which numbers its poses
            // from 0 again: the take keeps them as a new segment instead of dropping them.
            MocapPose Numbered(int index, ulong sequence)
            {
                var pose = _poses[index];
                pose.Sequence = sequence;
                return pose;
            }
            var take = new PoseTake(_model.Info);
            // The take begins mid-stream: engine poses 30..99.
            for (int i = 30; i < 100; i++)
            {
                Assert.IsTrue(take.Add(Numbered(i, (ulong)i)));
                Assert.IsFalse(take.Add(Numbered(i, (ulong)i)), "the latest pose handed in again is kept once");
            }
            Assert.IsFalse(take.Add(Numbered(95, 95)), "a pose a little older than the last is a duplicate");
            Assert.AreEqual(1, take.Segments);
            // The engine restarts: 0, 1, 2 ... again, for more than one second of frames.
            int second = (int)Math.Ceiling(_model.Info.FrameRate) + 20;
            Assert.Less(second, _poses.Count);
            for (int i = 0; i < second; i++)
            {
                Assert.IsTrue(take.Add(Numbered(i, (ulong)i)), $"pose {i} after the restart is kept");
                Assert.IsFalse(take.Add(Numbered(i, (ulong)i)));
            }
            Assert.IsFalse(take.Add(Numbered(second - 10, (ulong)second - 10)), "small duplicates within the new segment are still ignored");
            Assert.AreEqual(2, take.Segments);
            // A second restart, now below a segment that began at 0: the step back is larger than
            // a late duplicate can be (one second of frames).
            for (int i = 0; i < 10; i++) Assert.IsTrue(take.Add(Numbered(i, (ulong)i)), $"pose {i} after the second restart");
            Assert.AreEqual(3, take.Segments);
            Assert.AreEqual(70 + second + 10, take.Count);

            double expected = (_poses[99].TimeSeconds - _poses[30].TimeSeconds) + (_poses[second - 1].TimeSeconds - _poses[0].TimeSeconds) +
                              (_poses[9].TimeSeconds - _poses[0].TimeSeconds);
            Assert.AreEqual(expected, take.DurationSeconds, 1e-9, "the segments' spans, summed");

            var recording = take.ToRecording();
            Assert.AreEqual(80 + second, recording.Poses.Length);
            Assert.AreEqual(99ul, recording.Poses[69].Sequence, "the first segment, in order");
            Assert.AreEqual(0ul, recording.Poses[70].Sequence, "then the restarted engine's poses");
            Assert.AreEqual((ulong)second - 1, recording.Poses[69 + second].Sequence);
            Assert.AreEqual(0ul, recording.Poses[70 + second].Sequence);

            take.Clear();
            Assert.AreEqual(0, take.Segments);
            Assert.AreEqual(0, take.DurationSeconds);
        }

        [Test]
        public void CaptureNamesNeverReuseAnExistingFile()
        {
            // The engine's capture writer truncates an existing file: two recordings started
            // within one second (Start/Stop/Start, loop playback) must get different names.
            var dir = TestPaths.NewTempDirectory("capnames");
            var time = new DateTime(2024, 5, 1, 14, 3, 7, 123);
            var first = TakeNaming.CapturePath(dir, time, 0, "Robot/1 A", File.Exists);
            Assert.AreEqual(Path.Combine(dir, "20240501-140307-123-0-Robot_1_A.cap"), first);
            File.WriteAllText(first, "first recording");
            var later = TakeNaming.CapturePath(dir, time.AddMilliseconds(1), 0, "Robot/1 A", File.Exists);
            Assert.AreEqual(Path.Combine(dir, "20240501-140307-124-0-Robot_1_A.cap"), later, "milliseconds tell them apart");
            var same = TakeNaming.CapturePath(dir, time, 0, "Robot/1 A", File.Exists);
            Assert.AreNotEqual(first, same, "the same millisecond gets a counter");
            Assert.AreEqual(Path.Combine(dir, "20240501-140307-123-0-Robot_1_A-2.cap"), same);
            File.WriteAllText(same, "second recording");
            Assert.AreEqual(Path.Combine(dir, "20240501-140307-123-0-Robot_1_A-3.cap"),
                            TakeNaming.CapturePath(dir, time, 0, "Robot/1 A", File.Exists));
            Assert.AreEqual(Path.Combine(dir, "20240501-140307-123-1-character.cap"),
                            TakeNaming.CapturePath(dir, time, 1, null, File.Exists));
            Assert.AreEqual("first recording", File.ReadAllText(first));
        }

        [Test]
        public void TakeNamesAreTimestampedUniqueAndSafe()
        {
            var time = new DateTime(2024, 5, 1, 14, 3, 7);
            Assert.AreEqual("Take 2024-05-01 14-03-07", TakeNaming.TakeName(time));
            Assert.AreEqual("Robot_1 Take 2024-05-01 14-03-07", TakeNaming.TakeName(time, "Robot/1"));

            var taken = new HashSet<string> { "Assets/Mocap Takes/Take.anim", "Assets/Mocap Takes/Take 2.anim" };
            Assert.AreEqual("Assets/Mocap Takes/Take 3.anim",
                            TakeNaming.UniquePath("Assets/Mocap Takes/", "Take", "anim", taken.Contains));
            Assert.AreEqual("Assets/Mocap Takes/Other.anim",
                            TakeNaming.UniquePath("Assets\\Mocap Takes", "Other", ".anim", taken.Contains));
            Assert.AreEqual("Assets/Mocap Takes/a_b.anim", TakeNaming.UniquePath(TakeNaming.DefaultFolder, "a:b", ".anim", _ => false));
            Assert.AreEqual("Assets/Mocap Takes/Take 2.mcpose", TakeNaming.PosePathFor("Assets/Mocap Takes/Take 2.anim"));
        }
    }
}
