// The per-frame path must not allocate: a Unity game polls every frame and any garbage turns
// into GC spikes. Measured with the thread's allocation counter across 1,000 polls of a
// running replay, into a caller-owned buffer.

using System;
using System.Threading;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class ZeroAllocationTests
    {
        const int Polls = 1000;

        [Test]
        public void PollDrainStatsAndReportsAllocateNothing()
        {
            TestPaths.RequireEngine();
            var capture = TestPaths.Synth("mixed", seconds: 22);
            // At 10x the recorded pace frames keep arriving during the measured loop (a fast
            // replay would be over before it), so both "frames" and "no data" paths are measured.
            using var session = MocapSession.Open(SessionConfig.Replay(capture.CapturePath, realtime: true, speed: 10f));
            double t0 = Replay.FirstReceiveSeconds(capture.CapturePath);
            session.ScheduleCalibration(CalibrationStep.Heading, t0 + 0.5, 2f);
            session.ScheduleCalibration(CalibrationStep.TPose, t0 + 5.5, 2f);
            session.Start();

            var buffer = new MocapFrame[16];
            Span<MocapFrame> span = buffer;
            var latest = default(MocapFrame);
            int frames = 0, latestHits = 0;
            float checksum = 0;

            // Warm-up: JIT the P/Invoke stubs and every method on the path.
            for (int i = 0; i < 20; i++)
            {
                session.PollLatest(ref latest);
                session.Drain(span, out _);
                session.GetStats();
                session.GetCalibrationReport();
                session.GetCalibrationReport(CalibrationStep.TPose);
                Thread.Sleep(1);
            }

            long before = GC.GetAllocatedBytesForCurrentThread();
            for (int i = 0; i < Polls; i++)
            {
                if (session.PollLatest(ref latest) == MocapPollResult.Frames) latestHits++;
                // PollLatest empties the queue: let the engine produce again before draining.
                Thread.Sleep(1);
                if (session.Drain(span, out int count) == MocapPollResult.Frames)
                {
                    frames += count;
                    checksum += span[count - 1].GetSensor(0).BoneOrientation.W;
                }
                var stats = session.GetStats();
                var report = session.GetCalibrationReport();
                checksum += stats.FramesEmitted + report.Progress + (latest.TryGetSensor(MocapSegment.Head, out var head) ? head.BoneOrientation.W : 0f);
                Thread.Sleep(1);
            }
            long allocated = GC.GetAllocatedBytesForCurrentThread() - before;

            TestContext.WriteLine($"{latestHits} polls and {frames} drained frames returned data; checksum {checksum}");
            Assert.AreEqual(0, allocated, $"bytes allocated across {Polls} PollLatest + {Polls} Drain calls");
            Assert.Greater(latestHits, 10, "PollLatest returned new frames during the measurement");
            Assert.Greater(frames, 10, "Drain returned frames during the measurement");
        }
    }
}
