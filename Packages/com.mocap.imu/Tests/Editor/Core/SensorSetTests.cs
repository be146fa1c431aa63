// Sensor sets from C#: the config's sensor list reaches the engine as it is written, frames,
// reports and calibrations list the sensors in the config's order and name them by segment, and
// a calibration applies by segment, not by position. Against the real engine and real captures.

using System;
using System.IO;
using System.Linq;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed unsafe class SensorSetTests
    {
        // The six of the default set with the chest on node 6, the chest second: frames must
        // follow this order, not the segments' numbers.
        const string SevenSensorList =
            "pelvis=0,left_wrist=1,right_wrist=2,left_shin=3,right_shin=4,head=5,chest=6";

        static SessionSensor[] Seven(bool chestOptional = false) => new[]
        {
            new SessionSensor(MocapSegment.Pelvis, 0),
            new SessionSensor(MocapSegment.Chest, 6, chestOptional),
            new SessionSensor(MocapSegment.LeftWrist, 1),
            new SessionSensor(MocapSegment.RightWrist, 2),
            new SessionSensor(MocapSegment.LeftShin, 3),
            new SessionSensor(MocapSegment.RightShin, 4),
            new SessionSensor(MocapSegment.Head, 5),
        };

        static SessionSensor[] SixAndChest(bool chestOptional) =>
            SensorSets.DefaultSix().Append(new SessionSensor(MocapSegment.Chest, 6, chestOptional)).ToArray();

        string _dir;

        [OneTimeSetUp]
        public void Engine()
        {
            TestPaths.RequireEngine();
            _dir = TestPaths.NewTempDirectory("sensor-sets");
        }

        [Test]
        public void TheDefaultSensorSetIsTheEnginesDefaultSet()
        {
            var engine = SegmentTable.DefaultSet();
            CollectionAssert.AreEqual(engine, new SessionConfig().Sensors, "a new config holds the engine's default set");
            CollectionAssert.AreEqual(engine, SensorSets.DefaultSix(), "the serialized settings' default is the engine's default set");
            Assert.AreEqual(6, engine.Length);
            Assert.AreEqual(-1, SegmentTable.DefaultNode(MocapSegment.Chest), "the chest is not in the default set");
            Assert.AreEqual(9, SegmentTable.SmplJoint(MocapSegment.Chest), "the chest sensor follows spine3");
            Assert.AreEqual(0, SegmentTable.SmplJoint(MocapSegment.Pelvis));
            Assert.AreEqual(15, SegmentTable.SmplJoint(MocapSegment.Head));
        }

        [Test]
        public void SettingsSavedWithSixNodeIdsBecomeASensorList()
        {
            var set = SensorSets.FromNodeIdsOfTheSix(new[] { 10, 11, 12, -1, 14, 15 });
            CollectionAssert.AreEqual(new[]
            {
                new SessionSensor(MocapSegment.Pelvis, 10), new SessionSensor(MocapSegment.LeftWrist, 11),
                new SessionSensor(MocapSegment.RightWrist, 12), new SessionSensor(MocapSegment.RightShin, 14),
                new SessionSensor(MocapSegment.Head, 15),
            }, set, "a segment without a sensor (-1) is left out; the others keep their node ids");
            var e = Assert.Throws<ArgumentException>(() => SensorSets.FromNodeIdsOfTheSix(new[] { 0, 1, 2 }));
            StringAssert.Contains("3 node ids", e.Message);
        }

        [Test]
        public void TheSensorListReachesTheEnginesConfigInOrder()
        {
            var config = SessionConfig.Replay("x.cap");
            config.Sensors.Clear();
            config.Sensors.AddRange(Seven(chestOptional: true));
            config.ToNative(out var native);
            Assert.AreEqual(7u, native.SensorCount);
            for (int i = 0; i < 7; i++)
            {
                Assert.AreEqual((int)config.Sensors[i].Segment, native.SensorSegments[i], $"segment of sensor {i}");
                Assert.AreEqual(config.Sensors[i].NodeId, native.NodeIds[i], $"node of sensor {i}");
            }
            Assert.AreEqual(1u << 1, native.OptionalMask, "only the chest (sensor 1) is optional");
            for (int i = 7; i < MocapSession.MaxSensors; i++)
                Assert.AreEqual(0, native.SensorSegments[i] | native.NodeIds[i], $"entry {i} beyond the set is zero");

            var copy = config.Clone();
            CollectionAssert.AreEqual(config.Sensors, copy.Sensors);
            copy.Sensors.RemoveAt(1);
            Assert.AreEqual(7, config.Sensors.Count, "a clone has its own list");
        }

        [Test]
        public void BadSensorSetsAreRefusedNamingTheSensors()
        {
            ArgumentException Refusal(params SessionSensor[] sensors)
            {
                var config = SessionConfig.Replay("x.cap");
                config.Sensors.Clear();
                config.Sensors.AddRange(sensors);
                return Assert.Throws<ArgumentException>(() => MocapSession.Open(config));
            }

            var e = Refusal(new SessionSensor(MocapSegment.Pelvis, 0), new SessionSensor(MocapSegment.Pelvis, 1));
            StringAssert.Contains("sensors 0 and 1 are both on pelvis", e.Message);
            e = Refusal(new SessionSensor(MocapSegment.Pelvis, 0), new SessionSensor(MocapSegment.Chest, 0));
            StringAssert.Contains("both use node id 0", e.Message);
            StringAssert.Contains("chest", e.Message);
            e = Refusal();
            StringAssert.Contains("no sensors", e.Message);
            e = Refusal(Enumerable.Range(0, 17).Select(i => new SessionSensor((MocapSegment)i, i)).ToArray());
            StringAssert.Contains("17 sensors; the engine takes at most 16", e.Message);

            // Ranges are the engine's to check; its refusal names the value.
            var capture = TestPaths.Synth("walk", seconds: 3);
            var config = SessionConfig.Replay(capture.CapturePath);
            config.Sensors[0] = new SessionSensor(MocapSegment.Pelvis, 300);
            var engine = Assert.Throws<MocapException>(() => MocapSession.Open(config));
            Assert.AreEqual(MocapStatus.InvalidArgument, engine.Status, engine.Message);
            StringAssert.Contains("300", engine.Message);
            config = SessionConfig.Replay(capture.CapturePath);
            config.Sensors[0] = new SessionSensor((MocapSegment)40, 0);
            engine = Assert.Throws<MocapException>(() => MocapSession.Open(config));
            Assert.AreEqual(MocapStatus.InvalidArgument, engine.Status, engine.Message);
            StringAssert.Contains("40", engine.Message);
        }

        [Test]
        public void AnAbsentOptionalChestIsLeftOutAndARequiredOneRefused()
        {
            // A six-sensor capture: nothing ever sends as node 6.
            var capture = TestPaths.Synth("walk", seconds: 3);
            var optional = Replay.Run(capture, sensors: SixAndChest(chestOptional: true));
            Assert.AreEqual(CalibrationState.Accepted, optional.Heading.State, optional.Heading.ToString());
            Assert.AreEqual(CalibrationState.Accepted, optional.TPose.State, optional.TPose.ToString());
            Assert.AreEqual(7, optional.TPose.SensorCount);
            Assert.IsTrue(optional.TPose.TryGetSensor(MocapSegment.Chest, out var chestQuality));
            Assert.IsTrue(chestQuality.IsLeftOut, "the optional chest that sent nothing is left out");
            Assert.IsTrue(optional.TPose.TryGetSensor(MocapSegment.Head, out var head) && head.IsOk && !head.IsLeftOut);
            Assert.IsFalse(optional.Calibration.IsValid(MocapSegment.Chest));
            Assert.IsTrue(optional.Calibration.IsValid(MocapSegment.Head));
            var last = optional.Frames[optional.Frames.Count - 1];
            Assert.AreEqual(7, last.SensorCount);
            Assert.IsTrue(last.IsCalibrated, "the frames count as calibrated without the optional chest");
            Assert.IsTrue(last.TryGetSensor(MocapSegment.Chest, out var chest));
            Assert.AreEqual(MocapSensorState.Absent, chest.State);
            Assert.IsFalse(chest.IsValid || chest.IsCalibrated, chest.Flags.ToString());

            var required = Replay.Run(capture, sensors: SixAndChest(chestOptional: false));
            Assert.AreEqual(CalibrationState.Refused, required.Heading.State);
            StringAssert.Contains("chest", required.Heading.Reason, "the refusal names the missing sensor");
            Assert.IsFalse(required.Frames[required.Frames.Count - 1].IsCalibrated);
        }

        [Test]
        public void ASevenSensorSessionCarriesTheChestInConfigOrder()
        {
            var capture = TestPaths.Synth("walk", seconds: 4, seed: 7, sensors: SevenSensorList);
            var run = Replay.Run(capture, sensors: Seven());
            Assert.AreEqual(CalibrationState.Accepted, run.TPose.State, run.TPose.ToString());
            var frames = run.Frames;
            Assert.Greater(frames.Count, 300);
            var sensors = Seven();
            foreach (var frame in new[] { frames[0], frames[frames.Count / 2], frames[frames.Count - 1] })
            {
                Assert.AreEqual(7, frame.SensorCount, $"frame {frame.Sequence}");
                for (int i = 0; i < 7; i++)
                {
                    var sensor = frame.GetSensor(i);
                    Assert.AreEqual(sensors[i].Segment, sensor.Segment, $"frame {frame.Sequence} sensor {i}");
                    Assert.AreEqual((uint)sensors[i].NodeId, sensor.NodeId, $"frame {frame.Sequence} sensor {i}");
                }
                Assert.AreEqual(1, frame.IndexOf(MocapSegment.Chest));
            }
            var end = frames[frames.Count - 1];
            Assert.IsTrue(end.IsCalibrated);
            Assert.IsTrue(end.TryGetSensor(MocapSegment.Chest, out var chest));
            Assert.IsTrue(chest.IsValid && chest.IsCalibrated, chest.Flags.ToString());
            Assert.AreNotEqual(MocapSensorState.Absent, chest.State);
            int chestFresh = frames.Count(f => f.IsFresh(1) && f.GetSensor(1).State == MocapSensorState.Fresh);
            Assert.Greater(chestFresh, frames.Count / 2, "the chest sends like the others");
            Assert.AreEqual(0x7Fu, run.Stats.SensorsSeenMask, "all seven sensors were seen");
            Assert.IsTrue(run.TPose.TryGetSensor(MocapSegment.Chest, out var quality));
            Assert.IsTrue(quality.IsOk && !quality.IsLeftOut);
            Assert.Greater(quality.Samples, 50u);
            var summaries = CalibrationQuality.Summarize(run.TPose);
            Assert.AreEqual(MocapSegment.Chest, summaries[1].Segment);
            Assert.AreEqual("chest", CalibrationQuality.SensorName(summaries[1].Segment));
        }

        [Test]
        public void SevenSensorFramesEqualMocapctlsAndRoundTripAsARecording()
        {
            var capture = TestPaths.Synth("walk", seconds: 4, seed: 7, sensors: SevenSensorList);
            var run = Replay.Run(capture, sensors: Seven());
            var csv = Path.Combine(_dir, "mocapctl-seven.csv");
            // mocapctl with the same sensor list in the same order, the same prelude windows.
            TestPaths.RunMocapctl("replay", capture.CapturePath, "--csv", csv, "--sensors",
                                  string.Join(",", Seven().Select(x => $"{SegmentTable.Name(x.Segment)}={x.NodeId}")));
            var expected = Capture.FrameRecording.Load(csv);
            Assert.AreEqual(expected.Length, run.Frames.Count);
            for (int i = 0; i < expected.Length; i += 7)
            {
                Assert.AreEqual(7, expected[i].SensorCount, $"frame {i}: mocapctl's header names seven sensors");
                Assert.AreEqual(expected[i].Flags, run.Frames[i].Flags, $"frame {i}");
                for (int s = 0; s < 7; s++)
                {
                    MocapSensorFrame e = expected[i].GetSensor(s), a = run.Frames[i].GetSensor(s);
                    Assert.AreEqual(e.Segment, a.Segment, $"frame {i} sensor {s}");
                    Assert.AreEqual(e.Flags, a.Flags, $"frame {i} sensor {s}");
                    Assert.AreEqual(e.BoneOrientation.X, a.BoneOrientation.X, 2e-6, $"frame {i} sensor {s}");
                    Assert.AreEqual(e.BoneAcceleration.Y, a.BoneAcceleration.Y, 2e-4, $"frame {i} sensor {s}");
                }
            }

            var path = Path.Combine(_dir, "seven.csv");
            Capture.FrameRecording.Save(path, run.Frames.ToArray());
            StringAssert.Contains(",chest_qw,chest_qx,chest_qy,chest_qz,chest_ax,chest_ay,chest_az,chest_flags,left_wrist_qw",
                File.ReadAllText(path), "the chest's columns, second, as in the session");
            var loaded = Capture.FrameRecording.Load(path);
            var last = loaded[loaded.Length - 1];
            Assert.AreEqual(7, last.SensorCount);
            Assert.AreEqual(1, last.IndexOf(MocapSegment.Chest));
            Assert.AreEqual(run.Frames[run.Frames.Count - 1].GetSensor(1).BoneOrientation.Z, last.GetSensor(1).BoneOrientation.Z, 1e-6);

            // Frames of two sensor sets do not make one recording.
            var mixed = new[] { run.Frames[0], Replay.Run(TestPaths.Synth("walk", seconds: 3)).Frames[0] };
            var e2 = Assert.Throws<MocapException>(() => Capture.FrameRecording.Save(Path.Combine(_dir, "mixed.csv"), mixed));
            StringAssert.Contains("frame 1: 6 sensors, the first frame has 7", e2.Message);
        }

        [Test]
        public void ASevenSensorCalibrationRoundTripsThroughItsFile()
        {
            var capture = TestPaths.Synth("walk", seconds: 4, seed: 7, sensors: SevenSensorList);
            var calibration = Replay.Run(capture, sensors: Seven()).Calibration;
            Assert.AreEqual(7, calibration.SensorCount);
            Assert.IsTrue(calibration.IsComplete, "every one of the seven is calibrated");
            CollectionAssert.AreEqual(Seven().Select(s => s.Segment),
                Enumerable.Range(0, 7).Select(calibration.GetSegment), "entries in the session's order");

            var path = Path.Combine(_dir, "seven.calibration");
            calibration.Save(path);
            var text = File.ReadAllLines(path);
            StringAssert.StartsWith("mocap-calibration 2", text[0]);
            CollectionAssert.Contains(text, "sensors pelvis chest left_wrist right_wrist left_shin right_shin head");
            var loaded = CalibrationData.Load(path);
            var a = new ReadOnlySpan<byte>(&calibration, sizeof(CalibrationData));
            var b = new ReadOnlySpan<byte>(&loaded, sizeof(CalibrationData));
            Assert.IsTrue(a.SequenceEqual(b), "every entry, segment and mask comes back exactly");

            // Loaded into a session listing the seven in another order: each sensor gets its own
            // segment's entry, so the replay is calibrated from its first frame.
            var reordered = SixAndChest(chestOptional: false);
            var run = Replay.Run(capture, loaded, sensors: reordered);
            Assert.IsTrue(run.Frames[0].IsCalibrated);
            var chestNow = run.Calibration;
            int chestEntry = chestNow.EntryOf(MocapSegment.Chest);
            int chestBefore = loaded.EntryOf(MocapSegment.Chest);
            Assert.AreEqual(6, chestEntry, "the session's order");
            Assert.AreEqual(1, chestBefore, "the file's order");
            var m1 = chestNow.GetSensorToBone(chestEntry);
            var m0 = loaded.GetSensorToBone(chestBefore);
            for (int k = 0; k < 9; k++) Assert.AreEqual(m0[k / 3, k % 3], m1[k / 3, k % 3], $"chest sensor_to_bone[{k}]");
        }

        [Test]
        public void ACalibrationOfTheSixLeavesTheChestOfASevenSensorSessionUncalibrated()
        {
            var capture = TestPaths.Synth("walk", seconds: 4, seed: 7, sensors: SevenSensorList);
            var six = Replay.Run(capture).Calibration;
            Assert.AreEqual(6, six.SensorCount);
            Assert.IsTrue(six.IsComplete);
            Assert.AreEqual(-1, six.IndexOf(MocapSegment.Chest));

            var run = Replay.Run(capture, six, sensors: Seven());
            var calibration = run.Calibration;
            Assert.AreEqual(7, calibration.SensorCount);
            Assert.IsFalse(calibration.IsValid(MocapSegment.Chest), "no entry for the chest: it stays uncalibrated");
            foreach (var sensor in SensorSets.DefaultSix())
                Assert.IsTrue(calibration.IsValid(sensor.Segment), $"{sensor.Segment} took its entry by segment");
            var last = run.Frames[run.Frames.Count - 1];
            Assert.IsTrue(last.TryGetSensor(MocapSegment.Chest, out var chest));
            Assert.IsFalse(chest.IsCalibrated, "the chest's bone is an uncalibrated preview");
            Assert.IsTrue(chest.IsValid, "but it does send");
            Assert.IsTrue(last.TryGetSensor(MocapSegment.LeftWrist, out var wrist) && wrist.IsCalibrated);
            Assert.IsFalse(last.IsCalibrated, "a required chest without calibration keeps the frame uncalibrated");

            var optionalChest = Replay.Run(capture, six, sensors: Seven(chestOptional: true));
            Assert.IsTrue(optionalChest.Frames[optionalChest.Frames.Count - 1].IsCalibrated,
                "with the chest optional the six's calibration is enough");
        }

        [Test]
        public void SensorsTheModelCanDoWithoutBecomeOptional()
        {
            using var model = MocapModel.Open(TestPaths.ModelPath);
            Assert.AreEqual(6, model.Info.Sensors.Count, "the shipped model reads the six");
            Assert.That(model.Info.Sensors.All(s => s.Required), "contract 1: every sensor required");
            CollectionAssert.AreEqual(SensorSets.DefaultSix().Select(s => s.Segment), model.Info.Sensors.Select(s => s.Segment));

            var config = SessionConfig.Replay("x.cap");
            config.Sensors.Clear();
            config.Sensors.AddRange(Seven());
            config.MarkModelOptionalSensors(model.Info);
            CollectionAssert.AreEqual(new[] { false, true, false, false, false, false, false },
                config.Sensors.Select(s => s.Optional), "the chest, which the model does not read, may be missing");

            // The same metadata with the chest as an optional input (contract 2).
            NativeModelInfo native;
            NativeMethods.Check(NativeSolverMethods.mocap_model_get_info(model.Handle, &native));
            native.SensorSegments[6] = (int)MocapSegment.Chest;
            native.SensorCount = 7;
            native.SensorRequiredMask = 0x1Fu; // head (input 5) and chest (input 6) optional
            var info = new ModelInfo(in native);
            Assert.AreEqual(6, info.IndexOf(MocapSegment.Chest));
            Assert.IsFalse(info.Sensors[6].Required);
            config.Sensors.Clear();
            config.Sensors.AddRange(Seven());
            config.MarkModelOptionalSensors(info);
            CollectionAssert.AreEqual(new[] { false, true, false, false, false, false, true },
                config.Sensors.Select(s => s.Optional));
        }
    }
}
