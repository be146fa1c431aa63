// The Calibration window's state machine (CalibrationFlow) and per-sensor quality summaries:
// first against a scripted target (exact timing, stale reports, refusals, timeouts), then against
// the real engine replaying generated captures at their recorded pace, so the countdown, the
// engine's windows and the prelude of the capture (sensors lying still 0-3 s, strapping 3-5 s,
// T-pose 5-8 s, then the motion) line up as they would with a person.

using System;
using System.Collections.Generic;
using System.Diagnostics;
using System.Runtime.InteropServices;
using System.Threading;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    /// <summary>A target whose reports the test scripts.</summary>
    internal sealed class ScriptedTarget : ICalibrationTarget
    {
        public readonly List<(CalibrationStep Step, float Seconds)> Begun = new List<(CalibrationStep, float)>();
        public readonly Dictionary<CalibrationStep, CalibrationReport> Reports = new Dictionary<CalibrationStep, CalibrationReport>();
        public Exception ThrowOnBegin;

        public void BeginCalibration(CalibrationStep step, float durationSeconds)
        {
            if (ThrowOnBegin != null) throw ThrowOnBegin;
            Begun.Add((step, durationSeconds));
        }

        public CalibrationReport GetCalibrationReport(CalibrationStep step) =>
            Reports.TryGetValue(step, out var r) ? r : Fake.Report(step, CalibrationState.Idle);
    }

    internal static unsafe class Fake
    {
        /// <summary>A report as the engine would fill it (private fields written through their offsets).</summary>
        public static CalibrationReport Report(CalibrationStep step, CalibrationState state, string reason = "",
                                               float progress = 0, float gyro = 0.5f, uint samples = 100, bool ok = true,
                                               MocapSegment[] segments = null, int leftOut = -1)
        {
            segments ??= new[] { MocapSegment.Pelvis, MocapSegment.LeftWrist, MocapSegment.RightWrist,
                                 MocapSegment.LeftShin, MocapSegment.RightShin, MocapSegment.Head };
            var report = new CalibrationReport { Step = step, State = state, Progress = progress };
            byte* b = (byte*)&report;
            int sensors = (int)Marshal.OffsetOf<CalibrationReport>("_sensors");
            *(uint*)(b + (int)Marshal.OffsetOf<CalibrationReport>("_sensorCount")) = (uint)segments.Length;
            int okOffset = (int)Marshal.OffsetOf<SensorQuality>("_ok");
            int leftOutOffset = (int)Marshal.OffsetOf<SensorQuality>("_leftOut");
            for (int s = 0; s < segments.Length; s++)
            {
                var q = (SensorQuality*)(b + sensors + s * sizeof(SensorQuality));
                q->Segment = segments[s];
                if (s == leftOut)
                {
                    // What the engine reports for an optional sensor that sent nothing.
                    q->GyroRmsDps = q->OrientationSpreadDegrees = q->AccelerationNormError = q->TiltDegrees = 0f;
                    *(int*)((byte*)q + leftOutOffset) = 1;
                    continue;
                }
                q->GyroRmsDps = gyro;
                q->OrientationSpreadDegrees = 0.2f;
                q->AccelerationNormError = 0.05f;
                q->TiltDegrees = 2f;
                q->Samples = samples;
                *(int*)((byte*)q + okOffset) = ok ? 1 : 0;
            }
            var bytes = System.Text.Encoding.UTF8.GetBytes(reason);
            Assert.Less(bytes.Length, 256);
            byte* text = b + (int)Marshal.OffsetOf<CalibrationReport>("_reason");
            for (int i = 0; i < bytes.Length; i++) text[i] = bytes[i];
            return report;
        }
    }

    [TestFixture]
    public sealed class CalibrationFlowTests
    {
        static CalibrationFlowSettings Quick() => new CalibrationFlowSettings
        {
            CountdownSeconds = 3, HeadingSeconds = 2, TPoseSeconds = 1.5f, HeadingResetSeconds = 1, ResultTimeoutSeconds = 4,
        };

        static int ReadInstruction(CalibrationFlow flow, int times)
        {
            int length = 0;
            for (int i = 0; i < times; i++) length += flow.Instruction.Length;
            return length;
        }

        [Test]
        public void InstructionIsBuiltOnlyWhenItChanges()
        {
            // An overlay reads it several times per rendered frame: no string per read.
            var flow = new CalibrationFlow(new ScriptedTarget(), Quick());
            flow.StartFullCalibration(100.0);
            var first = flow.Instruction;
            Assert.AreSame(first, flow.Instruction);
            int length = ReadInstruction(flow, 100);  // warm-up: JIT the loop and the getter
            long before = GC.GetAllocatedBytesForCurrentThread();
            length += ReadInstruction(flow, 1000);
            // Into a local first: Assert's boxing of its arguments would count otherwise.
            long allocated = GC.GetAllocatedBytesForCurrentThread() - before;
            Assert.AreEqual(0, allocated, "bytes allocated by 1000 reads");
            Assert.Greater(length, 0);
            flow.Update(101.2);  // the countdown shows 2 now
            StringAssert.Contains("Starting in 2", flow.Instruction);
            Assert.AreNotSame(first, flow.Instruction);
            flow.Cancel();
            StringAssert.Contains("Press Calibrate", flow.Instruction);
        }

        [Test]
        public void CountsDownThenCollectsEachStepAndWaitsForTheUserBetween()
        {
            var target = new ScriptedTarget();
            var flow = new CalibrationFlow(target, Quick());
            var finished = new List<CalibrationReport>();
            flow.StepFinished += finished.Add;
            Assert.AreEqual(CalibrationFlowPhase.Idle, flow.Phase);

            flow.StartFullCalibration(100.0);
            Assert.AreEqual(CalibrationFlowPhase.Countdown, flow.Phase);
            Assert.AreEqual(CalibrationStep.Heading, flow.CurrentStep);
            Assert.AreEqual(3, flow.CountdownDisplay);
            StringAssert.Contains("flat", flow.Instruction);
            StringAssert.Contains("Starting in 3", flow.Instruction);

            Assert.IsFalse(flow.Update(100.5), "3 s still shows 3");
            Assert.IsTrue(flow.Update(101.2), "the display changes to 2");
            Assert.AreEqual(2, flow.CountdownDisplay);
            flow.Update(102.9);
            Assert.AreEqual(1, flow.CountdownDisplay);
            Assert.IsEmpty(target.Begun, "nothing is collected during the countdown");

            flow.Update(103.0);
            Assert.AreEqual(CalibrationFlowPhase.Collecting, flow.Phase);
            CollectionAssert.AreEqual(new[] { (CalibrationStep.Heading, 2f) }, target.Begun);

            target.Reports[CalibrationStep.Heading] = Fake.Report(CalibrationStep.Heading, CalibrationState.Collecting, progress: 0.4f);
            flow.Update(103.8);
            Assert.AreEqual(0.4f, flow.Progress, 1e-6f);
            Assert.IsTrue(flow.TryGetReport(out var collecting));
            Assert.AreEqual(CalibrationState.Collecting, collecting.State);

            target.Reports[CalibrationStep.Heading] = Fake.Report(CalibrationStep.Heading, CalibrationState.Accepted, progress: 1);
            flow.Update(105.1);
            Assert.AreEqual(CalibrationFlowPhase.AwaitingTPose, flow.Phase, "the user straps the sensors on first");
            StringAssert.Contains("Continue", flow.Instruction);
            Assert.AreEqual(1, finished.Count);
            flow.Update(200);
            Assert.AreEqual(1, target.Begun.Count, "no T-pose before Continue");

            flow.Continue(200);
            Assert.AreEqual(CalibrationStep.TPose, flow.CurrentStep);
            Assert.AreEqual(CalibrationFlowPhase.Countdown, flow.Phase);
            flow.Update(203.01);
            Assert.AreEqual((CalibrationStep.TPose, 1.5f), target.Begun[1]);
            target.Reports[CalibrationStep.TPose] = Fake.Report(CalibrationStep.TPose, CalibrationState.Waiting);
            flow.Update(203.1);
            target.Reports[CalibrationStep.TPose] = Fake.Report(CalibrationStep.TPose, CalibrationState.Accepted, progress: 1);
            flow.Update(204.7);
            Assert.AreEqual(CalibrationFlowPhase.Complete, flow.Phase);
            Assert.AreEqual(2, flow.AcceptedReports.Count);
            Assert.AreEqual(2, finished.Count);
            StringAssert.Contains("Calibrated", flow.Instruction);
        }

        [Test]
        public void ARefusalCarriesTheEnginesReasonAndRetryRepeatsTheStep()
        {
            var target = new ScriptedTarget();
            var flow = new CalibrationFlow(target, Quick());
            flow.StartHeadingReset(0);
            flow.Update(3);
            const string reason = "heading reset refused: left_wrist: gyro 30.2 deg/s > 10";
            target.Reports[CalibrationStep.HeadingReset] =
                Fake.Report(CalibrationStep.HeadingReset, CalibrationState.Refused, reason, gyro: 30.2f, ok: false);
            Assert.IsTrue(flow.Update(4.1));
            Assert.AreEqual(CalibrationFlowPhase.Refused, flow.Phase);
            Assert.AreEqual(reason, flow.Reason);
            StringAssert.Contains("gyro 30.2", flow.Instruction);
            StringAssert.Contains("Retry", flow.Instruction);
            Assert.Throws<InvalidOperationException>(() => flow.Continue(5), "Continue is only for after the heading");

            flow.Retry(10);
            Assert.AreEqual(CalibrationFlowPhase.Countdown, flow.Phase);
            Assert.AreEqual("", flow.Reason);
            flow.Update(13);
            Assert.AreEqual(2, target.Begun.Count, "the same step again");
            Assert.AreEqual(CalibrationStep.HeadingReset, target.Begun[1].Step);
            // The refused report is still what the engine shows until it takes the new request:
            // it must not be mistaken for the new result.
            Assert.IsFalse(flow.Update(13.1));
            Assert.AreEqual(CalibrationFlowPhase.Collecting, flow.Phase, "an unchanged old result is stale");
            target.Reports[CalibrationStep.HeadingReset] = Fake.Report(CalibrationStep.HeadingReset, CalibrationState.Accepted, progress: 1);
            flow.Update(14.2);
            Assert.AreEqual(CalibrationFlowPhase.Complete, flow.Phase);
            StringAssert.Contains("Heading reset accepted", flow.Instruction);
        }

        [Test]
        public void NoResultTimesOutAndSessionErrorsBecomeReasons()
        {
            var target = new ScriptedTarget();
            var flow = new CalibrationFlow(target, Quick());
            flow.StartFullCalibration(0);
            flow.Update(3);
            flow.Update(3 + 2 + 3.9);
            Assert.AreEqual(CalibrationFlowPhase.Collecting, flow.Phase, "within window + timeout");
            flow.Update(3 + 2 + 4.1);
            Assert.AreEqual(CalibrationFlowPhase.Refused, flow.Phase);
            StringAssert.Contains("no frames are arriving", flow.Reason);

            target.ThrowOnBegin = new InvalidOperationException("the session is stopped; Start() reopens it");
            flow.Retry(20);
            flow.Update(23);
            Assert.AreEqual(CalibrationFlowPhase.Refused, flow.Phase);
            StringAssert.Contains("the session is stopped", flow.Reason);
        }

        [Test]
        public void AutoAdvanceZeroCountdownCancelAndBadSettings()
        {
            var target = new ScriptedTarget();
            var settings = Quick();
            settings.AutoAdvance = true;
            settings.CountdownSeconds = 0;
            var flow = new CalibrationFlow(target, settings);
            flow.StartFullCalibration(0);
            Assert.AreEqual(CalibrationFlowPhase.Collecting, flow.Phase, "a zero countdown begins at once");
            target.Reports[CalibrationStep.Heading] = Fake.Report(CalibrationStep.Heading, CalibrationState.Accepted, progress: 1);
            flow.Update(2.1);
            Assert.AreEqual(CalibrationStep.TPose, flow.CurrentStep, "auto advance goes straight on");
            Assert.AreEqual(CalibrationFlowPhase.Collecting, flow.Phase);
            Assert.Throws<InvalidOperationException>(() => flow.StartHeadingReset(3), "one flow at a time");
            flow.Cancel();
            Assert.AreEqual(CalibrationFlowPhase.Idle, flow.Phase);
            Assert.IsFalse(flow.Update(4));

            settings.TPoseSeconds = 20;
            Assert.Throws<ArgumentOutOfRangeException>(() => flow.StartFullCalibration(5), "the engine takes 0.2..15 s");
            Assert.AreEqual(CalibrationFlowPhase.Idle, flow.Phase);
        }

        [Test]
        public void SensorSummariesCompareEachNumberWithItsLimit()
        {
            var good = Fake.Report(CalibrationStep.Heading, CalibrationState.Accepted, gyro: 0.5f);
            var summaries = CalibrationQuality.Summarize(good);
            Assert.AreEqual(6, summaries.Length);
            Assert.AreEqual(MocapSegment.Head, summaries[5].Segment);
            Assert.IsTrue(summaries[0].IsOk);
            Assert.IsEmpty(summaries[0].Problems);
            Assert.AreEqual(1f - 0.2f / 3f, summaries[0].Stillness, 1e-6f, "the spread (0.2/3) is worse than the gyro (0.5/10)");
            Assert.AreEqual("gyro 0.5/10 deg/s, spread 0.2/3 deg, |a|-g 0.05/1.5 m/s2, tilt 2/30 deg, 100 samples", summaries[0].Text);

            var moving = Fake.Report(CalibrationStep.TPose, CalibrationState.Refused, "x", gyro: 30.2f, ok: false);
            var left = CalibrationQuality.Summarize(moving)[(int)MocapSegment.LeftWrist];
            Assert.IsFalse(left.IsOk);
            Assert.AreEqual(0f, left.Stillness);
            CollectionAssert.AreEqual(new[] { "gyro 30.2 deg/s > 10" }, left.Problems);
            Assert.IsFalse(left.Text.Contains("tilt"), "tilt is checked for the heading step only");

            var reset = CalibrationQuality.Summarize(Fake.Report(CalibrationStep.HeadingReset, CalibrationState.Accepted))[0];
            Assert.IsFalse(reset.Text.Contains("|a|-g"), "the heading reset does not check the force");

            var silent = CalibrationQuality.Summarize(Fake.Report(CalibrationStep.TPose, CalibrationState.Refused, samples: 0, ok: false))[3];
            CollectionAssert.AreEqual(new[] { "no samples" }, silent.Problems);
            Assert.AreEqual(0f, silent.Stillness);
            var hidden = CalibrationQuality.Summarize(Fake.Report(CalibrationStep.TPose, CalibrationState.Refused, ok: false))[1];
            Assert.AreEqual(1, hidden.Problems.Count, "a sensor the engine refused is never shown as fine");
            Assert.AreEqual("left wrist", CalibrationQuality.SensorName(MocapSegment.LeftWrist));
        }

        [Test]
        public void ReportLinesAreKeptUntilTheNumbersTheyShowChange()
        {
            var lines = new CalibrationReportLines();
            var collecting = Fake.Report(CalibrationStep.TPose, CalibrationState.Collecting, gyro: 0.5f, samples: 40);
            string first = lines.GetLine(collecting, MocapSegment.RightShin);
            Assert.AreEqual("right shin - gyro 0.5/10 deg/s, spread 0.2/3 deg, |a|-g 0.05/1.5 m/s2, 40 samples", first);
            Assert.AreSame(first, lines.GetLine(collecting, MocapSegment.RightShin), "an unchanged sensor reuses its string");

            var more = Fake.Report(CalibrationStep.TPose, CalibrationState.Collecting, gyro: 0.5f, samples: 41);
            StringAssert.EndsWith("41 samples", lines.GetLine(more, MocapSegment.RightShin));
            var refused = Fake.Report(CalibrationStep.TPose, CalibrationState.Refused, "x", gyro: 30.2f, samples: 41, ok: false);
            string verdict = lines.GetLine(refused, MocapSegment.RightShin);
            StringAssert.StartsWith("right shin: REFUSED - gyro 30.2/10 deg/s", verdict);
            Assert.AreSame(verdict, lines.GetLine(refused, MocapSegment.RightShin));
            StringAssert.StartsWith("head: REFUSED", lines.GetLine(refused, MocapSegment.Head), "each sensor has its own line");

            var accepted = Fake.Report(CalibrationStep.TPose, CalibrationState.Accepted, gyro: 30.2f, samples: 41, ok: true);
            StringAssert.StartsWith("right shin: ok", lines.GetLine(accepted, MocapSegment.RightShin), "the verdict is part of what is shown");
            var heading = Fake.Report(CalibrationStep.Heading, CalibrationState.Accepted, gyro: 30.2f, samples: 41, ok: true);
            StringAssert.Contains("tilt 2/30 deg", lines.GetLine(heading, MocapSegment.RightShin), "the step decides which checks are shown");

            var unmeasured = Fake.Report(CalibrationStep.TPose, CalibrationState.Collecting, gyro: float.NaN, samples: 41);
            string nan = lines.GetLine(unmeasured, MocapSegment.RightShin);
            Assert.AreSame(nan, lines.GetLine(unmeasured, MocapSegment.RightShin), "NaN shows the same each frame");
            Assert.Throws<ArgumentException>(() => lines.GetLine(collecting, MocapSegment.Chest), "the six have no chest");
            Assert.Throws<ArgumentOutOfRangeException>(() => lines.GetLine(collecting, 6));
        }

        [Test]
        public void SummariesFollowTheSessionsSensorsByIndexAndNameThem()
        {
            var seven = new[] { MocapSegment.Chest, MocapSegment.Pelvis, MocapSegment.LeftWrist, MocapSegment.RightWrist,
                                MocapSegment.LeftShin, MocapSegment.RightShin, MocapSegment.Head };
            var report = Fake.Report(CalibrationStep.TPose, CalibrationState.Accepted, segments: seven, leftOut: 0);
            var summaries = CalibrationQuality.Summarize(report);
            Assert.AreEqual(7, summaries.Length);
            CollectionAssert.AreEqual(seven, Array.ConvertAll(summaries, s => s.Segment), "config order, not segment order");
            Assert.IsTrue(summaries[0].IsLeftOut);
            Assert.IsEmpty(summaries[0].Problems, "an optional sensor left out is not a problem");
            Assert.AreEqual("left out: optional and sent nothing", summaries[0].Text);
            Assert.IsFalse(summaries[1].IsLeftOut);
            Assert.AreEqual(1, report.IndexOf(MocapSegment.Pelvis));
            Assert.IsTrue(report.TryGetSensor(MocapSegment.Chest, out var chest) && chest.IsLeftOut);

            var lines = new CalibrationReportLines();
            Assert.AreEqual("chest: left out - left out: optional and sent nothing", lines.GetLine(report, MocapSegment.Chest));
            StringAssert.StartsWith("pelvis: ok", lines.GetLine(report, 1));
            // The same index now holding another segment is a new line, not the cached one.
            var six = Fake.Report(CalibrationStep.TPose, CalibrationState.Accepted);
            StringAssert.StartsWith("pelvis: ok", lines.GetLine(six, 0));
            StringAssert.StartsWith("left wrist: ok", lines.GetLine(six, 1));
        }

        // ---- against the engine, paced replays ----------------------------------------------

        /// <summary>Runs the flow on a paced replay; the flow's clock is the replay's (wall time x speed).</summary>
        sealed class PacedReplay : IDisposable
        {
            readonly Stopwatch _watch = new Stopwatch();
            readonly float _speed;
            public readonly MocapSession Session;

            public PacedReplay(SynthCapture capture, float speed)
            {
                _speed = speed;
                Session = MocapSession.Open(SessionConfig.Replay(capture.CapturePath, realtime: true, speed: speed));
                Session.Start();
                _watch.Start();
            }

            /// <summary>Seconds of capture since the start.</summary>
            public double Now => _watch.Elapsed.TotalSeconds * _speed;

            /// <summary>Update the flow until it leaves the countdown/collecting phases (or the capture time limit).</summary>
            public void Run(CalibrationFlow flow, double until)
            {
                while (flow.IsBusy)
                {
                    flow.Update(Now);
                    Assert.Less(Now, until, $"the flow was still {flow.Phase} of {flow.CurrentStep} at {Now:0.00} s");
                    Thread.Sleep(5);
                }
            }

            public void Dispose() => Session.Dispose();
        }

        [Test]
        public void GuidedCalibrationAndHeadingResetOfAReplayedCapture()
        {
            TestPaths.RequireEngine();
            var capture = TestPaths.Synth("walk", seconds: 6, seed: 3);
            using var replay = new PacedReplay(capture, speed: 1f);
            var flow = new CalibrationFlow(replay.Session, new CalibrationFlowSettings
            {
                CountdownSeconds = 0.5, HeadingSeconds = 2.0f, TPoseSeconds = 1.2f, HeadingResetSeconds = 0.6f,
            });

            // Heading: the prelude's sensors lie still from 0 to 3 s; window about 0.5..2.5 s.
            flow.StartFullCalibration(replay.Now);
            replay.Run(flow, until: 5.0);
            Assert.AreEqual(CalibrationFlowPhase.AwaitingTPose, flow.Phase, flow.Reason);
            Assert.IsTrue(flow.TryGetReport(out var heading));
            Assert.AreEqual(CalibrationState.Accepted, heading.State);
            foreach (var s in CalibrationQuality.Summarize(heading))
            {
                Assert.IsTrue(s.IsOk, $"{s.Segment}: {s.Text}");
                Assert.Greater(s.Quality.Samples, 0u);
                Assert.Greater(s.Stillness, 0.5f, $"{s.Segment} lies still: {s.Text}");
            }
            var calibration = replay.Session.Calibration;
            Assert.AreEqual(0x3Fu, calibration.HeadingMask, "every sensor has a heading");
            Assert.IsFalse(calibration.IsComplete, "no mounting yet");

            // T-pose: held from 5 to 8 s. Count down to 5.5 s, collect 1.2 s.
            flow.Settings.CountdownSeconds = Math.Max(0, 5.5 - replay.Now);
            flow.Continue(replay.Now);
            replay.Run(flow, until: 7.5);
            Assert.AreEqual(CalibrationFlowPhase.Complete, flow.Phase, flow.Reason);
            Assert.IsTrue(replay.Session.Calibration.IsComplete, "heading and T-pose done for all six");

            // Heading reset: still standing in the T-pose until 8 s; window about 7.0..7.6 s.
            flow.Settings.CountdownSeconds = Math.Max(0, 7.0 - replay.Now);
            flow.StartHeadingReset(replay.Now);
            replay.Run(flow, until: 8.5);
            Assert.AreEqual(CalibrationFlowPhase.Complete, flow.Phase, flow.Reason);
            Assert.AreEqual(CalibrationStep.HeadingReset, flow.CurrentStep);
            Assert.IsTrue(replay.Session.Calibration.IsComplete, "a heading reset keeps the calibration complete");
        }

        [Test]
        public void BadCalibrationsAreRefusedWithTheReason()
        {
            TestPaths.RequireEngine();
            var capture = TestPaths.Synth("walk", seconds: 6, seed: 3);
            using var replay = new PacedReplay(capture, speed: 2f);
            var flow = new CalibrationFlow(replay.Session, new CalibrationFlowSettings
            {
                CountdownSeconds = 0.5, HeadingSeconds = 1.0f, TPoseSeconds = 1.0f,
            });

            // A T-pose before any heading (sensors still lying on the table, 0.5..1.5 s).
            flow.StartTPoseOnly(replay.Now);
            replay.Run(flow, until: 3.0);
            Assert.AreEqual(CalibrationFlowPhase.Refused, flow.Phase, "a T-pose without a heading is refused");
            StringAssert.Contains("heading", flow.Reason.ToLowerInvariant());
            Assert.IsFalse(replay.Session.Calibration.IsComplete);

            // A T-pose while walking (the motion starts at 8 s): refused, naming moving sensors.
            flow.Cancel();
            flow.Settings.CountdownSeconds = 0;
            flow.StartFullCalibration(replay.Now);     // heading now (about 1.6..2.6 s): on the table until 3 s
            replay.Run(flow, until: 3.0);
            Assert.AreEqual(CalibrationFlowPhase.AwaitingTPose, flow.Phase, flow.Reason);
            flow.Settings.CountdownSeconds = Math.Max(0, 9.0 - replay.Now);
            flow.Continue(replay.Now);
            replay.Run(flow, until: 14.0);
            Assert.AreEqual(CalibrationFlowPhase.Refused, flow.Phase, "a T-pose taken while walking");
            Assert.AreEqual(CalibrationStep.TPose, flow.CurrentStep);
            StringAssert.Contains("refused", flow.Reason);
            Assert.IsTrue(flow.TryGetReport(out var refused));
            var failing = Array.FindAll(CalibrationQuality.Summarize(refused), s => !s.IsOk);
            Assert.IsNotEmpty(failing, "at least one sensor failed");
            foreach (var s in failing) Assert.IsNotEmpty(s.Problems, $"{s.Segment}: {s.Text}");
            // The engine's reason (at most 255 bytes, so it may end in "...") names failing sensors only.
            StringAssert.Contains(SensorKey(failing[0].Segment) + ":", flow.Reason, "the first failing sensor is named");
            foreach (var s in CalibrationQuality.Summarize(refused))
                if (s.IsOk) StringAssert.DoesNotContain(SensorKey(s.Segment) + ":", flow.Reason, $"{s.Segment} passed");
            Assert.IsFalse(replay.Session.Calibration.IsComplete, "a refused T-pose leaves the calibration as it was");
        }

        static string SensorKey(MocapSegment segment) => SegmentTable.Name(segment);
    }
}
