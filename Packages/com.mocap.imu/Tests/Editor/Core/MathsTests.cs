using System;
using Mocap.Imu.Maths;
using NUnit.Framework;

namespace Mocap.Imu.Tests.Maths
{
    /// <summary>Shared helpers for the maths-heavy tests.</summary>
    internal static class TestMaths
    {
        public const float Deg = MathF.PI / 180f;

        /// <summary>Uniformly distributed rotation (Shoemake's method).</summary>
        public static Quat RandomRotation(Random rng)
        {
            double u1 = rng.NextDouble(), u2 = rng.NextDouble() * 2 * Math.PI, u3 = rng.NextDouble() * 2 * Math.PI;
            double a = Math.Sqrt(1 - u1), b = Math.Sqrt(u1);
            return new Quat((float)(a * Math.Sin(u2)), (float)(a * Math.Cos(u2)), (float)(b * Math.Sin(u3)), (float)(b * Math.Cos(u3)));
        }

        /// <summary>Rotation about a random axis by a random angle up to <paramref name="maxDegrees"/>.</summary>
        public static Quat RandomRotation(Random rng, float maxDegrees) =>
            Quat.AxisAngle(RandomUnitVector(rng), (float)(rng.NextDouble() * maxDegrees) * Deg);

        public static Vec3 RandomUnitVector(Random rng)
        {
            while (true)
            {
                var v = new Vec3((float)(rng.NextDouble() * 2 - 1), (float)(rng.NextDouble() * 2 - 1), (float)(rng.NextDouble() * 2 - 1));
                float l = v.Length;
                if (l > 0.1f && l <= 1f) return v / l;
            }
        }

        public static void AssertVec(Vec3 expected, Vec3 actual, float tolerance, string what = "")
        {
            Assert.That(actual.ApproximatelyEquals(expected, tolerance), $"{what} expected {expected}, got {actual}");
        }

        public static void AssertRotation(Quat expected, Quat actual, float toleranceRadians, string what = "")
        {
            Assert.That(Quat.Angle(expected, actual), Is.LessThanOrEqualTo(toleranceRadians),
                $"{what} expected {expected}, got {actual}");
        }
    }

    public class MathsTests
    {
        [Test]
        public void Vec3_CrossFollowsTheRightHandFormula()
        {
            TestMaths.AssertVec(Vec3.UnitZ, Vec3.Cross(Vec3.UnitX, Vec3.UnitY), 0f);
            TestMaths.AssertVec(Vec3.UnitX, Vec3.Cross(Vec3.UnitY, Vec3.UnitZ), 0f);
            TestMaths.AssertVec(-Vec3.UnitY, Vec3.Cross(Vec3.UnitX, Vec3.UnitZ), 0f);
        }

        [Test]
        public void Vec3_NormalizedHasUnitLengthAndZeroStaysZero()
        {
            Assert.That(new Vec3(3f, -4f, 12f).Normalized.Length, Is.EqualTo(1f).Within(1e-6f));
            TestMaths.AssertVec(new Vec3(3f / 13f, -4f / 13f, 12f / 13f), new Vec3(3f, -4f, 12f).Normalized, 1e-6f);
            Assert.That(Vec3.Zero.Normalized, Is.EqualTo(Vec3.Zero));
        }

        [Test]
        public void Vec3_ArithmeticAndDot()
        {
            var a = new Vec3(1f, 2f, 3f);
            var b = new Vec3(-2f, 0.5f, 4f);
            Assert.That(a + b, Is.EqualTo(new Vec3(-1f, 2.5f, 7f)));
            Assert.That(a - b, Is.EqualTo(new Vec3(3f, 1.5f, -1f)));
            Assert.That(2f * a, Is.EqualTo(new Vec3(2f, 4f, 6f)));
            Assert.That(a / 2f, Is.EqualTo(new Vec3(0.5f, 1f, 1.5f)));
            Assert.That(Vec3.Dot(a, b), Is.EqualTo(-2f + 1f + 12f));
            Assert.That(Vec3.Distance(a, a + new Vec3(0f, 3f, 4f)), Is.EqualTo(5f).Within(1e-6f));
        }

        [Test]
        public void Quat_KnownQuarterTurns()
        {
            // The textbook right-hand formulas; Unity uses the same numbers (AngleAxis(90, up) * forward = right).
            TestMaths.AssertVec(Vec3.UnitX, Quat.AxisAngle(Vec3.UnitY, 90f * TestMaths.Deg) * Vec3.UnitZ, 1e-6f);
            TestMaths.AssertVec(Vec3.UnitY, Quat.AxisAngle(Vec3.UnitZ, 90f * TestMaths.Deg) * Vec3.UnitX, 1e-6f);
            TestMaths.AssertVec(Vec3.UnitZ, Quat.AxisAngle(Vec3.UnitX, 90f * TestMaths.Deg) * Vec3.UnitY, 1e-6f);
            TestMaths.AssertVec(-Vec3.UnitZ, Quat.AxisAngle(Vec3.UnitY, 180f * TestMaths.Deg) * Vec3.UnitZ, 1e-6f);
        }

        [Test]
        public void Quat_ProductAppliesRightOperandFirst()
        {
            Quat yaw = Quat.AxisAngle(Vec3.UnitY, 90f * TestMaths.Deg);
            Quat pitch = Quat.AxisAngle(Vec3.UnitX, 90f * TestMaths.Deg);
            // pitch first: Z -> -Y; then yaw leaves -Y alone.
            TestMaths.AssertVec(-Vec3.UnitY, (yaw * pitch) * Vec3.UnitZ, 1e-6f);
            // yaw first: Z -> X; then pitch leaves X alone.
            TestMaths.AssertVec(Vec3.UnitX, (pitch * yaw) * Vec3.UnitZ, 1e-6f);
        }

        [Test]
        public void Quat_CompositionMatchesSequentialRotation()
        {
            var rng = new Random(1);
            for (int i = 0; i < 200; i++)
            {
                Quat a = TestMaths.RandomRotation(rng), b = TestMaths.RandomRotation(rng);
                Vec3 v = TestMaths.RandomUnitVector(rng) * 2f;
                TestMaths.AssertVec(a * (b * v), (a * b) * v, 1e-5f);
                Assert.That((a * b).LengthSquared, Is.EqualTo(1f).Within(1e-5f));
                Assert.That((a * v).Length, Is.EqualTo(v.Length).Within(1e-5f));
            }
        }

        [Test]
        public void Quat_InverseUndoes()
        {
            var rng = new Random(2);
            for (int i = 0; i < 100; i++)
            {
                Quat q = TestMaths.RandomRotation(rng);
                Vec3 v = TestMaths.RandomUnitVector(rng);
                TestMaths.AssertVec(v, q.Inverse * (q * v), 1e-5f);
                TestMaths.AssertRotation(Quat.Identity, q * q.Inverse, 1e-3f);
            }
        }

        [Test]
        public void Quat_AngleTreatsNegatedQuaternionAsSameRotation()
        {
            Quat q = Quat.AxisAngle(new Vec3(1f, 2f, 3f), 1.2f);
            var neg = new Quat(-q.X, -q.Y, -q.Z, -q.W);
            Assert.That(q.ApproximatelyEquals(neg, 1e-3f), Is.True);
            Assert.That(Quat.Angle(Quat.Identity, Quat.AxisAngle(Vec3.UnitX, 0.5f)), Is.EqualTo(0.5f).Within(1e-3f));
            Assert.That(q.ApproximatelyEquals(Quat.Identity, 0.1f), Is.False);
        }

        [Test]
        public void Quat_ScalarFirstFactoryKeepsComponentsApart()
        {
            Quat q = Quat.FromWxyz(0.1f, 0.2f, 0.3f, 0.4f);
            Assert.That((q.W, q.X, q.Y, q.Z), Is.EqualTo((0.1f, 0.2f, 0.3f, 0.4f)));
            Assert.That(Quat.FromWxyz(1f, 0f, 0f, 0f), Is.EqualTo(Quat.Identity));
        }

        [Test]
        public void Quat_NormalizedOfZeroIsIdentity()
        {
            Assert.That(new Quat(0f, 0f, 0f, 0f).Normalized, Is.EqualTo(Quat.Identity));
            Assert.That(new Quat(0f, 0f, 2f, 0f).Normalized, Is.EqualTo(new Quat(0f, 0f, 1f, 0f)));
        }

        [Test]
        public void FromToRotation_MapsDirectionWithoutTwist()
        {
            var rng = new Random(3);
            for (int i = 0; i < 200; i++)
            {
                Vec3 a = TestMaths.RandomUnitVector(rng) * 3f, b = TestMaths.RandomUnitVector(rng) * 0.5f;
                Quat q = Quat.FromToRotation(a, b);
                TestMaths.AssertVec(b.Normalized, q * a.Normalized, 1e-5f);
                // Smallest rotation: its axis is perpendicular to both and the angle is the angle between them.
                Vec3 axis = new Vec3(q.X, q.Y, q.Z);
                if (axis.Length > 1e-4f)
                {
                    Assert.That(Vec3.Dot(axis.Normalized, a.Normalized), Is.EqualTo(0f).Within(1e-4f));
                    Assert.That(Vec3.Dot(axis.Normalized, b.Normalized), Is.EqualTo(0f).Within(1e-4f));
                }
                float between = MathF.Acos(Math.Clamp(Vec3.Dot(a.Normalized, b.Normalized), -1f, 1f));
                Assert.That(Quat.Angle(Quat.Identity, q), Is.EqualTo(between).Within(1e-3f));
            }
        }

        [Test]
        public void FromToRotation_ParallelOppositeAndZero()
        {
            Assert.That(Quat.Angle(Quat.Identity, Quat.FromToRotation(Vec3.UnitY, 2f * Vec3.UnitY)), Is.LessThan(1e-3f));
            foreach (Vec3 a in new[] { Vec3.UnitX, Vec3.UnitY, Vec3.UnitZ, new Vec3(1f, 1f, 1f).Normalized })
            {
                Quat q = Quat.FromToRotation(a, -a);
                TestMaths.AssertVec(-a, q * a, 1e-5f, $"half turn from {a}");
                Assert.That(q.LengthSquared, Is.EqualTo(1f).Within(1e-5f));
            }
            Assert.That(Quat.FromToRotation(Vec3.Zero, Vec3.UnitX), Is.EqualTo(Quat.Identity));
        }

        [Test]
        public void Mat3_FromRowMajorReadsRowsAndActsOnColumnVectors()
        {
            // Quarter turn about Z, written row by row as the contract stores it.
            ReadOnlySpan<float> rz = stackalloc float[] { 0f, -1f, 0f, 1f, 0f, 0f, 0f, 0f, 1f };
            Mat3 m = Mat3.FromRowMajor(rz);
            TestMaths.AssertVec(Vec3.UnitY, m * Vec3.UnitX, 0f);
            TestMaths.AssertVec(Vec3.UnitY, m.Column(0), 0f);
            TestMaths.AssertRotation(Quat.AxisAngle(Vec3.UnitZ, 90f * TestMaths.Deg), m.ToQuat(), 1e-5f);
            Span<float> back = stackalloc float[9];
            m.CopyToRowMajor(back);
            Assert.That(back.ToArray(), Is.EqualTo(rz.ToArray()));
            Assert.Throws<ArgumentException>(() => Mat3.FromRowMajor(new float[8]));
        }

        [Test]
        public void Mat3_QuaternionRoundTripCoversEveryBranch()
        {
            var rng = new Random(4);
            var cases = new System.Collections.Generic.List<Quat>
            {
                Quat.Identity,
                Quat.AxisAngle(Vec3.UnitX, MathF.PI), Quat.AxisAngle(Vec3.UnitY, MathF.PI), Quat.AxisAngle(Vec3.UnitZ, MathF.PI),
                Quat.AxisAngle(new Vec3(1f, 1f, 0f), 3.1f), Quat.AxisAngle(new Vec3(0f, 1f, 1f), 3.0f),
            };
            for (int i = 0; i < 300; i++) cases.Add(TestMaths.RandomRotation(rng));
            foreach (Quat q in cases)
            {
                Mat3 m = Mat3.FromQuat(q);
                Assert.That(m.Determinant, Is.EqualTo(1f).Within(1e-5f));
                Vec3 v = new Vec3(0.3f, -0.7f, 0.2f);
                TestMaths.AssertVec(q * v, m * v, 1e-5f);
                TestMaths.AssertRotation(q, m.ToQuat(), 1e-3f, "round trip");
                Assert.That((m * m.Transposed).ApproximatelyEquals(Mat3.Identity, 1e-5f), Is.True);
            }
        }

        [Test]
        public void Mat3_ProductMatchesQuaternionProduct()
        {
            var rng = new Random(5);
            for (int i = 0; i < 100; i++)
            {
                Quat a = TestMaths.RandomRotation(rng), b = TestMaths.RandomRotation(rng);
                Assert.That((Mat3.FromQuat(a) * Mat3.FromQuat(b)).ApproximatelyEquals(Mat3.FromQuat(a * b), 1e-5f), Is.True);
            }
        }

        [Test]
        public void Mat3_ToQuatOfSlightlySkewedMatrixIsNearbyUnitRotation()
        {
            Mat3 m = Mat3.FromQuat(Quat.AxisAngle(new Vec3(0.2f, 1f, -0.3f), 0.8f));
            var skewed = new Mat3(m.M00 * 1.01f, m.M01, m.M02 + 0.005f, m.M10, m.M11 * 0.99f, m.M12, m.M20, m.M21, m.M22);
            Quat q = skewed.ToQuat();
            Assert.That(q.LengthSquared, Is.EqualTo(1f).Within(1e-5f));
            TestMaths.AssertRotation(m.ToQuat(), q, 0.02f);
        }
    }
}
