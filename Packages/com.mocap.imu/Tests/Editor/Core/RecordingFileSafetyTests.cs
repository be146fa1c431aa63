// The core's file writers replace a file instead of rewriting it in place (a failure part way
// leaves the previous file and no temporary behind), the binary pose writer reports the first
// write failure rather than a later one from Dispose, and every reader turns a file-system error
// into a MocapException naming the file. Real files in scratch folders; /dev/full (Linux) is the
// full disk.

using System;
using System.IO;
using System.Linq;
using System.Text;
using System.Text.RegularExpressions;
using Mocap.Imu.Capture;
using Mocap.Imu.Maths;
using Mocap.Imu.Recording;
using Mocap.Imu.Skeleton;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class RecordingFileSafetyTests
    {
        const string DevFull = "/dev/full";

        [Test]
        public void PoseRecordingSaveFailingPartWayKeepsThePreviousFile()
        {
            var (dir, path) = Target("poserec", "take.mcpose");
            new PoseRecording(30f, SmplSkeleton.Default, Poses(3)).Save(path);
            byte[] before = File.ReadAllBytes(path);

            // The writer stops at pose 5 after writing the header and poses 0-4.
            var bad = Poses(8);
            bad[5].SetJointPosition(7, new Vec3(float.NaN, 0f, 0f));
            var e = Assert.Throws<MocapException>(() => new PoseRecording(30f, SmplSkeleton.Default, bad).Save(path));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status, e.Message);
            StringAssert.Contains(path, e.Message);
            StringAssert.Contains("pose 5: joint 7 position is not finite", e.Message);
            AssertUnchangedAndAlone(dir, path, before);

            new PoseRecording(30f, SmplSkeleton.Default, Poses(8)).Save(path);
            Assert.AreEqual(8, PoseRecording.Load(path).Poses.Length, "a good save replaces the file");
            AssertAlone(dir, path);
        }

        [Test]
        public void PoseJsonSaveFailingPartWayKeepsThePreviousFile()
        {
            var (dir, path) = Target("posejson", "take.jsonl");
            PoseJsonLines.Save(path, Poses(3));
            byte[] before = File.ReadAllBytes(path);

            // 400 poses of about 1.5 KB each: most of the file is written before pose 399.
            var bad = Poses(400);
            bad[399].TimeSeconds = double.PositiveInfinity;
            var e = Assert.Throws<MocapException>(() => PoseJsonLines.Save(path, bad));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status, e.Message);
            StringAssert.Contains(path, e.Message);
            StringAssert.Contains("pose 399: time is not finite", e.Message);
            AssertUnchangedAndAlone(dir, path, before);

            PoseJsonLines.Save(path, Poses(5));
            Assert.AreEqual(5, PoseJsonLines.Load(path).Length, "a good save replaces the file");
            AssertAlone(dir, path);
        }

        [Test]
        public void FrameRecordingSaveFailingPartWayKeepsThePreviousFile()
        {
            var (dir, path) = Target("framecsv", "take.csv");
            FrameRecording.Save(path, Frames(3));
            byte[] before = File.ReadAllBytes(path);

            var bad = Frames(600);
            int head = bad[599].IndexOf(MocapSegment.Head);
            var sensor = bad[599].GetSensor(head);
            sensor.BoneAcceleration = new MocapVector3(0f, float.NaN, 0f);
            bad[599].SetSensor(head, sensor);
            var e = Assert.Throws<MocapException>(() => FrameRecording.Save(path, bad));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status, e.Message);
            StringAssert.Contains(path, e.Message);
            StringAssert.Contains("frame 599: head acceleration is not finite", e.Message);
            AssertUnchangedAndAlone(dir, path, before);

            FrameRecording.Save(path, Frames(5));
            Assert.AreEqual(5, FrameRecording.Load(path).Length, "a good save replaces the file");
            AssertAlone(dir, path);
        }

        [Test]
        public void BvhExportWritesATemporaryAndReplacesTheFile()
        {
            TestPaths.RequireEngine();
            if (Environment.OSVersion.Platform == PlatformID.Win32NT)
                Assert.Ignore("reads a replaced file through a handle opened before, which Windows does not allow");
            var (dir, path) = Target("bvhsafe", "take.bvh");
            var recording = new PoseRecording(30f, SmplSkeleton.Default, Poses(4));
            Assert.AreEqual(4, BvhExporter.Export(recording, path));
            byte[] before = File.ReadAllBytes(path);

            // A reader holding the previous file open keeps reading it whole: the engine wrote
            // another file, which then took the name (rewriting in place would truncate it).
            using (var held = new FileStream(path, FileMode.Open, FileAccess.Read, FileShare.ReadWrite | FileShare.Delete))
            {
                Assert.AreEqual(40, BvhExporter.Export(new PoseRecording(30f, SmplSkeleton.Default, Poses(40)), path));
                var seen = new MemoryStream();
                held.CopyTo(seen);
                CollectionAssert.AreEqual(before, seen.ToArray(), "the file open before the export was not rewritten");
            }
            Assert.AreEqual(40, BvhFile.Load(path).FrameCount);
            AssertAlone(dir, path);

            // Replacing fails (the name is a folder): an error naming it, no temporary left.
            var folder = Path.Combine(dir, "folder.bvh");
            Directory.CreateDirectory(folder);
            var e = Assert.Throws<MocapException>(() => BvhExporter.Export(recording, folder));
            StringAssert.Contains(folder, e.Message);
            CollectionAssert.AreEquivalent(new[] { path, folder }, Directory.GetFileSystemEntries(dir), "no temporary left");
            Assert.IsEmpty(Directory.GetFileSystemEntries(folder));
        }

        [Test]
        public void PoseWriterFailureIsNotReplacedByTheFlushOfDispose()
        {
            RequireFullDisk();
            var writer = PoseRecordingWriter.Create(DevFull, 30f, SmplSkeleton.Default);
            Exception first = null;
            var thrown = Assert.Catch(() =>
            {
                using (writer)
                {
                    try
                    {
                        // 7,600 bytes, more than the stream's buffer: written (and refused) now.
                        writer.Append(Poses(10));
                    }
                    catch (Exception e)
                    {
                        first = e;
                        throw;
                    }
                }
            });
            Assert.IsNotNull(first, "Append met the full disk");
            Assert.AreSame(first, thrown, "the failure of Append reaches the caller, not one of Dispose's flush");
            var failure = (MocapException)first;
            Assert.AreEqual(MocapStatus.IO, failure.Status, failure.Message);
            StringAssert.Contains(DevFull, failure.Message);
            var again = Assert.Throws<ObjectDisposedException>(() => writer.Append(Poses(1)));
            StringAssert.Contains(DevFull, again.Message);
        }

        [Test]
        public void PoseWriterDisposeReportsAFailedFlush()
        {
            RequireFullDisk();
            var writer = PoseRecordingWriter.Create(DevFull, 30f, SmplSkeleton.Default);
            writer.Append(Poses(1)); // buffered: the disk is met by Dispose's flush
            var e = Assert.Throws<MocapException>(() => writer.Dispose());
            Assert.AreEqual(MocapStatus.IO, e.Status, e.Message);
            StringAssert.Contains(DevFull, e.Message);
            Assert.DoesNotThrow(() => writer.Dispose(), "closed once");

            // A failed Append is repeated by the next one, then Dispose closes without a new error.
            writer = PoseRecordingWriter.Create(DevFull, 30f, SmplSkeleton.Default);
            var first = Assert.Throws<MocapException>(() => writer.Append(Poses(10)));
            var second = Assert.Throws<MocapException>(() => writer.Append(Poses(1)));
            StringAssert.Contains(first.Message, second.Message);
            Assert.DoesNotThrow(() => writer.Dispose());
        }

        [Test]
        public void ReadersNameAMissingFolder()
        {
            var missing = Path.Combine(TestPaths.NewTempDirectory("nofolder"), "no such folder", "x");
            foreach (var (name, read) in Readers())
            {
                var e = Assert.Throws<MocapException>(() => read(missing), name);
                Assert.AreEqual(MocapStatus.NotFound, e.Status, $"{name}: {e.Message}");
                StringAssert.Contains(missing, e.Message, name);
            }
        }

        [Test]
        public void ReadersNameAFolderPassedAsAFile()
        {
            var folder = TestPaths.NewTempDirectory("isfolder");
            foreach (var (name, read) in Readers())
            {
                var e = Assert.Throws<MocapException>(() => read(folder), name);
                TestContext.WriteLine(e.Message);
                Assert.AreEqual(MocapStatus.IO, e.Status, $"{name}: {e.Message}");
                StringAssert.Contains(folder, e.Message, name);
                StringAssert.Contains("is a directory", e.Message, name);
            }
        }

        [Test]
        public void PoseJsonFlagsAndCharacterBeyondTheirFieldsAreFormatErrors()
        {
            var dir = TestPaths.NewTempDirectory("jsonrange");
            var path = Path.Combine(dir, "poses.jsonl");
            PoseJsonLines.Save(path, Poses(2));
            string[] lines = File.ReadAllLines(path);

            string WithSecond(string key, string value)
            {
                var changed = Regex.Replace(lines[1], $"\"{key}\":\\d+", $"\"{key}\":{value}");
                Assert.AreNotEqual(lines[1], changed);
                File.WriteAllText(path, lines[0] + "\n" + changed + "\n");
                return path;
            }

            Assert.AreEqual((MocapPoseFlags)uint.MaxValue, PoseJsonLines.Load(WithSecond("flags", "4294967295"))[1].Flags);
            Assert.AreEqual(int.MaxValue, PoseJsonLines.Load(WithSecond("character", "2147483647"))[1].Character);
            foreach (var (key, value) in new[] { ("flags", "4294967296"), ("flags", "8589934593"), ("character", "2147483648"),
                                                 ("character", "4294967296") })
            {
                var e = Assert.Throws<MocapException>(() => PoseJsonLines.Load(WithSecond(key, value)), $"{key} {value}");
                Assert.AreEqual(MocapStatus.Format, e.Status, e.Message);
                StringAssert.Contains(path + " line 2", e.Message);
                StringAssert.Contains($"\"{key}\" is {value}", e.Message);
            }
        }

        static (string name, Action<string> read)[] Readers() => new (string, Action<string>)[]
        {
            ("PoseJsonLines.Load", p => PoseJsonLines.Load(p)),
            ("BvhFile.Load", p => BvhFile.Load(p)),
            ("PoseRecording.Load", p => PoseRecording.Load(p)),
            ("FrameRecording.Load", p => FrameRecording.Load(p)),
            ("CaptureReader", p => new CaptureReader(p).Dispose()),
        };

        static void RequireFullDisk()
        {
            if (!File.Exists(DevFull)) Assert.Ignore($"needs {DevFull} (a device whose writes fail with a full disk)");
        }

        static (string dir, string path) Target(string dirName, string fileName)
        {
            var dir = TestPaths.NewTempDirectory(dirName);
            return (dir, Path.Combine(dir, fileName));
        }

        static void AssertUnchangedAndAlone(string dir, string path, byte[] before)
        {
            CollectionAssert.AreEqual(before, File.ReadAllBytes(path), "the previous file is unchanged");
            AssertAlone(dir, path);
        }

        static void AssertAlone(string dir, string path) =>
            CollectionAssert.AreEqual(new[] { path }, Directory.GetFileSystemEntries(dir), "no temporary file left");

        // Poses with finite values that vary (identity rotations turned a little per frame).
        static MocapPose[] Poses(int count)
        {
            var poses = new MocapPose[count];
            for (int i = 0; i < count; i++)
            {
                poses[i].Sequence = (ulong)i;
                poses[i].FrameSequence = (ulong)(100 + i);
                poses[i].TimeSeconds = i / 30.0;
                poses[i].Flags = (MocapPoseFlags)1;
                poses[i].RootPosition = new Vec3(0.01f * i, 0.9f, 0f);
                for (int j = 0; j < MocapPose.JointCount; j++)
                {
                    float angle = 0.01f * i + 0.001f * j;
                    poses[i].SetJointRotation(j, new Quat(MathF.Sin(angle / 2), 0f, 0f, MathF.Cos(angle / 2)));
                    poses[i].SetJointPosition(j, new Vec3(0f, 0.05f * j, 0f));
                }
            }
            return poses;
        }

        static MocapFrame[] Frames(int count)
        {
            var frames = new MocapFrame[count];
            for (int i = 0; i < count; i++)
            {
                frames[i].Sequence = (ulong)i;
                frames[i].TimeSeconds = i / 60.0;
                frames[i].SensorCount = 6;
                for (int s = 0; s < 6; s++)
                    frames[i].SetSensor(s, new MocapSensorFrame
                    {
                        Segment = (MocapSegment)s,
                        BoneOrientation = new MocapQuaternion(1f, 0f, 0f, 0f),
                        BoneAcceleration = new MocapVector3(0f, 0f, 9.81f + 0.001f * i),
                        Flags = MocapSensorFlags.Valid,
                    });
            }
            return frames;
        }
    }
}
