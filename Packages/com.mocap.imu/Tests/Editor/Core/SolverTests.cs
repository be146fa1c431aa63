// The pose model and solver driven from C#, end to end through the real engine: a generated
// capture's bytes -> calibrated frames -> the model on the engine's inference thread -> poses
// drained into C# structs, compared pose by pose with the engine's own `mocapctl replay --json`.
// The shipped model may be untrained, so structure is asserted, never accuracy.

using System;
using System.Collections.Generic;
using System.Diagnostics;
using System.IO;
using Mocap.Imu.Maths;
using Mocap.Imu.Recording;
using Mocap.Imu.Skeleton;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    /// <summary>Replays captures through MocapSession + MocapSolver from C#.</summary>
    internal static class SolverReplay
    {
        /// <summary>A fast replay session of a synth capture with the prelude's calibration windows
        /// scheduled as mocapctl replay schedules them.</summary>
        public static MocapSession OpenCalibratedReplay(SynthCapture capture, float frameRate,
                                                        bool realtime = false, float speed = 1f)
        {
            var config = SessionConfig.Replay(capture.CapturePath, realtime, speed);
            config.OutputRateHz = frameRate;
            var session = MocapSession.Open(config);
            double t0 = Replay.FirstReceiveSeconds(capture.CapturePath);
            session.ScheduleCalibration(CalibrationStep.Heading, t0 + 0.5, (float)(capture.HeadingSeconds - 1.0));
            session.ScheduleCalibration(CalibrationStep.TPose,
                t0 + capture.HeadingSeconds + capture.StrapSeconds + 0.5, (float)(capture.TPoseSeconds - 1.0));
            return session;
        }

        /// <summary>Every pose of one character: the capture replayed (calibrated) through a new
        /// solver of the model as fast as possible.</summary>
        public static List<MocapPose> SolveOneCharacter(SynthCapture capture, MocapModel model,
                                                        SolverConfig config = null, float heightMeters = 0f)
        {
            using var session = OpenCalibratedReplay(capture, model.Info.FrameRate);
            using var solver = MocapSolver.Open(model, config);
            Assert.AreEqual(0, solver.AddCharacter(session));
            solver.SetCharacterHeight(0, heightMeters);
            solver.Start();
            session.Start();
            return DrainAll(solver)[0];
        }

        /// <summary>Drains every character until each reports the end of its replay.</summary>
        public static List<MocapPose>[] DrainAll(MocapSolver solver, int capacity = 32)
        {
            var poses = new List<MocapPose>[solver.CharacterCount];
            for (int c = 0; c < poses.Length; c++) poses[c] = new List<MocapPose>();
            var buffer = new MocapPose[capacity];
            var watch = Stopwatch.StartNew();
            for (;;)
            {
                bool allEnded = true, none = true;
                for (int c = 0; c < poses.Length; c++)
                {
                    if (solver.IsEndOfStream(c)) continue;
                    allEnded = false;
                    var r = solver.Drain(c, buffer, out int count);
                    for (int i = 0; i < count; i++) poses[c].Add(buffer[i]);
                    none &= count == 0;
                }
                if (allEnded) return poses;
                if (none) System.Threading.Thread.Sleep(1);
                if (watch.Elapsed > TimeSpan.FromSeconds(90)) Assert.Fail("the replays did not end within 90 s");
            }
        }

        /// <summary>Asserts a C# pose equals one of mocapctl's JSON poses (printed with 6 decimals).</summary>
        public static void AssertSame(MocapPose expected, MocapPose actual, string where, float tolerance = 1e-5f)
        {
            Assert.AreEqual(expected.Sequence, actual.Sequence, where + " sequence");
            Assert.AreEqual(expected.FrameSequence, actual.FrameSequence, where + " frame_sequence");
            Assert.AreEqual(expected.TimeSeconds, actual.TimeSeconds, 1e-6, where + " time_s");
            Assert.AreEqual(expected.Flags, actual.Flags, where + " flags");
            AssertVec(expected.RootPosition, actual.RootPosition, tolerance, where + " root_position");
            AssertVec(expected.RootVelocity, actual.RootVelocity, tolerance, where + " root_velocity");
            // mocapctl prints contacts with 4 decimals: half a unit of the last digit is 5e-5.
            float contact = Math.Max(tolerance, 5.1e-5f);
            Assert.AreEqual(expected.LeftFootContact, actual.LeftFootContact, contact, where + " left contact");
            Assert.AreEqual(expected.RightFootContact, actual.RightFootContact, contact, where + " right contact");
            for (int j = 0; j < MocapPose.JointCount; j++)
            {
                Quat e = expected.GetJointRotation(j), a = actual.GetJointRotation(j);
                Assert.AreEqual(e.W, a.W, tolerance, $"{where} joint {j} w");
                Assert.AreEqual(e.X, a.X, tolerance, $"{where} joint {j} x");
                Assert.AreEqual(e.Y, a.Y, tolerance, $"{where} joint {j} y");
                Assert.AreEqual(e.Z, a.Z, tolerance, $"{where} joint {j} z");
                AssertVec(expected.GetJointPosition(j), actual.GetJointPosition(j), tolerance, $"{where} joint {j} position");
            }
        }

        public static void AssertVec(Vec3 e, Vec3 a, float tolerance, string where)
        {
            Assert.IsTrue(e.ApproximatelyEquals(a, tolerance), $"{where}: expected {e}, got {a} (tolerance {tolerance})");
        }

        /// <summary>
        /// Every frame of <paramref name="bvh"/> equals its pose: root position within 2e-6 m and
        /// every joint within 0.01 deg. Returns the worst joint angle difference (deg).
        /// </summary>
        public static double AssertBvhMatchesPoses(BvhFile bvh, int[] map, IReadOnlyList<MocapPose> poses, string what)
        {
            var smpl = new SmplPose();
            double worst = 0;
            for (int f = 0; f < bvh.FrameCount; f++)
            {
                bvh.ToSmplPose(f, map, smpl);
                AssertVec(poses[f].RootPosition, smpl.RootPosition, 2e-6f, $"frame {f} root position");
                for (int j = 0; j < SmplSkeleton.JointCount; j++)
                {
                    double deg = Quat.Angle(poses[f].GetJointRotation(j), smpl.Rotations[j]) * 180.0 / Math.PI;
                    worst = Math.Max(worst, deg);
                    Assert.Less(deg, 0.01, $"frame {f} {SmplSkeleton.NameOf(j)}: {what} rotations differ by {deg} deg");
                }
            }
            return worst;
        }
    }

    [TestFixture]
    public sealed class SolverTests
    {
        SynthCapture _capture;
        MocapModel _model;
        List<MocapPose> _poses;
        MocapPollResult _pollAfterEnd;

        [OneTimeSetUp]
        public void ReplayThroughTheSolver()
        {
            TestPaths.RequireEngine();
            _capture = TestPaths.Synth("walk", seconds: 6, seed: 3);
            _model = MocapModel.Open(TestPaths.ModelPath);
            using var session = SolverReplay.OpenCalibratedReplay(_capture, _model.Info.FrameRate);
            using var solver = MocapSolver.Open(_model);
            Assert.AreEqual(0, solver.AddCharacter(session));
            solver.Start();
            session.Start();
            _poses = SolverReplay.DrainAll(solver)[0];
            var last = default(MocapPose);
            _pollAfterEnd = solver.PollLatest(0, ref last);
        }

        [OneTimeTearDown]
        public void CloseModel() => _model?.Dispose();

        [Test]
        public void ModelInfoDescribesTheContractSkeleton()
        {
            var info = _model.Info;
            TestContext.WriteLine($"{info.ModelName}: {info.Precision}, {info.FrameRate} Hz, state {info.StateLayers} x {info.StateSize}");
            Assert.AreEqual(1, info.ContractVersion);
            Assert.AreEqual(60f, info.FrameRate, "the shipped model runs at 60 Hz");
            Assert.AreEqual("fp32", info.Precision);
            Assert.IsNotEmpty(info.ModelName);
            Assert.Greater(info.StateLayers, 0);
            Assert.Greater(info.StateSize, 0);
            CollectionAssert.AreEqual(SmplSkeleton.JointNames, info.JointNames);
            CollectionAssert.AreEqual(SmplSkeleton.Parents, info.JointParents);
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
                Assert.AreEqual(info.RestOffsets[j], info.Skeleton.RestOffset(j), $"joint {j} offset");
            Assert.Greater(info.Skeleton.RestPosition(0).Y, 0.5f, "the pelvis stands above the floor");
            Assert.AreEqual(TestPaths.ModelPath, _model.Path);
        }

        [Test]
        public void PosesFlowInOrderUntilEndOfStream()
        {
            Assert.Greater(_poses.Count, 100, "poses were solved");
            Assert.AreEqual(MocapPollResult.EndOfStream, _pollAfterEnd);
            double period = 1.0 / _model.Info.FrameRate;
            for (int i = 0; i < _poses.Count; i++)
            {
                var p = _poses[i];
                Assert.AreEqual((ulong)i, p.Sequence, "per-character sequence 0, 1, 2 ...");
                Assert.AreEqual(0, p.Character);
                if (i > 0)
                {
                    Assert.AreEqual(_poses[i - 1].FrameSequence + 1, p.FrameSequence, $"pose {i}: no frame skipped on a fast replay");
                    Assert.AreEqual(period, p.TimeSeconds - _poses[i - 1].TimeSeconds, 1e-6, $"pose {i} time step");
                }
                Assert.LessOrEqual(p.FrameEmittedNs, p.PoseEmittedNs, $"pose {i}: solved after its frame");
                for (int j = 0; j < MocapPose.JointCount; j++)
                {
                    Quat q = p.GetJointRotation(j);
                    Assert.AreEqual(1f, q.LengthSquared, 1e-4f, $"pose {i} joint {j} is a unit quaternion");
                    Assert.IsTrue(p.GetJointPosition(j).IsFinite, $"pose {i} joint {j} position");
                }
                Assert.IsTrue(p.RootVelocity.IsFinite);
                Assert.That(p.LeftFootContact, Is.InRange(0f, 1f));
                Assert.That(p.RightFootContact, Is.InRange(0f, 1f));
            }
        }

        [Test]
        public void JointPositionsAreTheForwardKinematicsOfTheRotations()
        {
            // The C# skeleton's FK (model proportions) reproduces the engine's positions: the
            // rotation conventions, the joint order and the conversion to SmplPose all agree.
            var skeleton = _model.Info.Skeleton;
            var smpl = new SmplPose();
            var global = new Quat[SmplSkeleton.JointCount];
            var positions = new Vec3[SmplSkeleton.JointCount];
            for (int i = 0; i < _poses.Count; i += 7)
            {
                var p = _poses[i];
                PoseConversion.ToSmplPose(ref p, smpl);
                Assert.AreEqual(p.RootPosition, smpl.RootPosition);
                skeleton.ForwardKinematics(smpl.Rotations, smpl.RootPosition, global, positions);
                for (int j = 0; j < SmplSkeleton.JointCount; j++)
                    SolverReplay.AssertVec(p.GetJointPosition(j), positions[j], 1e-4f, $"pose {i} joint {j}");

                var rebuilt = p;
                PoseConversion.FromSmplPose(smpl, skeleton, ref rebuilt);
                for (int j = 0; j < SmplSkeleton.JointCount; j++)
                    SolverReplay.AssertVec(p.GetJointPosition(j), rebuilt.GetJointPosition(j), 1e-4f, $"rebuilt pose {i} joint {j}");
            }
        }

        [Test]
        public void PosesEqualMocapctlReplayOfTheSameCapture()
        {
            var expected = PoseJsonLines.Load(TestPaths.ReplayPoses(_capture).JsonPath);
            Assert.AreEqual(expected.Length, _poses.Count, "pose count");
            for (int i = 0; i < expected.Length; i++)
                SolverReplay.AssertSame(expected[i], _poses[i], $"pose {i}");
        }

        [Test]
        public void ThreeCharactersFromThreeReplaysThroughOneSolver()
        {
            var captures = new[]
            {
                _capture,
                TestPaths.Synth("arms", seconds: 5, seed: 4),
                TestPaths.Synth("squat", seconds: 4, seed: 5),
            };
            var sessions = new MocapSession[3];
            try
            {
                using var solver = MocapSolver.Open(_model);
                for (int c = 0; c < 3; c++)
                {
                    sessions[c] = SolverReplay.OpenCalibratedReplay(captures[c], _model.Info.FrameRate);
                    Assert.AreEqual(c, solver.AddCharacter(sessions[c]));
                    Assert.AreSame(sessions[c], solver.GetSession(c));
                }
                Assert.AreEqual(3, solver.CharacterCount);
                solver.Start();
                foreach (var s in sessions) s.Start();
                var poses = SolverReplay.DrainAll(solver);
                for (int c = 0; c < 3; c++)
                {
                    // Each character equals its own single-character replay: batching characters
                    // into one inference call must not mix their states. (A batch of 3 may round
                    // differently from a batch of 1 inside ONNX Runtime, hence 1e-4.)
                    var expected = PoseJsonLines.Load(TestPaths.ReplayPoses(captures[c]).JsonPath);
                    Assert.AreEqual(expected.Length, poses[c].Count, $"character {c} pose count");
                    for (int i = 0; i < expected.Length; i++)
                    {
                        Assert.AreEqual(c, poses[c][i].Character);
                        SolverReplay.AssertSame(expected[i], poses[c][i], $"character {c} pose {i}", 1e-4f);
                    }
                    // The engine's counters agree with what came out, per character.
                    var stats = solver.GetStats(c);
                    Assert.AreEqual((ulong)poses[c].Count, stats.FramesSolved, $"character {c} frames solved");
                    Assert.AreEqual(0ul, stats.RunFailures);
                    Assert.AreEqual(MocapStatus.Ok, stats.LastRunStatus);
                    Assert.AreEqual("", stats.LastRunError);
                }
                var total = solver.GetStats();
                Assert.AreEqual((ulong)(poses[0].Count + poses[1].Count + poses[2].Count), total.FramesSolved);
                Assert.LessOrEqual(total.MaxBatch, 3ul);
                Assert.Greater(total.Ticks, 0ul);
                var refused = Assert.Throws<MocapException>(() => solver.GetStats(3));
                StringAssert.Contains("character 3", refused.Message);
            }
            finally
            {
                foreach (var s in sessions) s?.Dispose();
            }
        }

        [Test]
        public void CatchUpGivesTheNewestPoseAfterAPauseLongerThanTheEngineQueue()
        {
            // 22 s of motion, about 1,350 poses, at 10x the recorded pace: realtime, so the
            // engine drops what its 1024-pose queue cannot hold while nobody drains.
            var capture = TestPaths.Synth("mixed", seconds: 22, seed: 5);
            using var session = SolverReplay.OpenCalibratedReplay(capture, _model.Info.FrameRate,
                                                                  realtime: true, speed: 10f);
            using var solver = MocapSolver.Open(_model);
            solver.AddCharacter(session);
            solver.Start();
            session.Start();
            var watch = Stopwatch.StartNew();
            ulong done = ulong.MaxValue;
            for (;;) // the pause: until the replay ended and the solver has nothing left
            {
                System.Threading.Thread.Sleep(300);
                var s = solver.GetStats(0);
                ulong now = s.FramesSolved + s.FramesUncalibrated;
                if (session.GetStats().ConnectionState == MocapConnectionState.Ended && now == done) break;
                done = now;
                Assert.Less(watch.Elapsed.TotalSeconds, 120, "the replay did not end");
            }
            var stats = solver.GetStats(0);
            Assume.That(stats.PosesDropped, Is.GreaterThan(0UL), "the queue never filled");

            ulong seen = 0;
            var pose = default(MocapPose);
            // In normal running (nothing dropped since the last look) CatchUp takes nothing.
            ulong alreadySeen = stats.PosesDropped;
            Assert.AreEqual(MocapPollResult.NoData, solver.CatchUp(0, ref alreadySeen, ref pose));
            var drained = new List<MocapPose>();
            var buffer = new MocapPose[32];
            while (solver.Drain(0, buffer, out int n) == MocapPollResult.Frames)
                for (int i = 0; i < n; i++) drained.Add(buffer[i]);
            Assert.AreEqual(1024, drained.Count, "the engine keeps its queue's 1024 oldest poses");
            Assert.AreEqual(MocapPollResult.Frames, solver.CatchUp(0, ref seen, ref pose));
            Assert.AreEqual(stats.PosesDropped, seen);
            Assert.AreEqual(stats.FramesSolved, pose.Sequence + 1, "not the newest pose");
            Assert.Greater(pose.Sequence, drained[drained.Count - 1].Sequence);
            Assert.AreEqual(MocapPollResult.NoData, solver.CatchUp(0, ref seen, ref pose));
        }

        [Test]
        public void AWrongModelPathThrowsNamingTheFile()
        {
            var path = Path.Combine(TestPaths.NewTempDirectory("nomodel"), "missing_model.onnx");
            var e = Assert.Throws<MocapException>(() => MocapModel.Open(path));
            TestContext.WriteLine($"{e.Status}: {e.Message}");
            Assert.AreEqual(MocapStatus.NotFound, e.Status);
            StringAssert.Contains(path, e.Message);

            var notAModel = Path.Combine(TestPaths.NewTempDirectory("badmodel"), "not_a_model.onnx");
            File.WriteAllText(notAModel, "this is not an ONNX file");
            e = Assert.Throws<MocapException>(() => MocapModel.Open(notAModel));
            TestContext.WriteLine($"{e.Status}: {e.Message}");
            StringAssert.Contains(notAModel, e.Message);
        }

        [Test]
        public void CudaRequestedWithoutACudaBuildThrowsClearly()
        {
            var options = new ModelOptions { ExecutionProvider = ExecutionProvider.Cuda };
            MocapModel model = null;
            try
            {
                model = MocapModel.Open(TestPaths.ModelPath, options);
            }
            catch (MocapException e)
            {
                TestContext.WriteLine($"{e.Status}: {e.Message}");
                Assert.AreNotEqual(MocapStatus.Ok, e.Status);
                StringAssert.Contains("cuda", e.Message.ToLowerInvariant(), "the message says CUDA is the problem");
                return;
            }
            model.Dispose();
            Assert.Inconclusive("this ONNX Runtime has CUDA and a GPU: nothing to refuse");
        }

        [Test]
        public unsafe void NewModelOptionsHoldTheEnginesDefaults()
        {
            NativeModelOptions engine;
            NativeMethods.Check(NativeSolverMethods.mocap_model_options_defaults(&engine));
            var options = new ModelOptions();
            Assert.AreEqual(1, engine.IntraOpThreads, "one ONNX Runtime thread: no spinning pool");
            Assert.AreEqual(engine.IntraOpThreads, options.IntraOpThreads);
            Assert.AreEqual(engine.OptimizationLevel, (int)options.OptimizationLevel);
            Assert.AreEqual(engine.ExecutionProvider, (int)options.ExecutionProvider);
        }

        [Test]
        public void ModelOptionsReachTheEngine()
        {
            // (ONNX Runtime is loaded once per process, so a different library path cannot be
            // observed here after the first model; a path the engine cannot hold is refused in C#.)
            var e = Assert.Throws<ArgumentException>(() => MocapModel.Open(TestPaths.ModelPath,
                new ModelOptions { OnnxRuntimePath = new string('x', 300) }));
            StringAssert.Contains("OnnxRuntimePath", e.Message);

            using var model = MocapModel.Open(TestPaths.ModelPath, new ModelOptions
            {
                IntraOpThreads = 1, OptimizationLevel = GraphOptimizationLevel.Basic,
            });
            Assert.AreEqual(_model.Info.FrameRate, model.Info.FrameRate);
        }

        [Test]
        public void TheSolverOwnsItsSessionsFrames()
        {
            using var session = SolverReplay.OpenCalibratedReplay(_capture, _model.Info.FrameRate);
            var solver = MocapSolver.Open(_model);
            solver.AddCharacter(session);
            var frame = default(MocapFrame);
            Assert.Throws<InvalidOperationException>(() => session.PollLatest(ref frame));
            Assert.Throws<InvalidOperationException>(() => session.Drain(new MocapFrame[4], out _));
            Assert.Throws<InvalidOperationException>(() => session.Stop());
            using (var other = MocapSolver.Open(_model))
                Assert.Throws<InvalidOperationException>(() => other.AddCharacter(session));
            solver.Dispose();
            Assert.AreEqual(MocapPollResult.NoData, session.PollLatest(ref frame), "the session is free again");
            Assert.Throws<ObjectDisposedException>(() => solver.Start());
        }

        [Test]
        public void ASessionIsHandedBackOnlyWhenTheSolverHasReallyClosed()
        {
            // Another thread inside a solver call (ResetCharacter, GetStats) holds a reference on
            // the native handle, so Dispose only defers mocap_solver_close: until it runs, the
            // inference thread still takes the session's frames and the session must stay the
            // solver's. A reference taken here stands in for that call.
            using var session = SolverReplay.OpenCalibratedReplay(_capture, _model.Info.FrameRate);
            var solver = MocapSolver.Open(_model);
            solver.AddCharacter(session);
            solver.Start();
            var handle = solver.NativeHandle;
            bool added = false;
            handle.DangerousAddRef(ref added);
            Assert.IsTrue(added);
            solver.Dispose();
            var frame = default(MocapFrame);
            Assert.Throws<InvalidOperationException>(() => session.PollLatest(ref frame), "still the solver's");
            Assert.IsFalse(handle.IsClosed && handle.IsInvalid, "not closed yet");
            handle.DangerousRelease();                    // the other call returns: the close runs
            Assert.IsTrue(handle.IsClosed);
            Assert.DoesNotThrow(() => session.PollLatest(ref frame), "the session is free again");
        }

        [Test]
        public void EngineRefusalsCarryTheEngineText()
        {
            var config = SessionConfig.Replay(_capture.CapturePath);
            config.OutputRateHz = _model.Info.FrameRate / 2;
            using var slow = MocapSession.Open(config);
            using var solver = MocapSolver.Open(_model);
            var e = Assert.Throws<MocapException>(() => solver.AddCharacter(slow));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("Hz", e.Message);

            e = Assert.Throws<MocapException>(() => solver.Start());
            Assert.AreEqual(MocapStatus.State, e.Status);
            StringAssert.Contains("no characters", e.Message);

            using var session = SolverReplay.OpenCalibratedReplay(_capture, _model.Info.FrameRate);
            Assert.AreEqual(0, solver.AddCharacter(session), "the refused session took no index");
            solver.Start();
            var pose = default(MocapPose);
            e = Assert.Throws<MocapException>(() => solver.PollLatest(5, ref pose));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("character 5 does not exist", e.Message);
            e = Assert.Throws<MocapException>(() => solver.ResetCharacter(-1));
            StringAssert.Contains("does not exist", e.Message);
            solver.ResetCharacter(0);

            using var late = SolverReplay.OpenCalibratedReplay(_capture, _model.Info.FrameRate);
            e = Assert.Throws<MocapException>(() => solver.AddCharacter(late));
            Assert.AreEqual(MocapStatus.State, e.Status);

            var bad = new SolverConfig { ContactThreshold = 2f };
            e = Assert.Throws<MocapException>(() => MocapSolver.Open(_model, bad));
            StringAssert.Contains("contact_threshold", e.Message);
            bad = new SolverConfig { SmoothingMinCutoffHz = -1f };
            e = Assert.Throws<MocapException>(() => MocapSolver.Open(_model, bad));
            StringAssert.Contains("smoothing_min_cutoff_hz", e.Message);
        }

        [Test]
        public void APerformerHeightScalesTheRootByTheShippedModelsStrideLaw()
        {
            // The shipped model carries its stride law; a tall performer's root moves less for
            // the model's skeleton (its strides are read as too long for it), the pose is the same.
            ModelInfo info = _model.Info;
            Assert.IsTrue(info.HasStrideScaling, "the shipped model has no mocap.training_height / stride_exponent");
            Assert.That(info.TrainingHeight, Is.InRange(1.6f, 1.8f));
            Assert.That(info.StrideExponent, Is.InRange(0.05f, 0.95f));
            const float height = 1.95f;
            double gain = Math.Pow(height / info.TrainingHeight, info.StrideExponent - 1.0);
            var config = new SolverConfig { DriftCorrection = false };
            var own = SolverReplay.SolveOneCharacter(_capture, _model, config);
            var tall = SolverReplay.SolveOneCharacter(_capture, _model, config, height);
            Assert.AreEqual(own.Count, tall.Count);
            double travelledOwn = 0, travelledTall = 0;
            for (int i = 0; i < own.Count; i++)
            {
                Assert.AreEqual(own[i].GetJointRotation(5), tall[i].GetJointRotation(5), $"pose {i}: the pose is the model's");
                Vec3 v = own[i].RootVelocity, w = tall[i].RootVelocity;
                Assert.AreEqual(gain * v.X, w.X, 1e-5 + 1e-5 * Math.Abs(v.X), $"pose {i} velocity x");
                Assert.AreEqual(gain * v.Z, w.Z, 1e-5 + 1e-5 * Math.Abs(v.Z), $"pose {i} velocity z");
                if (i > 0)
                {
                    travelledOwn += (own[i].RootPosition - own[i - 1].RootPosition).Length;
                    travelledTall += (tall[i].RootPosition - tall[i - 1].RootPosition).Length;
                }
            }
            Assert.Greater(travelledOwn, 0.1, "the capture moves the root");
            Assert.AreEqual(gain, travelledTall / travelledOwn, 1e-3);

            using var session = SolverReplay.OpenCalibratedReplay(_capture, info.FrameRate);
            using var solver = MocapSolver.Open(_model);
            solver.AddCharacter(session);
            var e = Assert.Throws<MocapException>(() => solver.SetCharacterHeight(0, MocapSolver.MaxHeight + 0.1f));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("1..2.5 m", e.Message);
            solver.SetCharacterHeight(0, MocapSolver.MinHeight);
        }

        [Test]
        public void SmoothingSettingsReachTheEngine()
        {
            var defaults = new SolverConfig();
            Assert.AreEqual(2f, defaults.SmoothingMinCutoffHz);
            Assert.AreEqual(12f, defaults.SmoothingBeta);
            var raw = SolverReplay.SolveOneCharacter(_capture, _model, new SolverConfig { SmoothingMinCutoffHz = 0f });
            var strong = SolverReplay.SolveOneCharacter(_capture, _model,
                new SolverConfig { SmoothingMinCutoffHz = 0.5f, SmoothingBeta = 0.5f });
            Assert.AreEqual(_poses.Count, raw.Count);
            Assert.AreEqual(_poses.Count, strong.Count);
            // how much every joint's frame-to-frame turn changes from one frame to the next,
            // summed: the jitter a viewer sees (a steady turn scores 0, so the filter's trend,
            // which follows turns, is not counted as jitter); the defaults (the fixture's poses)
            // sit between raw and strong smoothing
            double Motion(List<MocapPose> poses)
            {
                double sum = 0;
                for (int i = 2; i < poses.Count; i++)
                    for (int j = 0; j < MocapPose.JointCount; j++)
                    {
                        Quat now = poses[i].GetJointRotation(j) * poses[i - 1].GetJointRotation(j).Inverse;
                        Quat before = poses[i - 1].GetJointRotation(j) * poses[i - 2].GetJointRotation(j).Inverse;
                        sum += Quat.Angle(now, before);
                    }
                return sum;
            }
            double r = Motion(raw), d = Motion(_poses), s = Motion(strong);
            Assert.Less(d, r, $"default {d} vs raw {r}");
            Assert.Less(s, d, $"strong {s} vs default {d}");
        }

        [Test]
        public void SmoothingThatWaitsReachesTheEngine()
        {
            // each pose the centred 1/4, 1/2, 1/4 average of the raw rotations around its frame,
            // stamped with its frame, one frame later; every frame keeps its pose
            Assert.AreEqual(0, new SolverConfig().SmoothingDelayFrames);
            var raw = SolverReplay.SolveOneCharacter(_capture, _model, new SolverConfig { SmoothingMinCutoffHz = 0f });
            var waited = SolverReplay.SolveOneCharacter(_capture, _model, new SolverConfig { SmoothingDelayFrames = 1 });
            Assert.AreEqual(raw.Count, waited.Count);
            Assert.Greater(raw.Count, 10);
            for (int i = 1; i + 1 < raw.Count; i++)
            {
                Assert.AreEqual(raw[i].FrameSequence, waited[i].FrameSequence);
                for (int j = 0; j < MocapPose.JointCount; j += 5)
                {
                    Quat before = raw[i - 1].GetJointRotation(j), at = raw[i].GetJointRotation(j),
                         after = raw[i + 1].GetJointRotation(j);
                    Quat Near(Quat q) => Quat.Dot(q, at) < 0 ? new Quat(-q.X, -q.Y, -q.Z, -q.W) : q;
                    Quat b = Near(before), a = Near(after);
                    var mean = new Quat(0.25f * b.X + 0.5f * at.X + 0.25f * a.X, 0.25f * b.Y + 0.5f * at.Y + 0.25f * a.Y,
                                        0.25f * b.Z + 0.5f * at.Z + 0.25f * a.Z, 0.25f * b.W + 0.5f * at.W + 0.25f * a.W).Normalized;
                    Assert.Less(Quat.Angle(mean, waited[i].GetJointRotation(j)), 2e-4, $"pose {i} joint {j} (radians)");
                }
            }
            var e = Assert.Throws<MocapException>(() => MocapSolver.Open(_model,
                new SolverConfig { SmoothingDelayFrames = SolverConfig.MaxSmoothingDelayFrames + 1 }));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("smoothing delay", e.Message);
        }

        [Test]
        public void FootPinningReachesTheEngine()
        {
            // Planted feet slide less; the root, the contacts and the upper body stay as they were.
            Assert.AreEqual(0f, new SolverConfig().FootPinSlideSpeed);
            var free = SolverReplay.SolveOneCharacter(_capture, _model, new SolverConfig { SmoothingMinCutoffHz = 0f });
            var pinned = SolverReplay.SolveOneCharacter(_capture, _model,
                new SolverConfig { SmoothingMinCutoffHz = 0f, FootPinSlideSpeed = 0.06f });
            Assert.AreEqual(free.Count, pinned.Count);
            Assert.Greater(free.Count, 100);
            int bent = 0;
            for (int i = 0; i < free.Count; i++)
            {
                Assert.AreEqual(free[i].RootPosition, pinned[i].RootPosition, $"pose {i}");
                Assert.AreEqual(free[i].Flags, pinned[i].Flags, $"pose {i}");
                Assert.AreEqual(free[i].GetJointPosition(SmplJoint.Head), pinned[i].GetJointPosition(SmplJoint.Head), $"pose {i}");
                if (!free[i].GetJointRotation(SmplJoint.LeftKnee).Equals(pinned[i].GetJointRotation(SmplJoint.LeftKnee))) bent++;
            }
            Assert.Greater(bent, 0, "no leg was bent to hold a foot");
            Assert.Less(PlantedFootSlide(pinned), PlantedFootSlide(free));
            var e = Assert.Throws<MocapException>(() => MocapSolver.Open(_model,
                new SolverConfig { FootPinSlideSpeed = SolverConfig.MaxFootPinSlideSpeed * 2f }));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("foot pinning", e.Message);
        }

        [Test]
        public void PoseLimitsReachTheEngine()
        {
            // A tolerance far tighter than any real use turns most joints back; the root's
            // orientation and the model's velocity are never touched (the corrected root follows
            // the guarded feet).
            Assert.AreEqual(0f, new SolverConfig().PoseLimitDegrees);
            var free = SolverReplay.SolveOneCharacter(_capture, _model, new SolverConfig { SmoothingMinCutoffHz = 0f });
            var guarded = SolverReplay.SolveOneCharacter(_capture, _model,
                new SolverConfig { SmoothingMinCutoffHz = 0f, PoseLimitDegrees = 2f });
            Assert.AreEqual(free.Count, guarded.Count);
            Assert.Greater(free.Count, 100);
            int turned = 0;
            for (int i = 0; i < free.Count; i++)
            {
                Assert.AreEqual(free[i].GetJointRotation(SmplJoint.Pelvis), guarded[i].GetJointRotation(SmplJoint.Pelvis), $"pose {i}");
                Assert.AreEqual(free[i].RootVelocity, guarded[i].RootVelocity, $"pose {i}");
                if (!free[i].GetJointRotation(SmplJoint.LeftShoulder).Equals(guarded[i].GetJointRotation(SmplJoint.LeftShoulder))) turned++;
            }
            Assert.Greater(turned, free.Count / 4, "a 2 deg tolerance turns shoulders back");
            var e = Assert.Throws<MocapException>(() => MocapSolver.Open(_model,
                new SolverConfig { PoseLimitDegrees = 0.5f }));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("pose limits", e.Message);
        }

        [Test]
        public void ChestFollowingReachesTheEngine()
        {
            // The share reaches the engine, which checks it; a model without a chest sensor has
            // nothing to follow, so its poses stay bit for bit the model's.
            Assert.AreEqual(0f, new SolverConfig().ChestFollowShare);
            var free = SolverReplay.SolveOneCharacter(_capture, _model, new SolverConfig { SmoothingMinCutoffHz = 0f });
            var followed = SolverReplay.SolveOneCharacter(_capture, _model,
                new SolverConfig { SmoothingMinCutoffHz = 0f, ChestFollowShare = 1f });
            Assert.AreEqual(free.Count, followed.Count);
            Assert.Greater(free.Count, 100);
            for (int i = 0; i < free.Count; i++)
                for (int j = 0; j < MocapPose.JointCount; j++)
                    Assert.AreEqual(free[i].GetJointRotation(j), followed[i].GetJointRotation(j), $"pose {i} joint {j}");
            var e = Assert.Throws<MocapException>(() => MocapSolver.Open(_model,
                new SolverConfig { ChestFollowShare = 1.5f }));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("chest following", e.Message);
            Assert.AreEqual(0f, SolverConfig.ChestFollowFrom(float.NaN));
            Assert.AreEqual(0f, SolverConfig.ChestFollowFrom(-0.5f));
            Assert.AreEqual(0.5f, SolverConfig.ChestFollowFrom(0.5f));
            Assert.AreEqual(1f, SolverConfig.ChestFollowFrom(3f));
        }

        [Test]
        public void APoseLimitFromASliderIsOneTheEngineTakes()
        {
            Assert.AreEqual(0f, SolverConfig.PoseLimitFrom(0f));
            Assert.AreEqual(0f, SolverConfig.PoseLimitFrom(-3f));
            Assert.AreEqual(0f, SolverConfig.PoseLimitFrom(float.NaN));
            Assert.AreEqual(SolverConfig.MinPoseLimitDegrees, SolverConfig.PoseLimitFrom(0.2f));
            Assert.AreEqual(25f, SolverConfig.PoseLimitFrom(25f));
            Assert.AreEqual(SolverConfig.MaxPoseLimitDegrees, SolverConfig.PoseLimitFrom(400f));
        }

        // Mean horizontal distance a foot moves between two poses that both say it is planted.
        static double PlantedFootSlide(IReadOnlyList<MocapPose> poses)
        {
            double sum = 0;
            int n = 0;
            for (int i = 1; i < poses.Count; i++)
            {
                foreach (var (flag, joint) in new[] { (MocapPoseFlags.ContactLeft, SmplJoint.LeftFoot),
                                                      (MocapPoseFlags.ContactRight, SmplJoint.RightFoot) })
                {
                    if ((poses[i].Flags & flag) == 0 || (poses[i - 1].Flags & flag) == 0) continue;
                    Vec3 a = poses[i - 1].GetJointPosition(joint), b = poses[i].GetJointPosition(joint);
                    sum += Math.Sqrt((b.X - a.X) * (b.X - a.X) + (b.Z - a.Z) * (b.Z - a.Z));
                    n++;
                }
            }
            Assert.Greater(n, 10, "the capture should plant a foot");
            return sum / n;
        }

        [Test]
        public void DisposingSessionAndModelBeforeTheSolverIsSafe()
        {
            // The wrong order on purpose: the solver's handle references the session and model
            // handles, so their native close waits until the solver has stopped its thread.
            var model = MocapModel.Open(TestPaths.ModelPath);
            var session = SolverReplay.OpenCalibratedReplay(_capture, model.Info.FrameRate);
            var solver = MocapSolver.Open(model);
            solver.AddCharacter(session);
            solver.Start();
            session.Start();
            session.Dispose();
            model.Dispose();
            Assert.IsTrue(model.IsDisposed);
            Assert.Throws<ObjectDisposedException>(() => MocapSolver.Open(model));
            // The native session and model are still alive: the replay runs to its end.
            var poses = SolverReplay.DrainAll(solver)[0];
            Assert.AreEqual(_poses.Count, poses.Count);
            solver.Dispose();
            solver.Dispose();
        }
    }
}
