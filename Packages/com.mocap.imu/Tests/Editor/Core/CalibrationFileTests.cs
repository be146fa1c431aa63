// Calibration data from C#: read from a calibrated session, saved, loaded and applied to a new
// session, which must then produce calibrated bones from its first frame on.

using System;
using System.IO;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class CalibrationFileTests
    {
        SynthCapture _capture;
        CalibrationData _calibration;
        string _dir;

        [OneTimeSetUp]
        public void Calibrate()
        {
            TestPaths.RequireEngine();
            _capture = TestPaths.Synth("walk", seconds: 6);
            _calibration = Replay.Run(_capture).Calibration;
            Assert.IsTrue(_calibration.IsComplete, "the replay calibrated every sensor");
            _dir = TestPaths.NewTempDirectory("calibration");
        }

        static unsafe bool SameBytes(CalibrationData a, CalibrationData b)
        {
            var x = new ReadOnlySpan<byte>(&a, sizeof(CalibrationData));
            var y = new ReadOnlySpan<byte>(&b, sizeof(CalibrationData));
            return x.SequenceEqual(y);
        }

        [Test]
        public void SaveThenLoadIsExact()
        {
            var path = Path.Combine(_dir, "exact.calibration");
            _calibration.Save(path);
            StringAssert.StartsWith("mocap-calibration 2", File.ReadAllText(path));
            CollectionAssert.Contains(File.ReadAllLines(path), "sensors pelvis left_wrist right_wrist left_shin right_shin head",
                "the file names its sensors by segment, in the session's order");
            var loaded = CalibrationData.Load(path);
            Assert.IsTrue(SameBytes(_calibration, loaded), "%.9g round-trips every float exactly");
            Assert.AreEqual(0x3Fu, loaded.ValidMask);
            Assert.AreEqual(0x3Fu, loaded.HeadingMask);
        }

        [Test]
        public void AccessorsReadTheFileValues()
        {
            var path = Path.Combine(_dir, "values.calibration");
            _calibration.Save(path);
            var lines = File.ReadAllLines(path);
            string line = Array.Find(lines, l => l.StartsWith("left_shin.sensor_to_bone "));
            Assert.IsNotNull(line);
            var numbers = line.Split(' ');
            var m = _calibration.GetSensorToBone(_calibration.EntryOf(MocapSegment.LeftShin));
            for (int k = 0; k < 9; k++)
                Assert.AreEqual(float.Parse(numbers[1 + k], System.Globalization.CultureInfo.InvariantCulture), m[k / 3, k % 3],
                    $"left_shin.sensor_to_bone[{k}]");
            line = Array.Find(lines, l => l.StartsWith("head.acceleration_offset "));
            var offset = _calibration.GetAccelerationOffset(_calibration.EntryOf(MocapSegment.Head));
            Assert.AreEqual(float.Parse(line.Split(' ')[2], System.Globalization.CultureInfo.InvariantCulture), offset.Y);
            Assert.AreEqual(9.81, offset.Y, 0.5, "gravity is on model +Y in the T-pose");
        }

        [Test]
        public void LoadedCalibrationAppliesToANewSessionFromTheFirstFrame()
        {
            var path = Path.Combine(_dir, "apply.calibration");
            _calibration.Save(path);
            var run = Replay.Run(_capture, CalibrationData.Load(path));
            Assert.AreEqual(CalibrationState.Idle, run.Heading.State, "nothing was scheduled");
            Assert.IsTrue(run.Frames[0].IsCalibrated, "calibrated from the first frame on");
            Assert.IsTrue(SameBytes(_calibration, run.Calibration));
            var (mean, max, _, compared) = Replay.CompareWithTruth(run.Frames, new TruthTable(_capture.TruthPath));
            Assert.Greater(compared, 300);
            for (int s = 0; s < 6; s++)
                Assert.Less(mean[s], 0.6, $"{(MocapSegment)s} mean angle error with the loaded calibration");
        }

        [Test]
        public void HandEditedCalibrationStillGetsItsStructSize()
        {
            // default(CalibrationData) has struct_size 0; the bindings fill it in on the way out.
            var manual = default(CalibrationData);
            for (int s = 0; s < _calibration.SensorCount; s++)
            {
                int entry = manual.AddSensor(_calibration.GetSegment(s));
                Assert.AreEqual(s, entry);
                manual.SetWorldToModel(entry, _calibration.GetWorldToModel(s));
                manual.SetSensorToBone(entry, _calibration.GetSensorToBone(s));
                manual.SetAccelerationOffset(entry, _calibration.GetAccelerationOffset(s));
            }
            manual.ValidMask = manual.HeadingMask = 0x3F;
            var path = Path.Combine(_dir, "manual.calibration");
            manual.Save(path);
            Assert.IsTrue(SameBytes(_calibration, CalibrationData.Load(path)));
        }

        [Test]
        public void LoadingAMissingFileNamesIt()
        {
            var path = Path.Combine(_dir, "nope.calibration");
            var e = Assert.Throws<MocapException>(() => CalibrationData.Load(path));
            Assert.AreEqual(MocapStatus.NotFound, e.Status);
            StringAssert.Contains(path, e.Message);
        }

        [Test]
        public void LoadingABrokenFileNamesTheLine()
        {
            var path = Path.Combine(_dir, "broken.calibration");
            _calibration.Save(path);
            var lines = File.ReadAllLines(path);
            int index = Array.FindIndex(lines, l => l.StartsWith("right_wrist.world_to_model "));
            lines[index] = "right_wrist.world_to_model 1 0 0 0 1 0 0 0 banana";
            File.WriteAllLines(path, lines);
            var e = Assert.Throws<MocapException>(() => CalibrationData.Load(path));
            Assert.AreEqual(MocapStatus.Format, e.Status);
            StringAssert.Contains(path, e.Message);
            StringAssert.Contains($"line {index + 1}", e.Message);
        }

        [Test]
        public void NonFiniteCalibrationIsRefused()
        {
            var bad = _calibration;
            int head = bad.EntryOf(MocapSegment.Head);
            var m = bad.GetWorldToModel(head);
            m.M11 = float.NaN;
            bad.SetWorldToModel(head, m);
            using var session = MocapSession.Open(SessionConfig.Replay(_capture.CapturePath));
            var e = Assert.Throws<MocapException>(() => session.Calibration = bad);
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("NaN", e.Message);
            Assert.Throws<MocapException>(() => bad.Save(Path.Combine(_dir, "nan.calibration")));
        }

        [Test]
        public void RestartCarriesCalibrationsOnlyToTheSameSensors()
        {
            // What MocapSessionComponent.Restart keeps: by character, only while the character
            // list is unchanged and each character still reads the same sensors.
            var headingOnly = default(CalibrationData);
            headingOnly.HeadingMask = 0x3Fu;
            SessionConfig Playback() => SessionConfig.Replay(_capture.CapturePath, realtime: true);
            SessionConfig Port() => SessionConfig.Serial("/dev/ttyUSB7");
            var before = new[] { Playback(), Port() };
            var calibrations = new CalibrationData?[] { _calibration, headingOnly };

            // Same characters; the rate, the pacing and the recording differ: carried.
            var again = new[] { Playback(), Port() };
            again[0].OutputRateHz = 30f;
            again[0].ReplayRealtime = false;
            again[1].CapturePath = Path.Combine(_dir, "now-recording.cap");
            var carried = CalibrationCarry.Match(before, calibrations, again);
            Assert.AreEqual(2, carried.Length);
            Assert.IsTrue(carried[0].HasValue && SameBytes(_calibration, carried[0].Value));
            Assert.AreEqual(0x3Fu, carried[1]?.HeadingMask);
            using (var session = MocapSession.Open(again[0]))
            {
                session.Calibration = carried[0].Value;
                Assert.AreEqual(0x3Fu, session.Calibration.ValidMask, "the carried calibration applies");
            }

            // A character added or removed: nothing is carried, and no index runs past the end.
            carried = CalibrationCarry.Match(before, calibrations, new[] { Playback(), Port(), SessionConfig.Serial("COM9") });
            Assert.AreEqual(3, carried.Length);
            Assert.That(carried, Has.All.Null);
            carried = CalibrationCarry.Match(before, calibrations, new[] { Port() });
            Assert.AreEqual(1, carried.Length);
            Assert.IsNull(carried[0], "the port's calibration does not move to index 0's old owner, nor the reverse");

            // Reordered, or another sensor on a segment: not carried to the other sensors.
            carried = CalibrationCarry.Match(before, calibrations, new[] { Port(), Playback() });
            Assert.That(carried, Has.All.Null);
            var rewired = new[] { Playback(), Port() };
            int headSensor = rewired[1].IndexOf(MocapSegment.Head);
            rewired[1].Sensors[headSensor] = new SessionSensor(MocapSegment.Head, 9);
            carried = CalibrationCarry.Match(before, calibrations, rewired);
            Assert.IsTrue(carried[0].HasValue, "the unchanged character keeps its calibration");
            Assert.IsNull(carried[1], "new node ids are other sensors");
            var otherPort = new[] { Playback(), SessionConfig.Serial("/dev/ttyUSB8") };
            Assert.IsNull(CalibrationCarry.Match(before, calibrations, otherPort)[1]);

            Assert.That(CalibrationCarry.Match(null, null, again), Has.Length.EqualTo(2).And.All.Null, "a first open carries nothing");
        }

        [Test]
        public void SavingIntoAMissingDirectoryFails()
        {
            var path = Path.Combine(_dir, "no-such-dir", "x.calibration");
            var e = Assert.Throws<MocapException>(() => _calibration.Save(path));
            StringAssert.Contains("no-such-dir", e.Message);
            TestContext.WriteLine($"{e.Status}: {e.Message}");
        }
    }
}
