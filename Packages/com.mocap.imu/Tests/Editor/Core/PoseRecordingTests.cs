// Pose recordings: the engine's JSON lines and BVH (read by C#, the BVH by a reader written
// independently of the engine's writer) and the package's binary format (written and read).

using System;
using System.IO;
using System.Linq;
using System.Runtime.InteropServices;
using System.Text.RegularExpressions;
using Mocap.Imu.Maths;
using Mocap.Imu.Recording;
using Mocap.Imu.Skeleton;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class PoseRecordingTests
    {
        SynthCapture _capture;
        MocapModel _model;
        MocapPose[] _json;

        [OneTimeSetUp]
        public void ReplayWithTheEngine()
        {
            TestPaths.RequireEngine();
            _capture = TestPaths.Synth("walk", seconds: 6, seed: 3);
            _model = MocapModel.Open(TestPaths.ModelPath);
            _json = PoseJsonLines.Load(TestPaths.ReplayPoses(_capture).JsonPath);
            Assert.Greater(_json.Length, 100);
        }

        [OneTimeTearDown]
        public void CloseModel() => _model?.Dispose();

        [TestCase("zxy")]
        [TestCase("xyz")]
        public void BvhOfTheEngineMatchesItsJsonPoses(string order)
        {
            var replay = TestPaths.ReplayPoses(_capture, order);
            var json = PoseJsonLines.Load(replay.JsonPath);
            var bvh = BvhFile.Load(replay.BvhPath);

            Assert.AreEqual(json.Length, bvh.FrameCount, "one BVH frame per pose");
            Assert.AreEqual(1.0 / _model.Info.FrameRate, bvh.FrameTime, 1e-8, "frame time");
            Assert.AreEqual(24, bvh.Joints.Count);
            Assert.AreEqual(6 + 23 * 3, bvh.ChannelCount);
            string expectedOrder = order == "zxy" ? "ZrotationXrotationYrotation" : "XrotationYrotationZrotation";
            Assert.AreEqual(expectedOrder, string.Concat(bvh.Joints[1].Channels));

            var map = bvh.SmplJointMap();
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
            {
                var joint = bvh.Joints[map[j]];
                int parent = SmplSkeleton.ParentOf(j);
                Assert.AreEqual(parent < 0 ? -1 : map[parent], joint.Parent, $"{joint.Name} parent");
                SolverReplay.AssertVec(_model.Info.RestOffsets[j], joint.Offset, 1e-6f, $"{joint.Name} offset");
                Assert.AreEqual(joint.Parent >= 0 && !bvh.Joints.Any(c => c.Parent == map[j]), joint.EndSite.HasValue && j > 0,
                                $"{joint.Name}: End Sites exactly on the leaves");
            }
            var skeleton = bvh.ToSmplSkeleton(map);
            Assert.AreEqual(_model.Info.Skeleton.RestPosition((int)SmplJoint.LeftHand), skeleton.RestPosition((int)SmplJoint.LeftHand));

            double worst = SolverReplay.AssertBvhMatchesPoses(bvh, map, json, "BVH and JSON");
            TestContext.WriteLine($"{bvh.FrameCount} frames, worst rotation difference {worst:G3} deg");
        }

        [Test]
        public void BvhRotationsAreIntrinsicInTheListedOrder()
        {
            // Zrotation 90 then Xrotation 90 (intrinsic: R = Rz Rx): Rx turns +Y to +Z, Rz keeps
            // +Z, so the child at +Y lands at +Z. Extrinsic composition (R = Rx Rz) would put it
            // at -X instead, so this pins the convention without using the reader's own maths.
            const string text = @"HIERARCHY
ROOT hips
{
  OFFSET 0 1 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT chest
  {
    OFFSET 0 0.5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 0.2 0
    }
  }
}
ROOT prop
{
  OFFSET 2 0 0
  CHANNELS 3 Yrotation Xrotation Zrotation
}
MOTION
Frames: 2
Frame Time: 0.04
0 1 0 90 90 0 0 0 0 0 0 0
1 2 3 0 0 0 90 0 0 90 90 0
";
            var bvh = BvhFile.Parse(text, "inline");
            Assert.AreEqual(3, bvh.Joints.Count);
            Assert.AreEqual(-1, bvh.Joints[2].Parent, "a second ROOT");
            Assert.AreEqual(12, bvh.ChannelCount);
            Assert.AreEqual(0.04, bvh.FrameTime);
            var global = new Quat[3];
            var positions = new Vec3[3];
            bvh.ForwardKinematics(0, global, positions);
            SolverReplay.AssertVec(new Vec3(0, 1, 0), positions[0], 1e-6f, "root");
            SolverReplay.AssertVec(new Vec3(0, 1, 0.5f), positions[1], 1e-6f, "child after Rz(90) Rx(90)");
            SolverReplay.AssertVec(new Vec3(0, 0, 1), global[0] * Vec3.UnitY, 1e-6f, "root +Y");
            SolverReplay.AssertVec(new Vec3(0, 1, 0), global[0] * Vec3.UnitX, 1e-6f, "root +X");

            bvh.ForwardKinematics(1, global, positions);
            SolverReplay.AssertVec(new Vec3(1, 2, 3), positions[0], 1e-6f, "position channels replace the OFFSET");
            // chest: Zrotation 90 turns its frame: +X -> +Y.
            SolverReplay.AssertVec(new Vec3(0, 1, 0), global[1] * Vec3.UnitX, 1e-6f, "chest Rz(90)");
            SolverReplay.AssertVec(new Vec3(2, 0, 0), positions[2], 1e-6f, "prop keeps its OFFSET");
            // R = Ry(90) Rx(90): +Y -> Rx -> +Z -> Ry(90) -> +X.
            SolverReplay.AssertVec(new Vec3(1, 0, 0), global[2] * Vec3.UnitY, 1e-6f, "prop Ry(90) Rx(90)");
        }

        [Test]
        public void MalformedBvhGivesClearErrors()
        {
            const string head = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n}\n";
            AssertFormat(() => BvhFile.Parse(head, "x.bvh"), "x.bvh", "MOTION");
            AssertFormat(() => BvhFile.Parse(head + "MOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n1 2\n", "x.bvh"),
                         "line 11", "2 values", "3 channels");
            AssertFormat(() => BvhFile.Parse(head + "MOTION\nFrames: 3\nFrame Time: 0.1\n1 2 3\n", "x.bvh"),
                         "says 3 frames", "holds 1");
            AssertFormat(() => BvhFile.Parse(head + "MOTION\nFrames: 1\nFrame Time: 0.1\n1 nan 3\n", "x.bvh"),
                         "'nan'");
            AssertFormat(() => BvhFile.Parse(head + "MOTION\nFrames: 1\nFrame Time: 0\n1 2 3\n", "x.bvh"), "frame time");
            AssertFormat(() => BvhFile.Parse(head.Replace("Xrotation", "Wrotation") + "MOTION\n", "x.bvh"),
                         "line 5", "unknown channel 'Wrotation'");
            AssertFormat(() => BvhFile.Parse("ROOT a\n", "x.bvh"), "line 1", "HIERARCHY");
            AssertFormat(() => BvhFile.Parse("HIERARCHY\nROOT a\n{\nOFFSET 0 0\n", "x.bvh"), "end of file");
            var e = Assert.Throws<MocapException>(() => BvhFile.Load(Path.Combine(TestPaths.NewTempDirectory("bvh"), "none.bvh")));
            Assert.AreEqual(MocapStatus.NotFound, e.Status);
            var plain = BvhFile.Parse(head + "MOTION\nFrames: 1\nFrame Time: 0.1\n1 2 3\n", "x.bvh");
            AssertFormat(() => plain.SmplJointMap(), "no joint 'pelvis'");
            Assert.AreEqual(0, plain.IgnoredTrailingLines);
            // A streaming writer stopped before it rewrote the count: whole and partial lines
            // after the counted frames are left out, and counted.
            var cut = BvhFile.Parse(head + "MOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n4 5 6\n7 8 9\n10 1", "x.bvh");
            Assert.AreEqual(2, cut.FrameCount);
            Assert.AreEqual(2, cut.IgnoredTrailingLines);
            Assert.AreEqual(6f, cut.GetChannel(1, 2));
        }

        [Test]
        public void JsonLinesRoundTripAndMalformedLinesNameTheLine()
        {
            var dir = TestPaths.NewTempDirectory("json");
            var path = Path.Combine(dir, "again.jsonl");
            PoseJsonLines.Save(path, _json);
            var again = PoseJsonLines.Load(path);
            Assert.AreEqual(_json.Length, again.Length);
            for (int i = 0; i < _json.Length; i++) SolverReplay.AssertSame(_json[i], again[i], $"pose {i}", 1e-6f);

            var lines = File.ReadAllLines(TestPaths.ReplayPoses(_capture).JsonPath);
            var broken = Path.Combine(dir, "broken.jsonl");
            File.WriteAllLines(broken, new[] { lines[0], lines[1].Substring(0, lines[1].Length / 2) });
            AssertFormat(() => PoseJsonLines.Load(broken), broken, "line 2");
            File.WriteAllLines(broken, new[] { lines[0].Replace("\"time_s\"", "\"when\"") });
            AssertFormat(() => PoseJsonLines.Load(broken), "line 1", "\"time_s\" is missing");
            File.WriteAllLines(broken, new[] { lines[0].Replace("\"joint_positions\":[[", "\"joint_positions\":[[1,") });
            AssertFormat(() => PoseJsonLines.Load(broken), "joint_positions[0]");
            // Numbers JSON allows but a float cannot hold are refused, not read as infinity.
            File.WriteAllLines(broken, new[] { Regex.Replace(lines[0], "\"joint_positions\":\\[\\[[^,]+", "\"joint_positions\":[[1e39") });
            AssertFormat(() => PoseJsonLines.Load(broken), "line 1", "joint_positions[0] item 0", "not a finite float");
            File.WriteAllLines(broken, new[] { Regex.Replace(lines[0], "\"time_s\":[^,]+", "\"time_s\":1e999") });
            AssertFormat(() => PoseJsonLines.Load(broken), "line 1", "\"time_s\" is not a finite number");
        }

        [Test]
        public void BinaryRecordingRoundTripsExactly()
        {
            var path = Path.Combine(TestPaths.NewTempDirectory("bin"), "poses.mcpose");
            var poses = (MocapPose[])_json.Clone();
            // Fill the fields JSON does not carry, so every byte of a record is exercised.
            for (int i = 0; i < poses.Length; i++)
            {
                poses[i].Character = i % 3;
                poses[i].NewestReceiveNs = 1_000_000_000L * i + 17;
                poses[i].FrameEmittedNs = poses[i].NewestReceiveNs + 5;
                poses[i].PoseEmittedNs = -i;
            }
            new PoseRecording(_model.Info.FrameRate, _model.Info.Skeleton, poses).Save(path);
            Assert.AreEqual(PoseRecording.RecordSize, 760, "a record is one mocap_pose");
            Assert.AreEqual(328 + 760L * poses.Length, new FileInfo(path).Length);

            var loaded = PoseRecording.Load(path);
            Assert.AreEqual(_model.Info.FrameRate, loaded.FrameRate);
            Assert.AreEqual(1, loaded.ContractVersion);
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
                Assert.AreEqual(_model.Info.Skeleton.RestOffset(j), loaded.Skeleton.RestOffset(j));
            Assert.AreEqual(poses.Length, loaded.Poses.Length);
            Assert.IsTrue(MemoryMarshal.AsBytes(poses.AsSpan()).SequenceEqual(MemoryMarshal.AsBytes(loaded.Poses.AsSpan())),
                          "every byte of every pose survives");
            Assert.AreEqual(poses[9].GetJointRotation(SmplJoint.RightKnee), loaded.Poses[9].GetJointRotation(SmplJoint.RightKnee));
        }

        [Test]
        public void StreamingWriterCountsFlushedPoses()
        {
            var path = Path.Combine(TestPaths.NewTempDirectory("stream"), "live.mcpose");
            var writer = PoseRecordingWriter.Create(path, _model.Info);
            writer.Append(_json.AsSpan(0, 10));
            writer.Flush();
            // A reader during recording sees what was flushed (the file is shared for reading).
            Assert.AreEqual(10, PoseRecording.Load(path).Poses.Length);
            writer.Append(in _json[10]);
            writer.Dispose();
            writer.Dispose();
            Assert.AreEqual(11, writer.Count);
            var loaded = PoseRecording.Load(path);
            Assert.AreEqual(11, loaded.Poses.Length);
            Assert.AreEqual(_json[10].Sequence, loaded.Poses[10].Sequence);
            Assert.AreEqual(0, loaded.DiscardedTailBytes);
            Assert.Throws<ObjectDisposedException>(() => writer.Append(in _json[0]));
        }

        [Test]
        public void AWriterStoppedBetweenFlushesLeavesALoadableFile()
        {
            // The writer's file buffer hands the OS whatever fits, so between two flushes the file
            // usually ends inside a record: what a crash (or a reader during recording) sees.
            var path = Path.Combine(TestPaths.NewTempDirectory("crash"), "live.mcpose");
            var writer = PoseRecordingWriter.Create(path, _model.Info);
            writer.Append(_json.AsSpan(0, 3));
            writer.Flush();
            for (int i = 3; i < 10; i++) writer.Append(in _json[i]);   // one pose per frame, as recorded
            long size = new FileInfo(path).Length;
            long body = size - PoseRecording.HeaderSize;
            Assert.AreNotEqual(0, body % PoseRecording.RecordSize, "the test needs a file ending inside a record");
            var loaded = PoseRecording.Load(path);
            Assert.AreEqual(body / PoseRecording.RecordSize, loaded.Poses.Length);
            Assert.GreaterOrEqual(loaded.Poses.Length, 3);
            Assert.AreEqual(body % PoseRecording.RecordSize, loaded.DiscardedTailBytes);
            for (int i = 0; i < loaded.Poses.Length; i++)
                Assert.AreEqual(_json[i].Sequence, loaded.Poses[i].Sequence, $"pose {i}");
            writer.Dispose();
            loaded = PoseRecording.Load(path);
            Assert.AreEqual(10, loaded.Poses.Length);
            Assert.AreEqual(0, loaded.DiscardedTailBytes);
        }

        [Test]
        public void MalformedBinaryRecordingsGiveClearErrors()
        {
            var dir = TestPaths.NewTempDirectory("badbin");
            var good = Path.Combine(dir, "good.mcpose");
            new PoseRecording(_model.Info.FrameRate, _model.Info.Skeleton, _json.AsSpan(0, 3)).Save(good);
            byte[] bytes = File.ReadAllBytes(good);

            AssertFormat(() => PoseRecording.Load(Write(dir, "short", bytes.AsSpan(0, 100).ToArray())), "shorter than the 328-byte header");
            var bad = (byte[])bytes.Clone();
            bad[0] = (byte)'X';
            AssertFormat(() => PoseRecording.Load(Write(dir, "magic", bad)), "not a pose recording");
            bad = (byte[])bytes.Clone();
            bad[8] = 9;
            AssertFormat(() => PoseRecording.Load(Write(dir, "version", bad)), "format version 9");
            // Fewer whole poses than the header counts is damage; a partial pose beyond them is not.
            AssertFormat(() => PoseRecording.Load(Write(dir, "partial", bytes.AsSpan(0, bytes.Length - 10).ToArray())),
                         "the header says 3 poses, the file holds 2 and 750 bytes of a partial pose");
            var longer = new byte[bytes.Length + 100];
            bytes.CopyTo(longer, 0);
            var tail = PoseRecording.Load(Write(dir, "tail", longer));
            Assert.AreEqual(3, tail.Poses.Length);
            Assert.AreEqual(100, tail.DiscardedTailBytes);
            AssertFormat(() => PoseRecording.Load(Write(dir, "missing", bytes.AsSpan(0, bytes.Length - 760).ToArray())),
                         "header says 3 poses, the file holds 2");
            bad = (byte[])bytes.Clone();
            BitConverter.GetBytes(float.NaN).CopyTo(bad, 20);
            AssertFormat(() => PoseRecording.Load(Write(dir, "rate", bad)), "frame rate");
            // A damaged pose (NaN where the engine never writes one) is named, not handed on.
            // (PoseRecording.Save refuses such poses; the streaming writer stores what it is given.)
            var damaged = _json.AsSpan(0, 3).ToArray();
            damaged[1].SetJointPosition(7, new Vec3(float.NaN, 0f, 0f));
            var damagedPath = Path.Combine(dir, "damaged.mcpose");
            WriteStreaming(damagedPath, damaged);
            AssertFormat(() => PoseRecording.Load(damagedPath), "pose 1: joint 7 position is not finite");
            damaged = _json.AsSpan(0, 3).ToArray();
            damaged[2].SetJointRotation(0, new Quat(0f, float.PositiveInfinity, 0f, 1f));
            WriteStreaming(damagedPath, damaged);
            AssertFormat(() => PoseRecording.Load(damagedPath), "pose 2: joint 0 rotation is not finite");
            var e = Assert.Throws<MocapException>(() => PoseRecording.Load(Path.Combine(dir, "none.mcpose")));
            Assert.AreEqual(MocapStatus.NotFound, e.Status);
        }

        [Test]
        public void BinaryRecordingTooLargeForMemoryIsAFormatError()
        {
            // Over 2 GiB of records cannot be read into one span: the reader must say so instead
            // of allocating gigabytes and failing with an OverflowException. A sparse file makes
            // the size without writing it.
            if (Environment.OSVersion.Platform == PlatformID.Win32NT)
                Assert.Ignore("needs a sparse file (NTFS would write the 2 GiB)");
            var dir = TestPaths.NewTempDirectory("hugebin");
            var path = Path.Combine(dir, "huge.mcpose");
            new PoseRecording(_model.Info.FrameRate, _model.Info.Skeleton, _json.AsSpan(0, 1)).Save(path);
            long records = int.MaxValue / PoseRecording.RecordSize + 1;
            try
            {
                using (var stream = new FileStream(path, FileMode.Open, FileAccess.Write))
                    stream.SetLength(PoseRecording.HeaderSize + records * PoseRecording.RecordSize);
                long before = GC.GetAllocatedBytesForCurrentThread();
                AssertFormat(() => PoseRecording.Load(path), path, $"{records} poses", "more than");
                Assert.Less(GC.GetAllocatedBytesForCurrentThread() - before, 64L << 20, "nothing the size of the file was allocated");
            }
            finally
            {
                File.Delete(path);
            }
        }

        [TestCase(false)]
        [TestCase(true)]
        public void BvhWithAHugeFrameCountIsAFormatError(bool engineBvh)
        {
            // A damaged "Frames:" must not size the motion array: 3 channels x 1e8 frames is 1.2 GB,
            // the engine's 75 channels x 1e8 more than an array holds.
            var dir = TestPaths.NewTempDirectory("hugebvh");
            var path = Path.Combine(dir, "damaged.bvh");
            string text = engineBvh
                ? File.ReadAllText(TestPaths.ReplayPoses(_capture).BvhPath)
                : "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n}\n" +
                  "MOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n4 5 6\n";
            var damaged = Regex.Replace(text, @"Frames:\s*\d+", "Frames: 100000000");
            Assert.AreNotEqual(text, damaged);
            File.WriteAllText(path, damaged);
            long before = GC.GetAllocatedBytesForCurrentThread();
            AssertFormat(() => BvhFile.Load(path), path, "line ", "says 100000000 frames");
            Assert.Less(GC.GetAllocatedBytesForCurrentThread() - before, 256L << 20, "the motion array follows the file, not the header");
        }

        void WriteStreaming(string path, MocapPose[] poses)
        {
            using var writer = PoseRecordingWriter.Create(path, _model.Info);
            writer.Append(poses);
        }

        static string Write(string dir, string name, byte[] bytes)
        {
            var path = Path.Combine(dir, name + ".mcpose");
            File.WriteAllBytes(path, bytes);
            return path;
        }

        static void AssertFormat(TestDelegate action, params string[] parts)
        {
            var e = Assert.Throws<MocapException>(action);
            TestContext.WriteLine(e.Message);
            Assert.AreEqual(MocapStatus.Format, e.Status, e.Message);
            foreach (var part in parts) StringAssert.Contains(part, e.Message);
        }
    }
}
