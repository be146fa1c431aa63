// HumanoidTake and TakeFiles: the curve data an editor take turns into Humanoid and Generic clips.
// Fails on keys off the model's frame clock (also after an hour), wrong curve names, quaternion sign
// flips between keys, any lost value when no reduction is asked for, a reduction that exceeds its
// tolerance, and allocation per sample.

using System;
using System.Collections.Generic;
using System.IO;
using System.Linq;
using Mocap.Imu.Maths;
using Mocap.Imu.Recording;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    public sealed class HumanoidTakeTests
    {
        // A few of HumanTrait.MuscleName's entries: body muscles keep their names in a clip, finger
        // muscles do not.
        static readonly string[] Muscles =
        {
            "Spine Front-Back", "Left Upper Leg In-Out", "Right Hand Down-Up",
            "Left Thumb 1 Stretched", "Left Thumb Spread", "Right Little 3 Stretched", "Right Index Spread",
        };

        static readonly string[] ClipMuscles =
        {
            "Spine Front-Back", "Left Upper Leg In-Out", "Right Hand Down-Up",
            "LeftHand.Thumb.1 Stretched", "LeftHand.Thumb.Spread", "RightHand.Little.3 Stretched", "RightHand.Index.Spread",
        };

        static readonly string[] Bones = { "Armature/Hips", "Armature/Hips/Spine", "Armature/Hips/Spine/Chest" };

        sealed class Sample
        {
            public ulong Sequence;
            public Vec3 Body;
            public Quat BodyRotation;
            public float[] Muscles;
            public Vec3 Hips;
            public Quat[] Bones;
        }

        /// <summary>Smooth motion: turning on the spot, swaying muscles, bones bending about different axes.</summary>
        static Sample Smooth(ulong sequence, float rate)
        {
            float t = sequence / rate;
            var sample = new Sample
            {
                Sequence = sequence,
                Body = new Vec3(0.3f * MathF.Sin(t), 1f + 0.05f * MathF.Sin(3 * t), 0.2f * t),
                BodyRotation = Quat.AxisAngle(Vec3.UnitY, 0.8f * t),
                Muscles = new float[Muscles.Length],
                Hips = new Vec3(0.1f * MathF.Sin(t), 0.95f, 0.2f * t),
                Bones = new Quat[Bones.Length],
            };
            for (int m = 0; m < Muscles.Length; m++) sample.Muscles[m] = 0.6f * MathF.Sin(0.7f * t * (m + 1));
            for (int b = 0; b < Bones.Length; b++)
                sample.Bones[b] = Quat.AxisAngle(new Vec3(b == 0 ? 1 : 0, b == 1 ? 1 : 0, b == 2 ? 1 : 0), 1.2f * MathF.Sin(0.9f * t + b));
            return sample;
        }

        static bool Add(HumanoidTake take, Sample s) =>
            take.Add(s.Sequence, s.Body, s.BodyRotation, s.Muscles, s.Hips, s.Bones);

        static TakeCurve Find(List<TakeCurve> curves, string path, string property) =>
            curves.Single(c => c.Path == path && c.Property == property);

        /// <summary>Linear interpolation of a curve's keys at <paramref name="time"/>, as Unity evaluates linear tangents.</summary>
        static float Evaluate(TakeCurve curve, float time)
        {
            int hi = Array.BinarySearch(curve.Times, time);
            if (hi >= 0) return curve.Values[hi];
            hi = ~hi;
            if (hi == 0) return curve.Values[0];
            if (hi == curve.Times.Length) return curve.Values[hi - 1];
            int lo = hi - 1;
            float u = (time - curve.Times[lo]) / (curve.Times[hi] - curve.Times[lo]);
            return curve.Values[lo] + (curve.Values[hi] - curve.Values[lo]) * u;
        }

        static Quat EvaluateRotation(List<TakeCurve> curves, string path, string prefix, float time) =>
            new Quat(Evaluate(Find(curves, path, prefix + ".x"), time), Evaluate(Find(curves, path, prefix + ".y"), time),
                     Evaluate(Find(curves, path, prefix + ".z"), time), Evaluate(Find(curves, path, prefix + ".w"), time)).Normalized;

        // ---- names -------------------------------------------------------------------------

        [Test]
        public void HumanoidCurvesAreRootMotionThenMusclesAsUnityClipsNameThem()
        {
            var take = new HumanoidTake(60, Muscles, Bones);
            for (ulong i = 0; i < 3; i++) Add(take, Smooth(i, 60));
            var curves = take.HumanoidCurves();
            Assert.That(curves.Select(c => c.Property),
                        Is.EqualTo(new[] { "RootT.x", "RootT.y", "RootT.z", "RootQ.x", "RootQ.y", "RootQ.z", "RootQ.w" }.Concat(ClipMuscles)));
            Assert.That(curves.All(c => c.Path == "" && c.Target == CurveTarget.Animator), Is.True);
        }

        [Test]
        public void GenericCurvesAreHipsPositionAndEveryBonesLocalRotationByPath()
        {
            var take = new HumanoidTake(60, Muscles, Bones);
            for (ulong i = 0; i < 3; i++) Add(take, Smooth(i, 60));
            var curves = take.GenericCurves();
            var expected = new List<(string, string)>
            {
                ("Armature/Hips", "m_LocalPosition.x"), ("Armature/Hips", "m_LocalPosition.y"), ("Armature/Hips", "m_LocalPosition.z"),
            };
            foreach (var bone in Bones)
                foreach (var axis in "xyzw")
                    expected.Add((bone, "m_LocalRotation." + axis));
            Assert.That(curves.Select(c => (c.Path, c.Property)), Is.EqualTo(expected));
            Assert.That(curves.All(c => c.Target == CurveTarget.Transform), Is.True);
            Assert.That(new HumanoidTake(60, Muscles, null).BoneCount, Is.Zero);
        }

        [TestCase("Left Thumb 1 Stretched", "LeftHand.Thumb.1 Stretched")]
        [TestCase("Left Thumb Spread", "LeftHand.Thumb.Spread")]
        [TestCase("Right Middle 2 Stretched", "RightHand.Middle.2 Stretched")]
        [TestCase("Right Ring Spread", "RightHand.Ring.Spread")]
        [TestCase("Left Hand Down-Up", "Left Hand Down-Up")]
        [TestCase("Left Arm Twist In-Out", "Left Arm Twist In-Out")]
        [TestCase("Jaw Close", "Jaw Close")]
        [TestCase("Neck Nod Down-Up", "Neck Nod Down-Up")]
        public void MusclePropertyMatchesHumanoidClipNaming(string humanTrait, string clipProperty)
        {
            Assert.That(HumanoidCurveNames.MuscleProperty(humanTrait), Is.EqualTo(clipProperty));
        }

        // ---- timing ------------------------------------------------------------------------

        [Test]
        public void KeysSitOnTheModelFrameClockWithoutDriftOverAnHour()
        {
            const float rate = 60;
            const int frames = 3600 * 60 + 1;
            var take = new HumanoidTake(rate, new[] { "Spine Front-Back" }, new[] { "Hips" }, capacityFrames: frames);
            var muscle = new float[1];
            var bone = new[] { Quat.Identity };
            const ulong firstSequence = 5000; // the engine had run before the take began
            for (int i = 0; i < frames; i++)
                take.Add(firstSequence + (ulong)i, new Vec3(0, 1, 0), Quat.Identity, muscle, new Vec3(0, 1, 0), bone);
            var times = take.HumanoidCurves()[0].Times;
            Assert.That(times.Length, Is.EqualTo(frames));
            Assert.That(times[0], Is.EqualTo(0f));
            Assert.That(times[frames - 1], Is.EqualTo(3600f), "an hour of frames ends at exactly 3600 s");
            for (int i = 0; i < frames; i++)
                if (times[i] != (float)(i / 60.0)) Assert.Fail($"key {i} at {times[i]:R} s, not {(float)(i / 60.0):R}");
            Assert.That(take.GenericCurves()[0].Times, Is.EqualTo(times));
            Assert.That(take.DurationSeconds, Is.EqualTo(3600.0));

            // Adding up 1/60 s per frame, as a per-frame delta would, is measurably off by then.
            float accumulated = 0;
            for (int i = 1; i < frames; i++) accumulated += 1f / 60f;
            Assert.That(Math.Abs(accumulated - 3600f), Is.GreaterThan(0.01f));
        }

        [Test]
        public void MissedPosesLeaveAGapNotAShift()
        {
            var take = new HumanoidTake(50, Muscles, Bones);
            foreach (ulong s in new ulong[] { 10, 11, 14, 15 }) Add(take, Smooth(s, 50));
            Assert.That(take.HumanoidCurves()[0].Times, Is.EqualTo(new[] { 0f, 0.02f, (float)(4 / 50.0), (float)(5 / 50.0) }));
            Assert.That(take.MissingFrames, Is.EqualTo(2));
        }

        [Test]
        public void RepeatedAndLatePosesAreIgnoredAndARestartContinuesTheClock()
        {
            var take = new HumanoidTake(60, Muscles, Bones);
            for (ulong s = 0; s < 10; s++) Assert.That(Add(take, Smooth(s, 60)), Is.True);
            Assert.That(Add(take, Smooth(9, 60)), Is.False, "the same pose twice");
            Assert.That(Add(take, Smooth(7, 60)), Is.False, "a late pose");
            Assert.That(take.Count, Is.EqualTo(10));
            // Loop playback restarts the engine: its poses number from 0 again, far behind the last.
            var restart = new HumanoidTake(60, Muscles, Bones);
            for (ulong s = 500; s < 600; s++) Add(restart, Smooth(s, 60));
            for (ulong s = 0; s < 5; s++) Assert.That(Add(restart, Smooth(s, 60)), Is.True);
            var times = restart.HumanoidCurves()[0].Times;
            Assert.That(times.Length, Is.EqualTo(105));
            for (int i = 0; i < times.Length; i++) Assert.That(times[i], Is.EqualTo((float)(i / 60.0)), $"key {i}");
            Assert.That(restart.MissingFrames, Is.Zero);
        }

        // ---- values ------------------------------------------------------------------------

        [Test]
        public void EveryValueIsKeptExactlyWithoutReduction()
        {
            var random = new Random(7);
            float R() => (float)(random.NextDouble() * 2 - 1);
            var take = new HumanoidTake(60, Muscles, Bones, capacityFrames: 16);
            var samples = new List<Sample>();
            for (ulong s = 0; s < 300; s++)
            {
                // Noisy values that no curve fit could reproduce; quaternions kept on one hemisphere.
                var sample = new Sample
                {
                    Sequence = s, Body = new Vec3(R(), R(), R()), BodyRotation = new Quat(R() * 0.3f, R() * 0.3f, R() * 0.3f, 1).Normalized,
                    Muscles = Enumerable.Range(0, Muscles.Length).Select(_ => R()).ToArray(), Hips = new Vec3(R(), R(), R()),
                    Bones = Enumerable.Range(0, Bones.Length).Select(_ => new Quat(R() * 0.3f, R() * 0.3f, R() * 0.3f, 1).Normalized).ToArray(),
                };
                samples.Add(sample);
                Add(take, sample);
            }
            Assert.That(take.Capacity, Is.GreaterThanOrEqualTo(300), "storage grew past the initial capacity");
            var humanoid = take.HumanoidCurves();
            var generic = take.GenericCurves();
            Assert.That(humanoid.Concat(generic).All(c => c.Times.Length == 300 && c.Values.Length == 300), Is.True);
            for (int i = 0; i < samples.Count; i++)
            {
                var s = samples[i];
                Assert.That(humanoid[0].Values[i], Is.EqualTo(s.Body.X));
                Assert.That(humanoid[2].Values[i], Is.EqualTo(s.Body.Z));
                Assert.That(humanoid[3].Values[i], Is.EqualTo(s.BodyRotation.X));
                Assert.That(humanoid[6].Values[i], Is.EqualTo(s.BodyRotation.W));
                for (int m = 0; m < Muscles.Length; m++) Assert.That(humanoid[7 + m].Values[i], Is.EqualTo(s.Muscles[m]));
                Assert.That(generic[1].Values[i], Is.EqualTo(s.Hips.Y));
                for (int b = 0; b < Bones.Length; b++)
                {
                    Assert.That(generic[3 + 4 * b].Values[i], Is.EqualTo(s.Bones[b].X));
                    Assert.That(generic[3 + 4 * b + 3].Values[i], Is.EqualTo(s.Bones[b].W));
                }
            }
        }

        [Test]
        public void QuaternionSignsStayContinuousFromKeyToKey()
        {
            // HumanPoseHandler and Transform.localRotation may hand back q or -q for one rotation;
            // feed every other frame negated and a full turn (which crosses w = 0).
            var take = new HumanoidTake(60, Muscles, Bones);
            var originals = new List<Sample>();
            for (ulong s = 0; s < 240; s++)
            {
                var sample = Smooth(s, 60);
                sample.BodyRotation = Quat.AxisAngle(Vec3.UnitY, 2 * MathF.PI * s / 120f);
                originals.Add(sample);
                var fed = Smooth(s, 60);
                fed.BodyRotation = sample.BodyRotation;
                if (s % 2 == 1)
                {
                    var q = fed.BodyRotation;
                    fed.BodyRotation = new Quat(-q.X, -q.Y, -q.Z, -q.W);
                    fed.Bones = fed.Bones.Select(b => new Quat(-b.X, -b.Y, -b.Z, -b.W)).ToArray();
                }
                Add(take, fed);
            }
            var humanoid = take.HumanoidCurves();
            var generic = take.GenericCurves();
            void CheckStream(List<TakeCurve> curves, string path, string prefix, Func<Sample, Quat> truth)
            {
                var x = Find(curves, path, prefix + ".x").Values; var y = Find(curves, path, prefix + ".y").Values;
                var z = Find(curves, path, prefix + ".z").Values; var w = Find(curves, path, prefix + ".w").Values;
                for (int i = 0; i < x.Length; i++)
                {
                    var key = new Quat(x[i], y[i], z[i], w[i]);
                    Assert.That(Quat.Angle(key, truth(originals[i])), Is.LessThan(1e-5f), $"{path} {prefix} key {i} is another rotation");
                    if (i > 0)
                        Assert.That(Quat.Dot(key, new Quat(x[i - 1], y[i - 1], z[i - 1], w[i - 1])), Is.GreaterThan(0f),
                                    $"{path} {prefix} flips sign at key {i}");
                }
            }
            CheckStream(humanoid, "", "RootQ", s => s.BodyRotation);
            for (int b = 0; b < Bones.Length; b++)
            {
                int bone = b;
                CheckStream(generic, Bones[b], "m_LocalRotation", s => s.Bones[bone]);
            }
        }

        [Test]
        public void ReductionKeepsEveryFrameWithinItsTolerances()
        {
            const float rate = 60;
            var take = new HumanoidTake(rate, Muscles, Bones);
            var samples = new List<Sample>();
            for (ulong s = 0; s < 1200; s++)
            {
                samples.Add(Smooth(s, rate));
                Add(take, samples[^1]);
            }
            var reduction = new KeyReduction(angleDegrees: 0.5f, muscle: 0.01f, position: 0.002f);
            var humanoid = take.HumanoidCurves(reduction);
            var generic = take.GenericCurves(reduction);
            int keys = humanoid.Concat(generic).Sum(c => c.Times.Length);
            int full = (humanoid.Count + generic.Count) * samples.Count;
            Assert.That(keys, Is.LessThan(full / 4), $"smooth motion should reduce well ({keys} of {full} keys kept)");

            const float angleSlack = 1e-4f; // float rounding of the normalised interpolation
            float worstAngle = 0, worstMuscle = 0, worstPosition = 0;
            for (int i = 0; i < samples.Count; i++)
            {
                var s = samples[i];
                float t = take.KeyTime(i);
                worstAngle = Math.Max(worstAngle, Quat.Angle(EvaluateRotation(humanoid, "", "RootQ", t), s.BodyRotation));
                for (int b = 0; b < Bones.Length; b++)
                    worstAngle = Math.Max(worstAngle, Quat.Angle(EvaluateRotation(generic, Bones[b], "m_LocalRotation", t), s.Bones[b]));
                for (int m = 0; m < Muscles.Length; m++)
                    worstMuscle = Math.Max(worstMuscle, Math.Abs(Evaluate(humanoid[7 + m], t) - s.Muscles[m]));
                var body = new Vec3(Evaluate(humanoid[0], t), Evaluate(humanoid[1], t), Evaluate(humanoid[2], t));
                worstPosition = Math.Max(worstPosition, (body - s.Body).Length);
                var hips = new Vec3(Evaluate(generic[0], t), Evaluate(generic[1], t), Evaluate(generic[2], t));
                worstPosition = Math.Max(worstPosition, (hips - s.Hips).Length);
            }
            Assert.That(worstAngle, Is.LessThanOrEqualTo(0.5f * MathF.PI / 180f + angleSlack));
            Assert.That(worstMuscle, Is.LessThanOrEqualTo(0.01f + 1e-6f));
            Assert.That(worstPosition, Is.LessThanOrEqualTo(0.002f + 1e-6f));
            // The reduction used its room: a far smaller tolerance keeps more keys.
            int tighter = take.HumanoidCurves(new KeyReduction(0.05f, 0.001f, 0.0002f)).Sum(c => c.Times.Length);
            Assert.That(tighter, Is.GreaterThan(humanoid.Sum(c => c.Times.Length)));
        }

        [Test]
        public void LinearTangentsMakeUnitysHermiteCurveTheStraightLineBetweenKeys()
        {
            var take = new HumanoidTake(30, Muscles, Bones);
            for (ulong s = 0; s < 300; s++) Add(take, Smooth(s, 30));
            foreach (var curve in take.HumanoidCurves(new KeyReduction(1f, 0.02f, 0.005f)).Take(9))
            {
                Assert.That(curve.Times.Length, Is.GreaterThan(2), curve.Property);
                for (int k = 0; k + 1 < curve.Times.Length; k++)
                {
                    curve.LinearTangents(k, out _, out float leave);
                    curve.LinearTangents(k + 1, out float arrive, out _);
                    float t0 = curve.Times[k], t1 = curve.Times[k + 1], p0 = curve.Values[k], p1 = curve.Values[k + 1];
                    foreach (float u in new[] { 0.25f, 0.5f, 0.8f })
                    {
                        // Cubic Hermite between two keys, as an unweighted AnimationCurve evaluates it.
                        float dt = t1 - t0, u2 = u * u, u3 = u2 * u;
                        float hermite = (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * dt * leave +
                                        (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * dt * arrive;
                        Assert.That(hermite, Is.EqualTo(p0 + (p1 - p0) * u).Within(1e-5f), $"{curve.Property} between keys {k} and {k + 1}");
                    }
                }
            }
            var single = new HumanoidTake(30, Muscles, Bones);
            Add(single, Smooth(0, 30));
            single.HumanoidCurves()[0].LinearTangents(0, out float a, out float b);
            Assert.That((a, b), Is.EqualTo((0f, 0f)));
        }

        [Test]
        public void QuaternionCurvesShareKeyTimesSoTheyStayRotations()
        {
            var take = new HumanoidTake(60, Muscles, Bones);
            for (ulong s = 0; s < 600; s++) Add(take, Smooth(s, 60));
            var generic = take.GenericCurves(new KeyReduction(1f, 0.02f, 0.01f));
            foreach (var bone in Bones)
            {
                var x = Find(generic, bone, "m_LocalRotation.x").Times;
                foreach (var axis in "yzw") Assert.That(Find(generic, bone, "m_LocalRotation." + axis).Times, Is.EqualTo(x));
            }
        }

        [Test]
        public void AddAllocatesNothingWithinCapacity()
        {
            var take = new HumanoidTake(60, Muscles, Bones, capacityFrames: 2000);
            var sample = Smooth(0, 60);
            var muscles = sample.Muscles;
            var bones = sample.Bones;
            take.Add(0, sample.Body, sample.BodyRotation, muscles, sample.Hips, bones); // JIT
            long before = GC.GetAllocatedBytesForCurrentThread();
            for (ulong s = 1; s < 1500; s++)
            {
                muscles[0] = s * 1e-4f;
                take.Add(s, sample.Body, sample.BodyRotation, muscles, sample.Hips, bones);
            }
            long allocated = GC.GetAllocatedBytesForCurrentThread() - before;
            Assert.That(take.Count, Is.EqualTo(1500));
            Assert.That(allocated, Is.Zero);
        }

        [Test]
        public void BadInputIsRefusedWithTheReason()
        {
            Assert.Throws<ArgumentOutOfRangeException>(() => new HumanoidTake(0, Muscles, Bones));
            Assert.Throws<ArgumentOutOfRangeException>(() => new HumanoidTake(float.NaN, Muscles, Bones));
            var e = Assert.Throws<ArgumentException>(() => new HumanoidTake(60, new[] { "Jaw Close", "Jaw Close" }, Bones));
            StringAssert.Contains("Jaw Close", e.Message);
            e = Assert.Throws<ArgumentException>(() => new HumanoidTake(60, Muscles, new[] { "/Hips" }));
            StringAssert.Contains("/Hips", e.Message);
            Assert.Throws<ArgumentException>(() => new HumanoidTake(60, Muscles, new[] { "Hips", "Hips" }));

            var take = new HumanoidTake(60, Muscles, Bones);
            var s = Smooth(0, 60);
            e = Assert.Throws<ArgumentException>(() => take.Add(0, s.Body, s.BodyRotation, new float[3], s.Hips, s.Bones));
            StringAssert.Contains("3 muscles given, the take has 7", e.Message);
            e = Assert.Throws<ArgumentException>(() => take.Add(0, s.Body, s.BodyRotation, s.Muscles, s.Hips, new Quat[1]));
            StringAssert.Contains("1 bone rotations given, the take has 3", e.Message);
            s.Muscles[2] = float.NaN;
            e = Assert.Throws<ArgumentException>(() => Add(take, s));
            StringAssert.Contains("muscle 2", e.Message);
            Assert.That(take.Count, Is.Zero, "a refused sample is not kept");
            Assert.Throws<ArgumentOutOfRangeException>(() => new KeyReduction(-1f, 0.01f, 0.01f));
            Assert.Throws<ArgumentOutOfRangeException>(() => take.KeyTime(0));
        }

        // ---- files ---------------------------------------------------------------------------

        [Test]
        public void TakeFilesShareOneStemAndNumberTogether()
        {
            var files = TakeFiles.Reserve("Assets/Mocap Takes", "Avatar Take 2026-11-26 18-00-00", _ => false);
            Assert.That(files.All, Is.EqualTo(new[]
            {
                "Assets/Mocap Takes/Avatar Take 2026-11-26 18-00-00.anim",
                "Assets/Mocap Takes/Avatar Take 2026-11-26 18-00-00 Generic.anim",
                "Assets/Mocap Takes/Avatar Take 2026-11-26 18-00-00.mcpose",
                "Assets/Mocap Takes/Avatar Take 2026-11-26 18-00-00.cap",
                "Assets/Mocap Takes/Avatar Take 2026-11-26 18-00-00.calibration",
            }));
            // Only another take's capture is in the way: the whole set moves on to " 2".
            var taken = new HashSet<string> { "Assets/Mocap Takes/T.cap" };
            var numbered = TakeFiles.Reserve("Assets/Mocap Takes/", "T", taken.Contains);
            Assert.That(numbered.HumanoidClip, Is.EqualTo("Assets/Mocap Takes/T 2.anim"));
            Assert.That(numbered.Capture, Is.EqualTo("Assets/Mocap Takes/T 2.cap"));
            Assert.That(numbered.GenericClip, Is.EqualTo("Assets/Mocap Takes/T 2 Generic.anim"));
        }

        [Test]
        public void TheRawCaptureAndCalibrationAreCopiedBesideTheClip()
        {
            var project = TestPaths.NewTempDirectory("project");
            var captures = Path.Combine(project, "Captures");
            Directory.CreateDirectory(captures);
            var capture = Path.Combine(captures, "20261126-180000-000-0-Performer.cap");
            var bytes = Enumerable.Range(0, 5000).Select(i => (byte)(i * 7)).ToArray();
            File.WriteAllBytes(capture, bytes);
            var calibration = Path.Combine(captures, "session.calibration");
            File.WriteAllText(calibration, "calibration text");
            Directory.CreateDirectory(Path.Combine(project, "Assets", "Mocap Takes"));

            var files = TakeFiles.Reserve("Assets/Mocap Takes", "Take", p => File.Exists(TakeFiles.Absolute(p, project)));
            // The session may still be appending to the capture while it is copied.
            using (new FileStream(capture, FileMode.Open, FileAccess.Write, FileShare.ReadWrite))
                Assert.That(files.KeepCapture(capture, project), Is.EqualTo(Path.Combine(project, "Assets", "Mocap Takes", "Take.cap")));
            files.KeepCalibration(calibration, project);
            Assert.That(File.ReadAllBytes(TakeFiles.Absolute(files.Capture, project)), Is.EqualTo(bytes));
            Assert.That(File.ReadAllText(TakeFiles.Absolute(files.Calibration, project)), Is.EqualTo("calibration text"));

            var next = TakeFiles.Reserve("Assets/Mocap Takes", "Take", p => File.Exists(TakeFiles.Absolute(p, project)));
            Assert.That(next.Capture, Is.EqualTo("Assets/Mocap Takes/Take 2.cap"));
            var missing = Path.Combine(captures, "gone.cap");
            var e = Assert.Throws<MocapException>(() => next.KeepCapture(missing, project));
            Assert.That(e.Status, Is.EqualTo(MocapStatus.NotFound));
            StringAssert.Contains(missing, e.Message);
            Assert.That(File.Exists(TakeFiles.Absolute(next.Capture, project)), Is.False);
        }
    }
}
