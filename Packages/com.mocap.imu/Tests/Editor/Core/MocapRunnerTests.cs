// The engine lifecycle the session component shows in the inspector, without Unity: open on a
// worker thread, drain poses each update, end, restart with calibrations carried, record, fail
// clearly. Against the real engine, model and generated captures.

using System;
using System.Collections.Generic;
using System.Diagnostics;
using System.IO;
using Mocap.Imu.Capture;
using Mocap.Imu.Maths;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class MocapRunnerTests
    {
        SynthCapture _walk, _mixed;

        [OneTimeSetUp]
        public void MakeCaptures()
        {
            TestPaths.RequireEngine();
            _walk = TestPaths.Synth("walk", seconds: 3, seed: 21);
            _mixed = TestPaths.Synth("mixed", seconds: 3, seed: 22);
        }

        static PlaybackCalibrationWindows PreludeWindows(SynthCapture capture) => new PlaybackCalibrationWindows(
            0.5f, (float)(capture.HeadingSeconds - 1.0),
            (float)(capture.HeadingSeconds + capture.StrapSeconds + 0.5), (float)(capture.TPoseSeconds - 1.0));

        static MocapRunCharacter Character(string name, SynthCapture capture, bool realtime = false, bool windows = true) =>
            new MocapRunCharacter
            {
                Name = name,
                Config = SessionConfig.Replay(capture.CapturePath, realtime),
                PlaybackWindows = windows ? PreludeWindows(capture) : (PlaybackCalibrationWindows?)null,
            };

        static MocapRunPlan Plan(params MocapRunCharacter[] characters) => new MocapRunPlan
        {
            ModelPath = TestPaths.ModelPath,
            Characters = characters,
        };

        /// <summary>Updates (as a frame loop would) until <paramref name="until"/> happens; the events seen.</summary>
        static List<MocapRunnerEvent> RunUntil(MocapRunner runner, MocapRunnerEvent until, double timeoutSeconds = 90)
        {
            var seen = new List<MocapRunnerEvent>();
            var watch = Stopwatch.StartNew();
            for (;;)
            {
                var e = runner.Update();
                if (e != MocapRunnerEvent.None) seen.Add(e);
                if (e == until || (e == MocapRunnerEvent.Failed && until != MocapRunnerEvent.Failed)) return seen;
                if (watch.Elapsed.TotalSeconds > timeoutSeconds)
                    Assert.Fail($"no {until} within {timeoutSeconds} s (status {runner.Status}, events {string.Join(",", seen)}): {runner.LastError}");
                System.Threading.Thread.Sleep(2);
            }
        }

        [Test]
        public void TwoReplaysOpenOffTheCallersThreadDrainEveryPoseInOrderAndEnd()
        {
            using var runner = new MocapRunner();
            var sequences = new[] { new List<ulong>(), new List<ulong>() };
            runner.PoseSolved += (int c, in MocapPose pose) => sequences[c].Add(pose.Sequence);
            Assert.IsTrue(runner.Open(Plan(Character("Ada", _walk), Character("Bo", _mixed))));
            Assert.AreEqual(MocapComponentStatus.Opening, runner.Status, "opening returns at once");
            Assert.AreEqual(0, runner.CharacterCount);
            Assert.IsFalse(runner.Open(Plan(Character("again", _walk))), "a second open while opening is refused");

            var events = RunUntil(runner, MocapRunnerEvent.Ended);
            CollectionAssert.AreEqual(new[] { MocapRunnerEvent.Opened, MocapRunnerEvent.Ended }, events);
            Assert.AreEqual(MocapComponentStatus.Ended, runner.Status);
            Assert.AreEqual(2, runner.CharacterCount);
            Assert.AreEqual("Bo", runner.GetCharacterName(1));
            for (int c = 0; c < 2; c++)
            {
                Assert.Greater(sequences[c].Count, 150, $"character {c} was solved");
                for (int i = 0; i < sequences[c].Count; i++)
                    Assert.AreEqual((ulong)i, sequences[c][i], $"character {c}: every pose once, in order");
                Assert.AreEqual((ulong)sequences[c].Count, runner.GetPoseCount(c));
                Assert.IsTrue(runner.TryGetLatestPose(c, out var latest));
                Assert.AreEqual(sequences[c][sequences[c].Count - 1], latest.Sequence, "the latest pose is the last drained");
                Assert.IsTrue(runner.GetSession(c).Calibration.IsComplete, "the capture's own windows calibrated it");
            }
            string status = runner.BuildStatusText();
            StringAssert.Contains("Ada: ", status);
            StringAssert.Contains($"{sequences[1].Count} poses, calibrated", status);
            Assert.AreEqual("", runner.Close());
            Assert.AreEqual(MocapComponentStatus.Idle, runner.Status);
            Assert.AreEqual(0, runner.CharacterCount);
            Assert.IsFalse(runner.TryGetLatestPose(0, out _) && runner.GetSession(0) != null);
        }

        [Test]
        public void AChestTheModelDoesNotReadDoesNotBlockCalibrationWhenAbsent()
        {
            // The shipped model reads the six; a character also listing a chest (node 6) that never
            // sends gets it marked optional by the runner, so the six calibrate and poses flow.
            using var runner = new MocapRunner();
            int poses = 0;
            runner.PoseSolved += (int c, in MocapPose pose) => poses++;
            var character = Character("Ada", _walk);
            character.Config.AddSensor(MocapSegment.Chest, 6);
            Assert.IsFalse(character.Config.Sensors[6].Optional, "the plan itself asks for a required chest");
            Assert.IsTrue(runner.Open(Plan(character)));
            RunUntil(runner, MocapRunnerEvent.Ended);
            var session = runner.GetSession(0);
            Assert.AreEqual(7, session.SensorCount);
            Assert.AreEqual(MocapSegment.Chest, session.SegmentOf(6));
            Assert.IsTrue(session.Config.Sensors[6].Optional, "the runner made the chest optional");
            var calibration = session.Calibration;
            Assert.IsTrue(calibration.IsValid(MocapSegment.Pelvis) && calibration.IsValid(MocapSegment.Head));
            Assert.IsFalse(calibration.IsValid(MocapSegment.Chest));
            Assert.IsTrue(session.GetCalibrationReport(CalibrationStep.TPose).TryGetSensor(MocapSegment.Chest, out var chest)
                          && chest.IsLeftOut, "left out, not refused");
            Assert.Greater(poses, 100, "the six calibrated: poses were solved");
        }

        [Test]
        public void ARestartCarriesEachCharactersCalibration()
        {
            using var runner = new MocapRunner();
            runner.Open(Plan(Character("Ada", _walk)));
            RunUntil(runner, MocapRunnerEvent.Ended);
            var first = runner.GetSession(0).Calibration;
            Assert.IsTrue(first.IsComplete);

            // Without its windows the capture would stay uncalibrated: only the carry calibrates it.
            Assert.IsTrue(runner.Restart(Plan(Character("Ada", _walk, windows: false))));
            RunUntil(runner, MocapRunnerEvent.Opened);
            var carried = runner.GetSession(0).Calibration;
            Assert.IsTrue(carried.IsComplete, "carried into the new session before it started");
            Assert.AreEqual(first.ValidMask, carried.ValidMask);
            RunUntil(runner, MocapRunnerEvent.Ended);
            Assert.Greater(runner.GetPoseCount(0), 150UL, "poses from the first frame, no calibration window needed");

            // Another sensor set is a different character: nothing carried, nothing calibrates it.
            var other = Character("Ada", _walk, windows: false);
            other.Config.Sensors[0] = new SessionSensor(other.Config.Sensors[0].Segment, 9);
            Assert.IsTrue(runner.Restart(Plan(other)));
            RunUntil(runner, MocapRunnerEvent.Opened);
            Assert.IsFalse(runner.GetSession(0).Calibration.IsComplete);
        }

        [Test]
        public void RecordingWritesOneNewCaptureFilePerCharacterThatReadsBack()
        {
            string folder = TestPaths.NewTempDirectory("runner-recording");
            using var runner = new MocapRunner();
            var plan = Plan(Character("Ada", _walk), Character("Ada", _mixed));
            plan.RecordingFolder = Path.Combine(folder, "takes");
            Assert.IsTrue(runner.Open(plan));
            string a = runner.GetRecordingPath(0), b = runner.GetRecordingPath(1);
            Assert.AreNotEqual("", a);
            Assert.AreNotEqual(a, b, "two characters of the same name record to two files");
            StringAssert.StartsWith(plan.RecordingFolder, a);
            RunUntil(runner, MocapRunnerEvent.Opened);
            Assert.IsTrue(runner.IsRecording);
            RunUntil(runner, MocapRunnerEvent.Ended);
            ulong written = runner.GetSession(0).GetStats().CaptureBytesWritten;
            Assert.AreEqual("", runner.Close());
            foreach (var path in new[] { a, b })
            {
                using var reader = new CaptureReader(path);
                int records = 0;
                while (reader.TryReadNext(out _)) records++;
                Assert.Greater(records, 100, $"{path} holds the replayed bytes");
            }
            Assert.AreEqual((long)written, new FileInfo(a).Length, "every byte counted reached the file");

            // A second take never overwrites the first.
            Assert.IsTrue(runner.Open(plan));
            Assert.AreNotEqual(a, runner.GetRecordingPath(0));
            Assert.AreNotEqual(b, runner.GetRecordingPath(1));
            RunUntil(runner, MocapRunnerEvent.Opened);
        }

        [Test]
        public void EachCharactersPerformerHeightReachesTheSolver()
        {
            // Two characters replay the same capture; Bo is 1.95 m tall: the pose is the same and
            // Bo's root velocity is the model's times its stride gain. A height out of range fails
            // the open naming the character.
            using var runner = new MocapRunner();
            var velocities = new[] { new List<Vec3>(), new List<Vec3>() };
            runner.PoseSolved += (int c, in MocapPose pose) => velocities[c].Add(pose.RootVelocity);
            var bo = Character("Bo", _walk);
            bo.HeightMeters = 1.95f;
            Assert.IsTrue(runner.Open(Plan(Character("Ada", _walk), bo)));
            RunUntil(runner, MocapRunnerEvent.Ended);
            ModelInfo info;
            using (var model = MocapModel.Open(TestPaths.ModelPath)) info = model.Info;
            Assert.IsTrue(info.HasStrideScaling);
            double gain = Math.Pow(1.95 / info.TrainingHeight, info.StrideExponent - 1.0);
            Assert.AreEqual(velocities[0].Count, velocities[1].Count);
            Assert.Greater(velocities[0].Count, 100);
            for (int i = 0; i < velocities[0].Count; i++)
                Assert.AreEqual(gain * velocities[0][i].X, velocities[1][i].X, 1e-5 + 1e-5 * Math.Abs(velocities[0][i].X), $"pose {i}");
            runner.SetCharacterHeight(0, 0f);
            var e = Assert.Throws<MocapException>(() => runner.SetCharacterHeight(1, 0.4f));
            StringAssert.Contains("1..2.5 m", e.Message);
            runner.Close();
            Assert.Throws<InvalidOperationException>(() => runner.SetCharacterHeight(0, 1.8f));

            var giant = Character("Goliath", _walk);
            giant.HeightMeters = 3f;
            Assert.IsTrue(runner.Open(Plan(giant)));
            RunUntil(runner, MocapRunnerEvent.Failed);
            StringAssert.Contains("Goliath", runner.LastError);
            StringAssert.Contains("1..2.5 m", runner.LastError);
        }

        [Test]
        public void AMissingModelFailsWithItsPathAndLeavesNothingOpen()
        {
            using var runner = new MocapRunner();
            var errors = new List<string>();
            runner.ErrorReported += errors.Add;
            var plan = Plan(Character("Ada", _walk));
            plan.ModelPath = Path.Combine(TestPaths.NewTempDirectory("runner-no-model"), "missing.onnx");
            Assert.IsTrue(runner.Open(plan));
            var events = RunUntil(runner, MocapRunnerEvent.Failed);
            CollectionAssert.AreEqual(new[] { MocapRunnerEvent.Failed }, events);
            Assert.AreEqual(MocapComponentStatus.Failed, runner.Status);
            StringAssert.Contains("missing.onnx", runner.LastError);
            CollectionAssert.AreEqual(new[] { runner.LastError }, errors);
            Assert.AreEqual(0, runner.CharacterCount);
            Assert.AreEqual("", runner.GetRecordingPath(0));

            // The same runner opens a good plan afterwards.
            Assert.IsTrue(runner.Open(Plan(Character("Ada", _walk))));
            RunUntil(runner, MocapRunnerEvent.Opened);
            Assert.AreEqual("", runner.LastError);
        }

        [Test]
        public void AnEmptyPlanOrAMissingCalibrationFileIsRefusedAtOnce()
        {
            using var runner = new MocapRunner();
            Assert.IsFalse(runner.Open(Plan()));
            Assert.AreEqual(MocapComponentStatus.Failed, runner.Status);
            StringAssert.Contains("at least one", runner.LastError);

            var ada = Character("Ada", _walk);
            ada.CalibrationFile = Path.Combine(TestPaths.NewTempDirectory("runner-no-cal"), "none.calibration");
            Assert.IsFalse(runner.Open(Plan(ada)));
            StringAssert.Contains("none.calibration", runner.LastError);
            Assert.AreEqual(MocapComponentStatus.Failed, runner.Status);
        }

        [Test]
        public void CloseWhileOpeningClosesWhatTheOpenMadeAndTheNextOpenWaitsForIt()
        {
            using var runner = new MocapRunner();
            Assert.IsTrue(runner.Open(Plan(Character("Ada", _walk, realtime: true))));
            runner.Close();
            Assert.AreEqual(MocapComponentStatus.Idle, runner.Status);
            Assert.AreEqual(MocapRunnerEvent.None, runner.Update(), "the abandoned open is never adopted");
            Assert.IsTrue(runner.Open(Plan(Character("Ada", _walk))));
            RunUntil(runner, MocapRunnerEvent.Ended);
            Assert.IsTrue(runner.WaitForAbandonedOpen(TimeSpan.FromSeconds(30)));
        }

        [Test]
        public void AThrowingListenerIsReportedAndTheCaptureGoesOn()
        {
            using var runner = new MocapRunner();
            var failures = new List<Exception>();
            runner.ListenerFailed = failures.Add;
            int after = 0;
            runner.PoseSolved += (int c, in MocapPose pose) => throw new InvalidOperationException("listener bug");
            runner.PoseSolved += (int c, in MocapPose pose) => after++;
            runner.Open(Plan(Character("Ada", _walk)));
            RunUntil(runner, MocapRunnerEvent.Ended);
            Assert.AreEqual((ulong)failures.Count, runner.GetPoseCount(0), "one report per pose the listener failed on");
            Assert.AreEqual("listener bug", failures[0].Message);
            Assert.AreEqual(MocapComponentStatus.Ended, runner.Status);
        }

        [Test]
        public void UpdatesWhileRunningAllocateNothing()
        {
            // A calibration file, so a realtime replay has poses from its first frames.
            string calibration = Path.Combine(TestPaths.NewTempDirectory("runner-alloc"), "ada.calibration");
            using (var first = new MocapRunner())
            {
                first.Open(Plan(Character("Ada", _walk)));
                RunUntil(first, MocapRunnerEvent.Ended);
                first.SaveCalibration(0, calibration);
            }
            using var runner = new MocapRunner();
            var live = Character("Ada", _walk, realtime: true, windows: false);
            live.CalibrationFile = calibration;
            runner.Open(Plan(live));
            RunUntil(runner, MocapRunnerEvent.Opened);
            Assert.IsTrue(runner.GetSession(0).Calibration.IsComplete, "the calibration file was loaded");
            for (int i = 0; i < 50; i++) { runner.Update(); runner.TryGetLatestPose(0, out _); System.Threading.Thread.Sleep(1); }
            long allocated = long.MaxValue;
            for (int run = 0; run < 3; run++)
            {
                long before = GC.GetAllocatedBytesForCurrentThread();
                for (int i = 0; i < 100; i++) { runner.Update(); runner.TryGetLatestPose(0, out _); System.Threading.Thread.Sleep(1); }
                allocated = Math.Min(allocated, GC.GetAllocatedBytesForCurrentThread() - before);
            }
            Assert.AreEqual(MocapComponentStatus.Running, runner.Status, "still running (a realtime replay)");
            Assert.Greater(runner.GetPoseCount(0), 0UL);
            Assert.AreEqual(0, allocated, "bytes allocated by 100 updates");
        }
    }
}
