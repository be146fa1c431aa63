using System;
using Mocap.Imu.Maths;
using Mocap.Imu.Retarget;
using Mocap.Imu.Tests.Maths;
using NUnit.Framework;

namespace Mocap.Imu.Tests.Retarget
{
    public class CoordinateConversionTests
    {
        // Directions named for the character, in each frame.
        private static readonly Vec3 ModelLeft = Vec3.UnitX, ModelUp = Vec3.UnitY, ModelForward = Vec3.UnitZ;
        private static readonly Vec3 UnityLeft = -Vec3.UnitX, UnityUp = Vec3.UnitY, UnityForward = Vec3.UnitZ;

        [Test]
        public void PositionsKeepTheirMeaning()
        {
            TestMaths.AssertVec(UnityLeft, CoordinateConversion.ModelToUnity(ModelLeft), 0f);
            TestMaths.AssertVec(UnityUp, CoordinateConversion.ModelToUnity(ModelUp), 0f);
            TestMaths.AssertVec(UnityForward, CoordinateConversion.ModelToUnity(ModelForward), 0f);
            TestMaths.AssertVec(new Vec3(-0.2f, 1.4f, 0.3f), CoordinateConversion.ModelToUnity(new Vec3(0.2f, 1.4f, 0.3f)), 0f);
            TestMaths.AssertVec(new Vec3(0.2f, 1.4f, 0.3f), CoordinateConversion.UnityToModel(new Vec3(-0.2f, 1.4f, 0.3f)), 0f);
        }

        [Test]
        public void TurnToTheLeftStaysATurnToTheLeft()
        {
            // In the right-handed model frame +90 deg about +Y takes forward (+Z) to the character's left (+X).
            Quat modelTurn = Quat.AxisAngle(ModelUp, 90f * TestMaths.Deg);
            TestMaths.AssertVec(ModelLeft, modelTurn * ModelForward, 1e-6f);

            Quat unityTurn = CoordinateConversion.ModelToUnity(modelTurn);
            TestMaths.AssertVec(UnityLeft, unityTurn * UnityForward, 1e-6f);
            // In Unity a positive angle about up turns right (AngleAxis(90, up) * forward = right), so a
            // left turn is -90 deg: the same numbers Unity's Quaternion.AngleAxis(-90, Vector3.up) holds.
            TestMaths.AssertRotation(Quat.AxisAngle(UnityUp, -90f * TestMaths.Deg), unityTurn, 1e-6f);
        }

        [Test]
        public void NodForwardStaysANodForward()
        {
            // The head's up tips towards forward: +90 deg about +X (the left axis) in the model frame.
            Quat modelNod = Quat.AxisAngle(ModelLeft, 90f * TestMaths.Deg);
            TestMaths.AssertVec(ModelForward, modelNod * ModelUp, 1e-6f);
            Quat unityNod = CoordinateConversion.ModelToUnity(modelNod);
            TestMaths.AssertVec(UnityForward, unityNod * UnityUp, 1e-6f);
            // Unity: the same nod is +90 deg about +X (right): AngleAxis(90, right) * up = forward.
            TestMaths.AssertRotation(Quat.AxisAngle(Vec3.UnitX, 90f * TestMaths.Deg), unityNod, 1e-6f);
        }

        [Test]
        public void RaisingTheLeftArmStaysRaisingTheLeftArm()
        {
            // The left arm points along the character's left; +90 deg about forward (+Z) raises it in the model frame.
            Quat modelRaise = Quat.AxisAngle(ModelForward, 90f * TestMaths.Deg);
            TestMaths.AssertVec(ModelUp, modelRaise * ModelLeft, 1e-6f);
            Quat unityRaise = CoordinateConversion.ModelToUnity(modelRaise);
            TestMaths.AssertVec(UnityUp, unityRaise * UnityLeft, 1e-6f);
            // And the right arm goes down in both, as the same rotation must do.
            TestMaths.AssertVec(-UnityUp, unityRaise * -UnityLeft, 1e-6f);
        }

        [Test]
        public void ConversionCommutesWithRotationAndComposition()
        {
            var rng = new Random(21);
            for (int i = 0; i < 200; i++)
            {
                Quat a = TestMaths.RandomRotation(rng), b = TestMaths.RandomRotation(rng);
                Vec3 v = TestMaths.RandomUnitVector(rng);
                // Rotating then converting equals converting then rotating.
                TestMaths.AssertVec(CoordinateConversion.ModelToUnity(a * v),
                    CoordinateConversion.ModelToUnity(a) * CoordinateConversion.ModelToUnity(v), 1e-5f);
                TestMaths.AssertRotation(CoordinateConversion.ModelToUnity(a * b),
                    CoordinateConversion.ModelToUnity(a) * CoordinateConversion.ModelToUnity(b), 1e-3f);
                // Round trip.
                Assert.That(CoordinateConversion.UnityToModel(CoordinateConversion.ModelToUnity(a)), Is.EqualTo(a));
                Assert.That(CoordinateConversion.UnityToModel(CoordinateConversion.ModelToUnity(v)), Is.EqualTo(v));
                // The angle is kept; the conversion is not the identity on a generic rotation.
                Assert.That(Quat.Angle(Quat.Identity, CoordinateConversion.ModelToUnity(a)),
                    Is.EqualTo(Quat.Angle(Quat.Identity, a)).Within(1e-4f));
            }
        }

        [Test]
        public void MatrixConversionAgreesWithQuaternionConversion()
        {
            var rng = new Random(22);
            for (int i = 0; i < 100; i++)
            {
                Quat q = TestMaths.RandomRotation(rng);
                Mat3 m = CoordinateConversion.ModelToUnity(Mat3.FromQuat(q));
                Assert.That(m.ApproximatelyEquals(Mat3.FromQuat(CoordinateConversion.ModelToUnity(q)), 1e-5f), Is.True);
                Assert.That(m.Determinant, Is.EqualTo(1f).Within(1e-5f), "still a rotation, not a reflection");
                Assert.That(CoordinateConversion.UnityToModel(m).ApproximatelyEquals(Mat3.FromQuat(q), 1e-6f), Is.True);
            }
            // Column 2 (where the bone's forward points) converts like a direction.
            Mat3 turn = Mat3.FromQuat(Quat.AxisAngle(ModelUp, 90f * TestMaths.Deg));
            TestMaths.AssertVec(CoordinateConversion.ModelToUnity(turn.Column(2)), CoordinateConversion.ModelToUnity(turn).Column(2), 1e-6f);
        }
    }
}
