// Every file reader of the core, fed damaged copies of a good file made by the engine or by the
// core's own writers: it either refuses the copy with a MocapException that names the file, or
// reads it into values that are all finite. Any other exception (IndexOutOfRange, Overflow,
// NullReference, ...) is a reader bug that would reach the user as a stack trace instead of a
// message; a NaN or infinity read in silence would reach Unity's transforms. The damage is
// deterministic (seeded), so a failure names a mutation that can be replayed.

using System;
using System.Collections.Generic;
using System.IO;
using System.Text;
using Mocap.Imu.Capture;
using Mocap.Imu.Recording;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class CorruptFileTests
    {
        const int MutationsPerFile = 120;

        SynthCapture _capture;
        PoseReplay _replay;
        MocapModel _model;
        MocapPose[] _poses;
        ReplayResult _run;
        string _dir;

        [OneTimeSetUp]
        public void MakeGoodFiles()
        {
            TestPaths.RequireEngine();
            _capture = TestPaths.Synth("walk", seconds: 6, seed: 3);
            _replay = TestPaths.ReplayPoses(_capture);
            _model = MocapModel.Open(TestPaths.ModelPath);
            _poses = PoseJsonLines.Load(_replay.JsonPath);
            _run = Replay.Run(_capture);
            _dir = TestPaths.NewTempDirectory("corrupt-files");
        }

        [OneTimeTearDown]
        public void CloseModel() => _model?.Dispose();

        [Test]
        public void PoseJsonLinesReadOrRefuseDamagedCopies() =>
            AssertEveryCopyIsReadOrRefused(File.ReadAllBytes(_replay.JsonPath), "poses.jsonl", text: true,
                                           path => AssertFinite(PoseJsonLines.Load(path)));

        [Test]
        public void BvhReadsOrRefusesDamagedCopies() =>
            AssertEveryCopyIsReadOrRefused(File.ReadAllBytes(_replay.BvhPath), "poses.bvh", text: true,
                                           path => BvhFile.Load(path));

        [Test]
        public void FrameRecordingReadsOrRefusesDamagedCopies()
        {
            var good = Path.Combine(_dir, "good-frames.csv");
            FrameRecording.Save(good, _run.Frames.ToArray());
            AssertEveryCopyIsReadOrRefused(File.ReadAllBytes(good), "frames.csv", text: true,
                                           path => AssertFinite(FrameRecording.Load(path)));
        }

        [Test]
        public void BinaryPoseRecordingReadsOrRefusesDamagedCopies()
        {
            var good = Path.Combine(_dir, "good.mcpose");
            new PoseRecording(_model.Info.FrameRate, _model.Info.Skeleton, _poses.AsSpan(0, 40)).Save(good);
            AssertEveryCopyIsReadOrRefused(File.ReadAllBytes(good), "poses.mcpose", text: false,
                                           path => AssertFinite(PoseRecording.Load(path).Poses));
        }

        [Test]
        public void CaptureReaderReadsOrRefusesDamagedCopies() =>
            // The capture reader skips damaged chunks rather than refusing the file: reading to the
            // end must still end cleanly.
            AssertEveryCopyIsReadOrRefused(File.ReadAllBytes(_capture.CapturePath), "capture.cap", text: false,
                                           path =>
                                           {
                                               using var reader = new CaptureReader(path);
                                               int records = 0;
                                               while (reader.TryReadNext(out _)) records++;
                                               Assert.IsTrue(reader.IsEnded, "reading stopped before the end");
                                           });

        void AssertEveryCopyIsReadOrRefused(byte[] good, string name, bool text, Action<string> load)
        {
            load(Write(name, good)); // the unharmed file reads
            int refused = 0;
            int seed = 20261122;
            foreach (char c in name) seed = seed * 31 + c; // string.GetHashCode differs per process
            var random = new Random(seed);
            for (int i = 0; i < MutationsPerFile; i++)
            {
                var (what, bytes) = text ? DamageText(good, random) : DamageBinary(good, random);
                string path = Write(name, bytes);
                try
                {
                    load(path);
                }
                catch (AssertionException)
                {
                    TestContext.WriteLine($"copy {i} ({what}) read into non-finite values");
                    throw;
                }
                catch (MocapException e)
                {
                    refused++;
                    StringAssert.Contains(name, e.Message, $"copy {i} ({what}): the message names the file");
                }
                catch (Exception e)
                {
                    Assert.Fail($"copy {i} ({what}): {e.GetType().Name} instead of a MocapException: {e.Message}");
                }
            }
            TestContext.WriteLine($"{name}: {MutationsPerFile} damaged copies, {refused} refused, the rest read");
            Assert.Greater(refused, 0, "no damaged copy was refused: the mutations do not reach the reader");
        }

        static void AssertFinite(MocapPose[] poses)
        {
            foreach (var p in poses)
            {
                Assert.IsTrue(double.IsFinite(p.TimeSeconds) && p.RootPosition.IsFinite && p.RootVelocity.IsFinite &&
                              float.IsFinite(p.LeftFootContact) && float.IsFinite(p.RightFootContact),
                              $"pose {p.Sequence}: a root value is not finite");
                for (int j = 0; j < MocapPose.JointCount; j++)
                    Assert.IsTrue(p.GetJointRotation(j).IsFinite && p.GetJointPosition(j).IsFinite,
                                  $"pose {p.Sequence}: joint {j} is not finite");
            }
        }

        static void AssertFinite(MocapFrame[] frames)
        {
            foreach (var f in frames)
            {
                Assert.IsTrue(double.IsFinite(f.TimeSeconds), $"frame {f.Sequence}: time is not finite");
                for (int s = 0; s < f.SensorCount; s++)
                {
                    var sensor = f.GetSensor(s);
                    var q = sensor.BoneOrientation;
                    var a = sensor.BoneAcceleration;
                    Assert.IsTrue(float.IsFinite(q.W) && float.IsFinite(q.X) && float.IsFinite(q.Y) && float.IsFinite(q.Z) &&
                                  float.IsFinite(a.X) && float.IsFinite(a.Y) && float.IsFinite(a.Z),
                                  $"frame {f.Sequence}: sensor {s} is not finite");
                }
            }
        }

        string Write(string name, byte[] bytes)
        {
            var path = Path.Combine(_dir, name);
            File.WriteAllBytes(path, bytes);
            return path;
        }

        // Values a number field might be damaged into: beyond float range, not numbers, huge
        // integers, empty, signs and exponents alone.
        static readonly string[] OddNumbers =
        {
            "1e39", "-7.7e39", "1e999", "nan", "NaN", "-inf", "Infinity", "99999999999999999999999",
            "-0", "", "e", "-", "1e", ".", "0x10", "1,5", "18446744073709551616", "-9223372036854775809",
        };

        static (string, byte[]) DamageText(byte[] good, Random random)
        {
            string s = Encoding.UTF8.GetString(good);
            var lines = new List<string>(s.Split('\n'));
            int line = random.Next(lines.Count);
            switch (random.Next(6))
            {
                case 0:
                {
                    // One number token on a line replaced by an odd one.
                    var tokens = lines[line].Split(' ', ',', '\t', '[', ']', ':');
                    string token = tokens[random.Next(tokens.Length)];
                    string odd = OddNumbers[random.Next(OddNumbers.Length)];
                    int at = token.Length > 0 ? lines[line].IndexOf(token, StringComparison.Ordinal) : -1;
                    if (at < 0) goto case 1;
                    lines[line] = lines[line].Substring(0, at) + odd + lines[line].Substring(at + token.Length);
                    return ($"line {line + 1}: '{token}' -> '{odd}'", Encoding.UTF8.GetBytes(string.Join("\n", lines)));
                }
                case 1:
                    lines.RemoveAt(line);
                    return ($"line {line + 1} removed", Encoding.UTF8.GetBytes(string.Join("\n", lines)));
                case 2:
                    lines.Insert(line, lines[line]);
                    return ($"line {line + 1} repeated", Encoding.UTF8.GetBytes(string.Join("\n", lines)));
                case 3:
                {
                    int cut = random.Next(good.Length);
                    return ($"cut at byte {cut}", good.AsSpan(0, cut).ToArray());
                }
                case 4:
                {
                    int at = random.Next(lines[line].Length + 1);
                    string junk = random.Next(2) == 0 ? "\u00e9\u0000{" : new string('9', 1 + random.Next(400));
                    lines[line] = lines[line].Insert(at, junk);
                    return ($"line {line + 1}: junk at column {at + 1}", Encoding.UTF8.GetBytes(string.Join("\n", lines)));
                }
                default:
                    return DamageBinary(good, random);
            }
        }

        static (string, byte[]) DamageBinary(byte[] good, Random random)
        {
            var bytes = (byte[])good.Clone();
            switch (random.Next(4))
            {
                case 0:
                {
                    int n = 1 + random.Next(8);
                    for (int k = 0; k < n; k++) bytes[random.Next(bytes.Length)] ^= (byte)(1 << random.Next(8));
                    return ($"{n} bits flipped", bytes);
                }
                case 1:
                {
                    // A float or count field overwritten: NaN, infinity, a huge or negative value.
                    // Half of the time inside the first 400 bytes, where the headers live.
                    int at = random.Next(2) == 0 ? random.Next(Math.Min(400, bytes.Length - 4)) : random.Next(bytes.Length - 4);
                    uint[] patterns = { 0x7fc00000u, 0x7f800000u, 0xff800000u, 0x7f7fffffu, 0xffffffffu, 0x80000000u, 0u };
                    uint p = patterns[random.Next(patterns.Length)];
                    BitConverter.GetBytes(p).CopyTo(bytes, at);
                    return ($"0x{p:x8} written at byte {at}", bytes);
                }
                case 2:
                {
                    int cut = random.Next(bytes.Length);
                    return ($"cut at byte {cut}", bytes.AsSpan(0, cut).ToArray());
                }
                default:
                {
                    int at = random.Next(bytes.Length);
                    int n = 1 + random.Next(64);
                    var longer = new byte[bytes.Length + n];
                    Array.Copy(bytes, longer, at);
                    for (int k = 0; k < n; k++) longer[at + k] = (byte)random.Next(256);
                    Array.Copy(bytes, at, longer, at + n, bytes.Length - at);
                    return ($"{n} random bytes inserted at byte {at}", longer);
                }
            }
        }
    }
}
