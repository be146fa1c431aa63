// End to end through the real engine, driven from C#: a generated capture's bytes -> decoded,
// filtered, calibrated frames -> drained into C# structs and checked against the generator's
// ground truth.

using System;
using System.Collections.Generic;
using System.Diagnostics;
using System.Globalization;
using System.IO;
using System.Linq;
using Mocap.Imu.Capture;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    /// <summary>The synth truth CSV: bone orientation and acceleration of every segment per tick.</summary>
    internal sealed class TruthTable
    {
        readonly double[] _t;
        readonly int[] _phase;
        readonly double[][] _values; // per row: 6 x (qw qx qy qz ax ay az)

        public TruthTable(string path)
        {
            var t = new List<double>();
            var phase = new List<int>();
            var values = new List<double[]>();
            foreach (var line in File.ReadLines(path))
            {
                if (line.Length == 0 || line[0] == 't' || line[0] == '#') continue;
                var cells = line.Split(',');
                Assert.AreEqual(44, cells.Length, $"truth row has {cells.Length} columns: {line}");
                t.Add(double.Parse(cells[0], CultureInfo.InvariantCulture));
                phase.Add(int.Parse(cells[1], CultureInfo.InvariantCulture));
                values.Add(cells.Skip(2).Select(c => double.Parse(c, CultureInfo.InvariantCulture)).ToArray());
            }
            _t = t.ToArray();
            _phase = phase.ToArray();
            _values = values.ToArray();
        }

        /// <summary>Truth at time t (linear in time, quaternions normalised); false outside the table.</summary>
        public bool TryGet(double t, out int phase, out MocapQuaternion[] bones, out MocapVector3[] accelerations)
        {
            phase = 0;
            bones = null;
            accelerations = null;
            if (t < _t[0] || t > _t[_t.Length - 1]) return false;
            int i = Array.BinarySearch(_t, t);
            if (i < 0) i = ~i - 1;
            int j = Math.Min(i + 1, _t.Length - 1);
            double u = _t[j] > _t[i] ? (t - _t[i]) / (_t[j] - _t[i]) : 0;
            phase = u < 0.5 ? _phase[i] : _phase[j];
            bones = new MocapQuaternion[6];
            accelerations = new MocapVector3[6];
            for (int s = 0; s < 6; s++)
            {
                double[] a = _values[i], b = _values[j];
                int o = s * 7;
                // Rows are 10 ms apart: a sign-aligned normalised lerp is as good as slerp here.
                double sign = a[o] * b[o] + a[o + 1] * b[o + 1] + a[o + 2] * b[o + 2] + a[o + 3] * b[o + 3] < 0 ? -1 : 1;
                var q = new double[4];
                double norm = 0;
                for (int k = 0; k < 4; k++)
                {
                    q[k] = a[o + k] + u * (sign * b[o + k] - a[o + k]);
                    norm += q[k] * q[k];
                }
                norm = Math.Sqrt(norm);
                bones[s] = new MocapQuaternion((float)(q[0] / norm), (float)(q[1] / norm), (float)(q[2] / norm),
                                               (float)(q[3] / norm));
                accelerations[s] = new MocapVector3((float)(a[o + 4] + u * (b[o + 4] - a[o + 4])),
                                                    (float)(a[o + 5] + u * (b[o + 5] - a[o + 5])),
                                                    (float)(a[o + 6] + u * (b[o + 6] - a[o + 6])));
            }
            return true;
        }
    }

    /// <summary>Everything a replay run through <see cref="MocapSession"/> produced.</summary>
    internal sealed class ReplayResult
    {
        public readonly List<MocapFrame> Frames = new List<MocapFrame>();
        public CalibrationReport Heading, TPose;
        public CalibrationReport HeadingBeforeStart, TPoseBeforeStart;
        public MocapSessionStats Stats;
        public CalibrationData Calibration;
        public bool ReachedEndOfStream;
        public MocapPollResult ResultAfterEnd;
    }

    internal static class Replay
    {
        /// <summary>First receive time of a capture, seconds on the session clock (pure C# reader).</summary>
        public static double FirstReceiveSeconds(string capturePath)
        {
            using var reader = new CaptureReader(capturePath);
            Assert.IsTrue(reader.TryReadNext(out var record), "the capture holds no records");
            return record.ReceiveNs * 1e-9;
        }

        /// <summary>
        /// Replays a synth capture as fast as possible. With calibration == null it schedules
        /// the heading and T-pose windows of the prelude before Start (the middle of each window,
        /// as mocapctl replay does); otherwise it sets that calibration and schedules nothing.
        /// <paramref name="sensors"/> replaces the default sensor set.
        /// </summary>
        public static ReplayResult Run(SynthCapture capture, CalibrationData? calibration = null,
                                       int drainCapacity = 64, IEnumerable<SessionSensor> sensors = null)
        {
            var result = new ReplayResult();
            var config = SessionConfig.Replay(capture.CapturePath);
            if (sensors != null)
            {
                config.Sensors.Clear();
                config.Sensors.AddRange(sensors);
            }
            using var session = MocapSession.Open(config);
            if (calibration == null)
            {
                double t0 = FirstReceiveSeconds(capture.CapturePath);
                session.ScheduleCalibration(CalibrationStep.Heading, t0 + 0.5, (float)(capture.HeadingSeconds - 1.0));
                session.ScheduleCalibration(CalibrationStep.TPose,
                    t0 + capture.HeadingSeconds + capture.StrapSeconds + 0.5, (float)(capture.TPoseSeconds - 1.0));
            }
            else
            {
                session.Calibration = calibration.Value;
            }
            result.HeadingBeforeStart = session.GetCalibrationReport(CalibrationStep.Heading);
            result.TPoseBeforeStart = session.GetCalibrationReport(CalibrationStep.TPose);
            session.Start();

            var buffer = new MocapFrame[drainCapacity];
            var watch = Stopwatch.StartNew();
            for (;;)
            {
                var r = session.Drain(buffer, out int count);
                for (int i = 0; i < count; i++) result.Frames.Add(buffer[i]);
                if (r == MocapPollResult.EndOfStream) break;
                if (r == MocapPollResult.NoData) System.Threading.Thread.Sleep(1);
                if (watch.Elapsed > TimeSpan.FromSeconds(60)) Assert.Fail("the replay did not end within 60 s");
            }
            result.ReachedEndOfStream = session.IsEndOfStream;
            var last = default(MocapFrame);
            result.ResultAfterEnd = session.PollLatest(ref last);
            result.Heading = session.GetCalibrationReport(CalibrationStep.Heading);
            result.TPose = session.GetCalibrationReport(CalibrationStep.TPose);
            result.Stats = session.GetStats();
            result.Calibration = session.Calibration;
            return result;
        }

        /// <summary>Per-sensor mean and max bone angle error (deg) and acceleration RMS over the motion phase.</summary>
        public static (double[] mean, double[] max, double[] accRms, int compared) CompareWithTruth(
            IEnumerable<MocapFrame> frames, TruthTable truth)
        {
            var sum = new double[6];
            var max = new double[6];
            var acc = new double[6];
            int n = 0;
            foreach (var f in frames)
            {
                if (!f.IsCalibrated) continue;
                if (!truth.TryGet(f.TimeSeconds, out int phase, out var bones, out var accs) || phase != 3) continue;
                // The truth lists the six default segments in segment order.
                for (int s = 0; s < 6; s++)
                {
                    Assert.IsTrue(f.TryGetSensor((MocapSegment)s, out var sensor), $"frame {f.Sequence} has no {(MocapSegment)s}");
                    double angle = MocapQuaternion.AngleDegrees(sensor.BoneOrientation, bones[s]);
                    sum[s] += angle;
                    max[s] = Math.Max(max[s], angle);
                    double dx = sensor.BoneAcceleration.X - accs[s].X, dy = sensor.BoneAcceleration.Y - accs[s].Y,
                           dz = sensor.BoneAcceleration.Z - accs[s].Z;
                    acc[s] += dx * dx + dy * dy + dz * dz;
                }
                n++;
            }
            var mean = sum.Select(x => n > 0 ? x / n : double.NaN).ToArray();
            var rms = acc.Select(x => n > 0 ? Math.Sqrt(x / n) : double.NaN).ToArray();
            return (mean, max, rms, n);
        }
    }

    [TestFixture]
    public sealed class SessionReplayTests
    {
        // The engine reaches ~0.2-0.3 deg mean with the synth's realistic noise; these bounds
        // leave room for platform differences but catch any mapping, order or sign mistake.
        const double MeanAngleToleranceDeg = 0.6;
        const double MaxAngleToleranceDeg = 3.0;
        const double AccelerationRmsTolerance = 1.0; // m/s^2 (the engine gives ~0.3)

        SynthCapture _capture;
        ReplayResult _run;

        [OneTimeSetUp]
        public void ReplayOnce()
        {
            TestPaths.RequireEngine();
            _capture = TestPaths.Synth("walk", seconds: 6);
            _run = Replay.Run(_capture);
        }

        [Test]
        public void CalibrationStepsWaitBeforeStartThenAreAccepted()
        {
            Assert.AreEqual(CalibrationState.Waiting, _run.HeadingBeforeStart.State);
            Assert.AreEqual(CalibrationState.Waiting, _run.TPoseBeforeStart.State);
            foreach (var report in new[] { _run.Heading, _run.TPose })
            {
                Assert.AreEqual(CalibrationState.Accepted, report.State, report.ToString());
                Assert.AreEqual("", report.Reason);
                Assert.AreEqual(1f, report.Progress, 1e-6f);
                Assert.AreEqual(6, report.SensorCount);
                for (int s = 0; s < 6; s++)
                {
                    var q = report.GetSensor(s);
                    Assert.AreEqual((MocapSegment)s, q.Segment, "the default set is in segment order");
                    Assert.IsFalse(q.IsLeftOut);
                    Assert.IsTrue(q.IsOk, $"{report.Step} {(MocapSegment)s} not ok");
                    Assert.Greater(q.Samples, 50u, $"{report.Step} {(MocapSegment)s} samples");
                    Assert.Less(q.GyroRmsDps, 10f);
                    Assert.Less(q.OrientationSpreadDegrees, 3f);
                }
            }
            Assert.AreEqual(CalibrationStep.Heading, _run.Heading.Step);
            Assert.AreEqual(CalibrationStep.TPose, _run.TPose.Step);
            Assert.AreEqual(0x3Fu, _run.Calibration.ValidMask);
            Assert.IsTrue(_run.Calibration.IsComplete);
        }

        [Test]
        public void FramesFlowInOrderUntilEndOfStream()
        {
            var frames = _run.Frames;
            double duration = _capture.HeadingSeconds + _capture.StrapSeconds + _capture.TPoseSeconds + 6;
            Assert.That(frames.Count, Is.InRange((int)((duration - 1) * 60), (int)((duration + 1) * 60)));
            for (int i = 0; i < frames.Count; i++)
            {
                Assert.AreEqual((ulong)i, frames[i].Sequence, "a fast replay loses no frame");
                if (i > 0)
                    Assert.AreEqual(1.0 / 60, frames[i].TimeSeconds - frames[i - 1].TimeSeconds, 1e-6, $"frame {i} time step");
            }
            Assert.IsTrue(_run.ReachedEndOfStream);
            Assert.AreEqual(MocapPollResult.EndOfStream, _run.ResultAfterEnd, "stays at the end");
            // Calibrated from the end of the T-pose window on, uncalibrated before the heading step.
            Assert.IsFalse(frames[0].IsCalibrated);
            Assert.IsFalse(frames[0].GetSensor(0).IsCalibrated);
            Assert.IsTrue(frames[frames.Count - 1].IsCalibrated);
            for (int s = 0; s < 6; s++)
            {
                Assert.AreEqual(6, frames[frames.Count - 1].SensorCount);
                var sensor = frames[frames.Count - 1].GetSensor(s);
                Assert.AreEqual((MocapSegment)s, sensor.Segment);
                Assert.IsTrue(sensor.IsValid && sensor.IsCalibrated, $"{(MocapSegment)s} flags {sensor.Flags}");
                Assert.AreNotEqual(MocapSensorState.Absent, sensor.State, $"{(MocapSegment)s} sent samples");
                Assert.AreEqual((uint)s, sensor.NodeId, "default node ids are 0..5 in segment order");
            }
            int calibrated = frames.Count(f => f.IsCalibrated);
            Assert.That(calibrated, Is.InRange(5 * 60, 7 * 60), "the motion phase (6 s) is calibrated");
        }

        [Test]
        public void CalibratedBonesMatchTheTruth()
        {
            var truth = new TruthTable(_capture.TruthPath);
            var (mean, max, accRms, compared) = Replay.CompareWithTruth(_run.Frames, truth);
            Assert.Greater(compared, 300, "motion-phase frames compared");
            for (int s = 0; s < 6; s++)
            {
                var name = (MocapSegment)s;
                TestContext.WriteLine($"{name,-11} mean {mean[s]:F3} deg  max {max[s]:F3} deg  acc rms {accRms[s]:F3} m/s^2");
                Assert.Less(mean[s], MeanAngleToleranceDeg, $"{name} mean angle error");
                Assert.Less(max[s], MaxAngleToleranceDeg, $"{name} max angle error");
                Assert.Less(accRms[s], AccelerationRmsTolerance, $"{name} acceleration RMS error");
            }
        }

        [Test]
        public void StatsCountWhatTheCaptureHolds()
        {
            long bytes = 0, records = 0;
            using (var reader = new CaptureReader(_capture.CapturePath))
                while (reader.TryReadNext(out var r))
                {
                    bytes += r.Bytes.Length;
                    records++;
                }
            var stats = _run.Stats;
            Assert.AreEqual((ulong)bytes, stats.BytesReceived, "every byte of the capture reached the engine");
            // The synth writes one 0x62 gateway frame of six nodes per record.
            Assert.AreEqual((ulong)records, stats.FramesDecoded);
            Assert.AreEqual(6 * stats.FramesDecoded, stats.SamplesDecoded);
            Assert.AreEqual(0ul, stats.CrcFailures);
            Assert.AreEqual(0ul, stats.BytesSkipped);
            Assert.AreEqual(0ul, stats.SamplesRejected);
            Assert.AreEqual(0ul, stats.FramesDropped);
            Assert.AreEqual(0ul, stats.BytesDropped);
            Assert.AreEqual((ulong)_run.Frames.Count, stats.FramesEmitted);
            Assert.AreEqual(0x3Fu, stats.SensorsSeenMask);
            Assert.AreEqual(MocapConnectionState.Ended, stats.ConnectionState);
            Assert.AreEqual(MocapStatus.Ok, stats.CaptureError);
            Assert.AreEqual(0ul, stats.ReplayChunksSkipped);
            Assert.IsFalse(stats.ReplayTailDamaged);
            Assert.AreEqual("", stats.ReplayDamage);
        }

        [Test]
        public void StatsSayWhatADamagedCaptureLeftOut()
        {
            // Three damaged chunks and a cut-off end: the replay passes over them (a crash-damaged
            // capture is still worth replaying) and the stats say what is missing.
            var run = ReplayAlteredCopy("damaged", bytes =>
            {
                Assert.Greater(bytes.Length, 200000);
                for (int k = 0; k < 3; k++) bytes[bytes.Length / 3 + k * 30000] ^= 0xff;
                Array.Resize(ref bytes, bytes.Length - 100);
                return bytes;
            });
            Assert.IsTrue(run.ReachedEndOfStream);
            Assert.AreEqual(3ul, run.Stats.ReplayChunksSkipped);
            Assert.IsTrue(run.Stats.ReplayTailDamaged);
            Assert.AreEqual("", run.Stats.LastError, "the damage is not an error that ended the replay");
            Assert.AreEqual("The capture is damaged: 3 chunk(s) passed over and its end cut short; "
                            + "what they held is missing from the poses.", run.Stats.ReplayDamage);
            Assert.Less(run.Stats.BytesReceived, _run.Stats.BytesReceived);
            Assert.Greater(run.Frames.Count, _run.Frames.Count / 2, "what could be read was replayed");
        }

        [Test]
        public void StatsTellACutShortCaptureFromAnInnerDamagedOne()
        {
            // A recording that stopped mid-chunk (a crash) is whole up to its end: only the tail
            // is missing, and the wording must not claim chunks were passed over.
            var run = ReplayAlteredCopy("cut", bytes =>
            {
                Array.Resize(ref bytes, bytes.Length - 100);
                return bytes;
            });
            Assert.AreEqual(0ul, run.Stats.ReplayChunksSkipped);
            Assert.IsTrue(run.Stats.ReplayTailDamaged);
            Assert.AreEqual("The capture is cut short: its last records are missing from the poses.",
                            run.Stats.ReplayDamage);
        }

        /// <summary>Replays a copy of the shared capture whose bytes <paramref name="alter"/> changed.</summary>
        ReplayResult ReplayAlteredCopy(string name, Func<byte[], byte[]> alter)
        {
            var copy = new SynthCapture
            {
                CapturePath = Path.Combine(TestPaths.NewTempDirectory(name), name + ".cap"),
                TruthPath = _capture.TruthPath,
            };
            File.WriteAllBytes(copy.CapturePath, alter(File.ReadAllBytes(_capture.CapturePath)));
            return Replay.Run(copy);
        }

        [Test]
        public void FramesEqualMocapctlReplayOfTheSameCapture()
        {
            // mocapctl schedules the same windows; its frame CSV, read back with FrameRecording,
            // must equal what C# drained field for field (to the CSV's printed precision).
            var csv = Path.Combine(TestPaths.NewTempDirectory("frames"), "frames.csv");
            TestPaths.RunMocapctl("replay", _capture.CapturePath, "--csv", csv);
            var expected = FrameRecording.Load(csv);
            Assert.AreEqual(expected.Length, _run.Frames.Count);
            for (int i = 0; i < expected.Length; i++)
            {
                MocapFrame e = expected[i], a = _run.Frames[i];
                Assert.AreEqual(e.Sequence, a.Sequence);
                Assert.AreEqual(e.TimeSeconds, a.TimeSeconds, 1e-6);
                Assert.AreEqual(e.Flags, a.Flags, $"frame {i} flags");
                Assert.AreEqual(e.FreshMask, a.FreshMask, $"frame {i} fresh mask");
                Assert.AreEqual(e.SensorCount, a.SensorCount, $"frame {i} sensor count");
                for (int s = 0; s < e.SensorCount; s++)
                {
                    var es = e.GetSensor(s);
                    var sensor = a.GetSensor(s);
                    string where = $"frame {i} sensor {s}";
                    Assert.AreEqual(es.Segment, sensor.Segment, where);
                    Assert.AreEqual(es.Flags, sensor.Flags, where);
                    Assert.AreEqual(es.BoneOrientation.W, sensor.BoneOrientation.W, 2e-6, where);
                    Assert.AreEqual(es.BoneOrientation.X, sensor.BoneOrientation.X, 2e-6, where);
                    Assert.AreEqual(es.BoneOrientation.Y, sensor.BoneOrientation.Y, 2e-6, where);
                    Assert.AreEqual(es.BoneOrientation.Z, sensor.BoneOrientation.Z, 2e-6, where);
                    Assert.AreEqual(es.BoneAcceleration.X, sensor.BoneAcceleration.X, 2e-4, where);
                    Assert.AreEqual(es.BoneAcceleration.Y, sensor.BoneAcceleration.Y, 2e-4, where);
                    Assert.AreEqual(es.BoneAcceleration.Z, sensor.BoneAcceleration.Z, 2e-4, where);
                }
            }
        }

        [Test]
        public void FrameRecordingRoundTrips()
        {
            var path = Path.Combine(TestPaths.NewTempDirectory("recording"), "frames.csv");
            var frames = _run.Frames.ToArray();
            FrameRecording.Save(path, frames);
            var loaded = FrameRecording.Load(path);
            Assert.AreEqual(frames.Length, loaded.Length);
            var last = loaded[loaded.Length - 1];
            Assert.AreEqual(frames[frames.Length - 1].Sequence, last.Sequence);
            Assert.IsTrue(frames[frames.Length - 1].TryGetSensor(MocapSegment.Head, out var savedHead));
            Assert.IsTrue(last.TryGetSensor(MocapSegment.Head, out var loadedHead));
            Assert.AreEqual(savedHead.BoneOrientation.X, loadedHead.BoneOrientation.X, 1e-6);
            Assert.AreEqual(6, last.SensorCount);
            StringAssert.StartsWith($"# mocap frame recording {FrameRecording.Version}\n", File.ReadAllText(path));
        }

        [Test]
        public void FrameRecordingOfVersionOneStillReadsAsTheSix()
        {
            // Version 1 (before sensor sets): no version line; mocapctl wrote the six's header,
            // older files may hold rows only. Both read as the six segments pelvis .. head.
            var dir = TestPaths.NewTempDirectory("recording-v1");
            var current = Path.Combine(dir, "current.csv");
            FrameRecording.Save(current, _run.Frames.ToArray());
            var lines = File.ReadAllLines(current);
            Assert.AreEqual("# mocap frame recording 2", lines[0]);
            StringAssert.StartsWith("sequence,time_s,flags,pelvis_qw,pelvis_qx", lines[1]);
            var withHeader = Path.Combine(dir, "v1-header.csv");
            File.WriteAllLines(withHeader, lines.Skip(1));
            var rowsOnly = Path.Combine(dir, "v1-rows.csv");
            File.WriteAllLines(rowsOnly, lines.Skip(2));
            foreach (var path in new[] { withHeader, rowsOnly })
            {
                var frames = FrameRecording.Load(path);
                Assert.AreEqual(_run.Frames.Count, frames.Length, path);
                var last = frames[frames.Length - 1];
                Assert.AreEqual(6, last.SensorCount, path);
                for (int s = 0; s < 6; s++) Assert.AreEqual((MocapSegment)s, last.GetSensor(s).Segment, path);
                Assert.AreEqual(_run.Frames[_run.Frames.Count - 1].GetSensor(5).BoneOrientation.Y,
                                last.GetSensor(5).BoneOrientation.Y, 1e-6, path);
            }

            // A later version, or a version 2 file without its header, is refused by name.
            var future = Path.Combine(dir, "v3.csv");
            File.WriteAllLines(future, new[] { "# mocap frame recording 3" }.Concat(lines.Skip(1)));
            var e = Assert.Throws<MocapException>(() => FrameRecording.Load(future));
            StringAssert.Contains("format version 3", e.Message);
            var headless = Path.Combine(dir, "v2-rows.csv");
            File.WriteAllLines(headless, new[] { lines[0] }.Concat(lines.Skip(2)));
            e = Assert.Throws<MocapException>(() => FrameRecording.Load(headless));
            StringAssert.Contains("v2-rows.csv:2: a row before the header", e.Message);
            var unknown = Path.Combine(dir, "tail.csv");
            File.WriteAllLines(unknown, new[] { lines[0], lines[1].Replace("pelvis_", "tail_") }.Concat(lines.Skip(2)));
            e = Assert.Throws<MocapException>(() => FrameRecording.Load(unknown));
            StringAssert.Contains("column 'tail_qw' does not name a body segment", e.Message);
        }

        [TestCase(0, "12x")]
        [TestCase(0, "-1")]
        [TestCase(2, "4294967296")]
        [TestCase(10, "7.5")]
        public void FrameRecordingNamesTheFileAndLineOfABadWholeNumber(int column, string bad)
        {
            // Sequence, frame flags and sensor flags are whole numbers: a corrupt cell is a format
            // error naming the file and line, like a bad float cell, not a bare FormatException.
            var e = LoadFramesWithOneCellReplaced(frame: 2, column, bad, out int line);
            StringAssert.Contains($"frames.csv:{line}:", e.Message);
            StringAssert.Contains(bad, e.Message);
        }

        [TestCase(3, "1e39", "beyond float range")]      // finite as a double, infinite as a float
        [TestCase(7, "nan", "not a finite number")]
        [TestCase(1, "-inf", "not a finite number")]
        public void FrameRecordingRefusesNumbersThatAreNotFiniteFloats(int column, string bad, string expected)
        {
            var e = LoadFramesWithOneCellReplaced(frame: 0, column, bad, out int line);
            StringAssert.Contains($"frames.csv:{line}:", e.Message);
            StringAssert.Contains(expected, e.Message);
        }

        // Saves the replay's frames as CSV with one cell of one frame's row replaced, loads it and
        // returns the format error; line is the 1-based line of that row.
        MocapException LoadFramesWithOneCellReplaced(int frame, int column, string value, out int line)
        {
            var path = Path.Combine(TestPaths.NewTempDirectory("corrupt"), "frames.csv");
            FrameRecording.Save(path, _run.Frames.ToArray());
            var lines = File.ReadAllLines(path);
            int row = Array.FindIndex(lines, l => l.Length > 0 && char.IsDigit(l[0])) + frame;
            var cells = lines[row].Split(',');
            cells[column] = value;
            lines[row] = string.Join(",", cells);
            File.WriteAllLines(path, lines);
            var e = Assert.Throws<MocapException>(() => FrameRecording.Load(path));
            Assert.AreEqual(MocapStatus.Format, e.Status, e.Message);
            line = row + 1;
            return e;
        }

        [Test]
        public void PollLatestReturnsTheNewestFrameThenNoData()
        {
            using var session = MocapSession.Open(SessionConfig.Replay(_capture.CapturePath));
            var frame = default(MocapFrame);
            Assert.AreEqual(MocapPollResult.NoData, session.PollLatest(ref frame), "nothing before Start");
            Assert.IsFalse(session.IsRunning);
            session.Start();
            Assert.IsTrue(session.IsRunning);
            var watch = Stopwatch.StartNew();
            ulong lastSequence = 0;
            int polls = 0;
            MocapPollResult r;
            while ((r = session.PollLatest(ref frame)) != MocapPollResult.EndOfStream)
            {
                if (r == MocapPollResult.Frames)
                {
                    Assert.That(frame.Sequence, polls == 0 ? Is.GreaterThanOrEqualTo(0ul) : Is.GreaterThan(lastSequence));
                    lastSequence = frame.Sequence;
                    polls++;
                }
                Assert.Less(watch.Elapsed.TotalSeconds, 60);
            }
            Assert.Greater(polls, 0);
            Assert.AreEqual((ulong)_run.Frames.Count - 1, lastSequence, "the last poll saw the last frame");
            Assert.AreEqual(MocapPollResult.EndOfStream, session.PollLatest(ref frame));
            Assert.AreEqual(lastSequence, frame.Sequence, "frame untouched at the end");
        }

        [Test]
        public void StopThenStartReplaysAgainWithTheSameCalibration()
        {
            using var session = MocapSession.Open(SessionConfig.Replay(_capture.CapturePath));
            session.Calibration = _run.Calibration;
            session.Start();
            var buffer = new MocapFrame[8];
            var watch = Stopwatch.StartNew();
            int count;
            while (session.Drain(buffer, out count) != MocapPollResult.Frames)
                Assert.Less(watch.Elapsed.TotalSeconds, 30);
            var final = session.Stop();
            Assert.IsFalse(session.IsRunning);
            Assert.Greater(final.BytesReceived, 0ul);
            Assert.AreEqual(final.BytesReceived, session.GetStats().BytesReceived, "GetStats keeps the final stats");
            Assert.AreEqual(final.BytesReceived, session.Stop().BytesReceived, "a second Stop returns them too");
            // Read after the stop (a step can still finish on the bytes read before it), and
            // readable while stopped: what the next Start restores.
            Assert.AreEqual(0x3Fu, session.Calibration.ValidMask, "the calibration as the session stopped");

            session.Start();
            watch.Restart();
            while (session.Drain(buffer, out count) != MocapPollResult.Frames)
                Assert.Less(watch.Elapsed.TotalSeconds, 30);
            Assert.AreEqual(0ul, buffer[0].Sequence, "the reopened replay starts over");
            Assert.AreEqual(0x3Fu, session.Calibration.ValidMask, "calibration kept across Stop/Start");
            Assert.IsTrue(buffer[count - 1].IsCalibrated || !buffer[count - 1].IsComplete);
        }

        // The capture replayed to its end while recording it again into copy, then stopped: Stop
        // is where the last chunk is written and the file closed. Returns Stop's final stats.
        MocapSessionStats RecordWholeReplay(MocapSession session)
        {
            session.Start();
            var buffer = new MocapFrame[64];
            var watch = Stopwatch.StartNew();
            while (session.Drain(buffer, out _) != MocapPollResult.EndOfStream)
                Assert.Less(watch.Elapsed.TotalSeconds, 60);
            var final = session.Stop();
            Assert.AreEqual(MocapStatus.Ok, final.CaptureError, final.LastError);
            return final;
        }

        MocapSession OpenRecordingReplay(string copy)
        {
            var config = SessionConfig.Replay(_capture.CapturePath);
            config.CapturePath = copy;
            return MocapSession.Open(config);
        }

        [Test]
        public void StopClosesTheRecordingAndReportsItsFinalSize()
        {
            var copy = Path.Combine(TestPaths.NewTempDirectory("rerecord"), "copy.cap");
            using var session = OpenRecordingReplay(copy);
            var final = RecordWholeReplay(session);
            Assert.AreEqual((ulong)new FileInfo(copy).Length, final.CaptureBytesWritten,
                            "the final stats give the closed file's size");
            long original = 0, recorded = 0;
            using (var reader = new CaptureReader(_capture.CapturePath))
                while (reader.TryReadNext(out var r)) original += r.Bytes.Length;
            using (var reader = new CaptureReader(copy))
                while (reader.TryReadNext(out var r)) recorded += r.Bytes.Length;
            Assert.AreEqual(original, recorded, "every replayed byte is in the new recording");
            Assert.AreEqual(final.CaptureBytesWritten, session.GetStats().CaptureBytesWritten);
        }

        [Test]
        public void StartAfterStopRefusesToOverwriteTheRecording()
        {
            // Reopening with the same CapturePath would truncate the first recording.
            var copy = Path.Combine(TestPaths.NewTempDirectory("norestart"), "first.cap");
            using var session = OpenRecordingReplay(copy);
            var final = RecordWholeReplay(session);
            var recorded = File.ReadAllBytes(copy);
            Assert.Greater(recorded.Length, 0);
            Assert.AreEqual((ulong)recorded.Length, final.CaptureBytesWritten);

            var e = Assert.Throws<InvalidOperationException>(() => session.Start());
            StringAssert.Contains(copy, e.Message, "the message names the capture");
            StringAssert.Contains("would be overwritten", e.Message);
            StringAssert.Contains("another CapturePath", e.Message);
            Assert.IsFalse(session.IsRunning);
            CollectionAssert.AreEqual(recorded, File.ReadAllBytes(copy), "the first recording is intact");
            Assert.AreEqual(final.CaptureBytesWritten, session.GetStats().CaptureBytesWritten, "the final stats are kept");
        }

        [Test]
        public void OpeningAMissingPortThrowsTheEngineText()
        {
            string port = Environment.OSVersion.Platform == PlatformID.Win32NT ? "COM243" : "/dev/ttyMOCAP-missing-42";
            var e = Assert.Throws<MocapException>(() => MocapSession.Open(SessionConfig.Serial(port)));
            Assert.AreEqual(MocapStatus.NotFound, e.Status);
            StringAssert.Contains(port, e.Message, "the message names the port");
            TestContext.WriteLine(e.Message);
        }

        [Test]
        public void OpeningAMissingHidDeviceThrowsTheEngineText()
        {
            var path = Environment.OSVersion.Platform == PlatformID.Win32NT ? @"\\?\hid#missing" : "/dev/hidraw-mocap-missing";
            var e = Assert.Throws<MocapException>(() => MocapSession.Open(SessionConfig.Hid(path)));
            TestContext.WriteLine($"{e.Status}: {e.Message}");
            // NotFound with HIDAPI compiled in; Unsupported (saying so) in a build without it.
            Assert.That(e.Status, Is.EqualTo(MocapStatus.NotFound).Or.EqualTo(MocapStatus.Unsupported));
            if (e.Status == MocapStatus.NotFound) StringAssert.Contains(path, e.Message);
        }

        [Test]
        public void OpeningAMissingCaptureThrowsNotFound()
        {
            var path = Path.Combine(TestPaths.NewTempDirectory("missing"), "nothing.cap");
            var e = Assert.Throws<MocapException>(() => MocapSession.Open(SessionConfig.Replay(path)));
            Assert.AreEqual(MocapStatus.NotFound, e.Status);
            StringAssert.Contains(path, e.Message);
        }

        [Test]
        public void InvalidRequestsThrowWithTheEngineReason()
        {
            using var session = MocapSession.Open(SessionConfig.Replay(_capture.CapturePath));
            var e = Assert.Throws<MocapException>(() => session.BeginCalibration(CalibrationStep.TPose, 60f));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("0.2..15", e.Message);

            var config = SessionConfig.Replay(_capture.CapturePath);
            config.ReplaySpeed = -1;
            config.ReplayRealtime = true;
            e = Assert.Throws<MocapException>(() => MocapSession.Open(config));
            Assert.AreEqual(MocapStatus.InvalidArgument, e.Status);
            StringAssert.Contains("replay_speed", e.Message);

            // The engine queues a bounded number of steps (the header says 8; the session's 8 plus
            // the pipeline's 4 in this build); one more is refused with its own reason.
            int queued = 0;
            e = null;
            for (; queued < 64 && e == null; queued++)
            {
                try { session.ScheduleCalibration(CalibrationStep.HeadingReset, 100 + queued, 1f); }
                catch (MocapException refused) { e = refused; }
            }
            Assert.IsNotNull(e, "the queue is bounded");
            TestContext.WriteLine($"refused after {queued - 1} queued steps: {e.Message}");
            Assert.GreaterOrEqual(queued - 1, 8, "at least 8 steps can wait, as the header promises");
            Assert.AreEqual(MocapStatus.State, e.Status);
            StringAssert.Contains("already waiting", e.Message);
        }

        [Test]
        public void ApiVersionAndNamesComeFromTheEngine()
        {
            Assert.AreEqual(MocapEngine.BindingsApiVersion, MocapEngine.ApiVersion);
            StringAssert.IsMatch(@"^\d+\.\d+\.\d+$", MocapEngine.Version);
            Assert.AreEqual("left_wrist", MocapEngine.SegmentName(MocapSegment.LeftWrist));
            Assert.AreEqual("MOCAP_ERR_NOT_FOUND", MocapEngine.StatusName(MocapStatus.NotFound));
        }
    }
}
