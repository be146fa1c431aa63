// How the C API grows without breaking bindings: major.minor versions (a binding accepts any
// minor at or above its own within its major) and counters read by key instead of new struct
// fields, checked against the real engine and its header.

using System;
using System.Collections.Generic;
using System.IO;
using System.Text.RegularExpressions;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class ApiGrowthTests
    {
        [TestCase(5, 1, 5, 1, true)]
        [TestCase(5, 1, 5, 4, true)]
        [TestCase(5, 1, 5, 0, false)]
        [TestCase(5, 1, 4, 9, false)]
        [TestCase(5, 1, 6, 1, false)]
        [TestCase(5, 0, 5, 0, true)]
        public void ABindingAcceptsItsMajorAtItsMinorOrNewer(int bMajor, int bMinor, int lMajor, int lMinor, bool accepted)
        {
            var bindings = new ApiVersion(bMajor, bMinor);
            var library = new ApiVersion(lMajor, lMinor);
            Assert.AreEqual(accepted, ApiVersion.Accepts(bindings, library));
            var refusal = ApiVersion.Refusal(bindings, library, "mocap_imu");
            Assert.AreEqual(accepted, refusal == null, refusal);
            if (refusal != null)
            {
                StringAssert.Contains($"has API version {library}", refusal);
                StringAssert.Contains(lMajor != bMajor ? "structs differ" : "lacks functions", refusal);
            }
        }

        [Test]
        public void TheLoadedEngineIsTheVersionTheseBindingsWereWrittenFor()
        {
            TestPaths.RequireEngine();
            Assert.AreEqual(MocapEngine.BindingsApi, MocapEngine.LibraryApi);
            Assert.AreEqual(MocapEngine.ApiVersion, MocapEngine.LibraryApi.Major);
            Assert.GreaterOrEqual(MocapEngine.LibraryApi.Major, 6, "sensor sets came with 6.0");
            Assert.DoesNotThrow(MocapEngine.EnsureCompatible);
        }

        /// <summary>Every key of a C enum "PREFIX_NAME = value," in the engine's public header.</summary>
        static Dictionary<string, int> HeaderKeys(string prefix)
        {
            var header = Path.Combine(TestPaths.RequireRepoRoot(), "Packages", "com.mocap.imu", "Native~", "include", "mocap_imu.h");
            var keys = new Dictionary<string, int>();
            foreach (Match m in Regex.Matches(File.ReadAllText(header), $@"\b{prefix}([A-Z_]+)\s*=\s*(\d+)"))
                if (m.Groups[1].Value != "COUNTER_COUNT") keys[m.Groups[1].Value] = int.Parse(m.Groups[2].Value);
            return keys;
        }

        // "FramesNonFinite" and FRAMES_NONFINITE are one key: compare without underscores or case.
        static string Key(string name) => name.Replace("_", "").ToUpperInvariant();

        static void AssertMirrors<TEnum>(string prefix, int minimum = 11) where TEnum : struct, Enum
        {
            var header = new Dictionary<string, int>();
            foreach (var pair in HeaderKeys(prefix)) header[Key(pair.Key)] = pair.Value;
            var names = Enum.GetNames(typeof(TEnum));
            Assert.GreaterOrEqual(header.Count, minimum, $"the header's {prefix}* keys were found");
            Assert.AreEqual(header.Count, names.Length, $"{typeof(TEnum).Name} has as many keys as the header");
            foreach (var name in names)
            {
                string c = Key(name);
                Assert.IsTrue(header.ContainsKey(c), $"{typeof(TEnum).Name}.{name}: no {prefix}{c} in the header");
                Assert.AreEqual(header[c], Convert.ToInt32(Enum.Parse(typeof(TEnum), name)), $"{typeof(TEnum).Name}.{name}");
            }
        }

        [Test]
        public void CounterKeysMirrorTheHeader()
        {
            AssertMirrors<SessionCounter>("MOCAP_SESSION_");
            AssertMirrors<SolverCounter>("MOCAP_SOLVER_");
        }

        [Test]
        public void SegmentEnumEqualsTheEnginesSegmentTable()
        {
            // Segments are added as table rows (a minor version): MocapSegment must list exactly
            // the engine's rows, each under its name in PascalCase, and the header's enum agrees.
            TestPaths.RequireEngine();
            var members = (MocapSegment[])Enum.GetValues(typeof(MocapSegment));
            Assert.AreEqual(SegmentTable.Count, members.Length, "MocapSegment has a member per row of the engine's table");
            for (int s = 0; s < SegmentTable.Count; s++)
            {
                var segment = (MocapSegment)s;
                Assert.IsTrue(Enum.IsDefined(typeof(MocapSegment), segment), $"no MocapSegment member for row {s} ({SegmentTable.Name(segment)})");
                Assert.AreEqual(SegmentTable.Name(segment), SegmentTable.SnakeName(segment), $"MocapSegment.{segment}");
                Assert.IsTrue(SegmentTable.TryFind(SegmentTable.Name(segment), out var found));
                Assert.AreEqual(segment, found);
                Assert.IsTrue(SegmentTable.TryParseSnakeName(SegmentTable.Name(segment), out var parsed));
                Assert.AreEqual(segment, parsed);
            }
            AssertMirrors<MocapSegment>("MOCAP_SEGMENT_", minimum: 6);
            Assert.IsFalse(SegmentTable.TryFind("tail", out _));
            Assert.IsFalse(SegmentTable.TryFind("Pelvis", out _), "names are exact, lower case");
            Assert.Throws<ArgumentOutOfRangeException>(() => SegmentTable.Name((MocapSegment)SegmentTable.Count));
        }

        [Test]
        public void CountersByKeyEqualTheStatsAfterAReplay()
        {
            TestPaths.RequireEngine();
            var capture = TestPaths.Synth("walk", seconds: 3, seed: 11);
            using var model = MocapModel.Open(TestPaths.ModelPath);
            using var session = SolverReplay.OpenCalibratedReplay(capture, model.Info.FrameRate);
            using var solver = MocapSolver.Open(model);
            solver.AddCharacter(session);
            solver.Start();
            session.Start();
            var poses = SolverReplay.DrainAll(solver)[0];

            var s = session.GetStats();
            var expectedSession = new Dictionary<SessionCounter, ulong>
            {
                [SessionCounter.BytesReceived] = s.BytesReceived, [SessionCounter.FramesDecoded] = s.FramesDecoded,
                [SessionCounter.CrcFailures] = s.CrcFailures, [SessionCounter.BytesSkipped] = s.BytesSkipped,
                [SessionCounter.UnknownPackets] = s.UnknownPackets, [SessionCounter.SamplesDecoded] = s.SamplesDecoded,
                [SessionCounter.SamplesRejected] = s.SamplesRejected, [SessionCounter.FramesEmitted] = s.FramesEmitted,
                [SessionCounter.FramesDropped] = s.FramesDropped, [SessionCounter.BytesDropped] = s.BytesDropped,
                [SessionCounter.Reconnects] = s.Reconnects, [SessionCounter.CaptureBytesWritten] = s.CaptureBytesWritten,
                [SessionCounter.ReplayChunksSkipped] = s.ReplayChunksSkipped,
                [SessionCounter.ReplayTailDamaged] = s.ReplayTailDamaged ? 1UL : 0UL, [SessionCounter.SensorsSeenMask] = s.SensorsSeenMask,
            };
            Assert.AreEqual(Enum.GetValues(typeof(SessionCounter)).Length, expectedSession.Count);
            foreach (var pair in expectedSession)
                Assert.AreEqual(pair.Value, session.GetCounter(pair.Key), pair.Key.ToString());
            Assert.Greater(session.GetCounter(SessionCounter.FramesEmitted), 100UL);

            var t = solver.GetStats();
            var expectedSolver = new Dictionary<SolverCounter, ulong>
            {
                [SolverCounter.Ticks] = t.Ticks, [SolverCounter.BatchedCalls] = t.BatchedCalls,
                [SolverCounter.MaxBatch] = t.MaxBatch, [SolverCounter.FramesSolved] = t.FramesSolved,
                [SolverCounter.FramesUncalibrated] = t.FramesUncalibrated, [SolverCounter.FramesNonFinite] = t.FramesNonFinite,
                [SolverCounter.OutputsNonFinite] = t.OutputsNonFinite, [SolverCounter.PosesDropped] = t.PosesDropped,
                [SolverCounter.RunFailures] = t.RunFailures, [SolverCounter.SolveNsTotal] = t.SolveNsTotal,
                [SolverCounter.SolveNsMax] = t.SolveNsMax, [SolverCounter.RunNsTotal] = t.RunNsTotal,
            };
            Assert.AreEqual(Enum.GetValues(typeof(SolverCounter)).Length, expectedSolver.Count);
            foreach (var pair in expectedSolver)
                Assert.AreEqual(pair.Value, solver.GetCounter(pair.Key), pair.Key.ToString());
            Assert.AreEqual((ulong)poses.Count, solver.GetCounter(SolverCounter.FramesSolved, 0));

            var unknown = Assert.Throws<MocapException>(() => session.GetCounter((SessionCounter)999));
            Assert.AreEqual(MocapStatus.Unsupported, unknown.Status);
            StringAssert.Contains("session counter 999 is not known", unknown.Message);
            unknown = Assert.Throws<MocapException>(() => solver.GetCounter((SolverCounter)999));
            StringAssert.Contains("solver counter 999 is not known", unknown.Message);
        }
    }
}
