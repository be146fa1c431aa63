// Polling poses must not allocate: a Unity game polls every character every frame. Measured with
// the thread's allocation counter across 1,000 PollLatest + 1,000 Drain calls on a paced replay,
// so poses keep arriving during the measurement and both the "poses" and "no data" paths run.

using System;
using System.Diagnostics;
using System.IO;
using System.Threading;
using Mocap.Imu.Recording;
using Mocap.Imu.Skeleton;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class ZeroAllocationPoseTests
    {
        const int Polls = 1000;

        [Test]
        public void PollLatestDrainConversionAndRecordingAllocateNothing()
        {
            TestPaths.RequireEngine();
            // 8 s of prelude + 40 s of motion at 5x: about 9.6 s of wall time, well beyond the loop
            // (about 3 s), with a pose every 3.3 ms.
            var capture = TestPaths.Synth("mixed", seconds: 40);
            using var model = MocapModel.Open(TestPaths.ModelPath);
            using var session = SolverReplay.OpenCalibratedReplay(capture, model.Info.FrameRate, realtime: true, speed: 5f);
            using var solver = MocapSolver.Open(model);
            int character = solver.AddCharacter(session);
            solver.Start();
            session.Start();

            var buffer = new MocapPose[16];
            Span<MocapPose> span = buffer;
            var latest = default(MocapPose);
            var smpl = new SmplPose();
            var recordingPath = Path.Combine(TestPaths.NewTempDirectory("alloc"), "poses.mcpose");
            using var writer = PoseRecordingWriter.Create(recordingPath, model.Info);

            // Warm-up until the first pose (calibration ends 1.7 s into the paced replay): JITs
            // every method on the path, including the "poses" branch.
            var watch = Stopwatch.StartNew();
            while (solver.PollLatest(character, ref latest) != MocapPollResult.Frames)
            {
                Assert.Less(watch.Elapsed.TotalSeconds, 30, "no pose within 30 s");
                solver.Drain(character, span, out _);
                Thread.Sleep(1);
            }
            latest.CopyTo(smpl);
            writer.Append(in latest);
            writer.Append(span.Slice(0, 1));

            int hits = 0, drained = 0;
            float checksum = 0;
            long before = GC.GetAllocatedBytesForCurrentThread();
            for (int i = 0; i < Polls; i++)
            {
                if (solver.PollLatest(character, ref latest) == MocapPollResult.Frames)
                {
                    hits++;
                    PoseConversion.ToSmplPose(ref latest, smpl);
                    writer.Append(in latest);
                    checksum += smpl.Rotations[(int)SmplJoint.LeftElbow].W;
                }
                // PollLatest empties the queue: let the solver produce again before draining.
                Thread.Sleep(1);
                if (solver.Drain(character, span, out int count) == MocapPollResult.Frames)
                {
                    drained += count;
                    writer.Append(span.Slice(0, count));
                    checksum += span[count - 1].RootPosition.Y + span[count - 1].GetJointRotation(SmplJoint.Head).W;
                }
                Thread.Sleep(1);
            }
            long allocated = GC.GetAllocatedBytesForCurrentThread() - before;

            TestContext.WriteLine($"{hits} polls and {drained} drained poses returned data; checksum {checksum}");
            Assert.AreEqual(0, allocated, $"bytes allocated across {Polls} PollLatest + {Polls} Drain calls");
            Assert.Greater(hits, 10, "PollLatest returned new poses during the measurement");
            Assert.Greater(drained, 10, "Drain returned poses during the measurement");
            Assert.IsFalse(solver.IsEndOfStream(character), "the replay was still running: the measurement saw live poses");
        }
    }
}
