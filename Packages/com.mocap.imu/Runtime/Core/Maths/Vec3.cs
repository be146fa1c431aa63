using System;
using System.Globalization;

namespace Mocap.Imu.Maths
{
    /// <summary>
    /// A 3-component float vector. Handedness-agnostic: the same numbers mean different things in
    /// the model frame and in Unity's frame, so every API that takes one says which frame it expects
    /// (see <see cref="Retarget.CoordinateConversion"/>).
    /// </summary>
    /// <remarks>
    /// Our own type rather than <c>System.Numerics.Vector3</c> or <c>UnityEngine.Vector3</c>: the core
    /// stays engine-free and the Unity glue must convert explicitly at the boundary, which is the one
    /// place where a frame change could be forgotten. Floats match Unity's precision.
    /// </remarks>
    [Serializable]
    public readonly struct Vec3 : IEquatable<Vec3>
    {
        /// <summary>X component.</summary>
        public readonly float X;
        /// <summary>Y component.</summary>
        public readonly float Y;
        /// <summary>Z component.</summary>
        public readonly float Z;

        /// <summary>Creates a vector from its components.</summary>
        public Vec3(float x, float y, float z)
        {
            X = x;
            Y = y;
            Z = z;
        }

        /// <summary>(0, 0, 0).</summary>
        public static Vec3 Zero => new Vec3(0f, 0f, 0f);
        /// <summary>(1, 0, 0).</summary>
        public static Vec3 UnitX => new Vec3(1f, 0f, 0f);
        /// <summary>(0, 1, 0).</summary>
        public static Vec3 UnitY => new Vec3(0f, 1f, 0f);
        /// <summary>(0, 0, 1).</summary>
        public static Vec3 UnitZ => new Vec3(0f, 0f, 1f);

        /// <summary>Euclidean length.</summary>
        public float Length => MathF.Sqrt(X * X + Y * Y + Z * Z);

        /// <summary>Squared Euclidean length.</summary>
        public float LengthSquared => X * X + Y * Y + Z * Z;

        /// <summary>True when every component is a finite number.</summary>
        public bool IsFinite => float.IsFinite(X) && float.IsFinite(Y) && float.IsFinite(Z);

        /// <summary>This vector scaled to unit length; the zero vector stays zero.</summary>
        public Vec3 Normalized
        {
            get
            {
                float len = Length;
                // Zero stays zero instead of becoming NaN: callers test for degenerate input themselves.
                return len > 0f ? new Vec3(X / len, Y / len, Z / len) : Zero;
            }
        }

        /// <summary>Dot product.</summary>
        public static float Dot(Vec3 a, Vec3 b) => a.X * b.X + a.Y * b.Y + a.Z * b.Z;

        /// <summary>Cross product a x b (the same formula in either handedness).</summary>
        public static Vec3 Cross(Vec3 a, Vec3 b) =>
            new Vec3(a.Y * b.Z - a.Z * b.Y, a.Z * b.X - a.X * b.Z, a.X * b.Y - a.Y * b.X);

        /// <summary>Distance between two points.</summary>
        public static float Distance(Vec3 a, Vec3 b) => (a - b).Length;

        /// <summary>Component-wise sum.</summary>
        public static Vec3 operator +(Vec3 a, Vec3 b) => new Vec3(a.X + b.X, a.Y + b.Y, a.Z + b.Z);
        /// <summary>Component-wise difference.</summary>
        public static Vec3 operator -(Vec3 a, Vec3 b) => new Vec3(a.X - b.X, a.Y - b.Y, a.Z - b.Z);
        /// <summary>Negation.</summary>
        public static Vec3 operator -(Vec3 a) => new Vec3(-a.X, -a.Y, -a.Z);
        /// <summary>Scaling.</summary>
        public static Vec3 operator *(Vec3 a, float s) => new Vec3(a.X * s, a.Y * s, a.Z * s);
        /// <summary>Scaling.</summary>
        public static Vec3 operator *(float s, Vec3 a) => new Vec3(a.X * s, a.Y * s, a.Z * s);
        /// <summary>Division by a scalar.</summary>
        public static Vec3 operator /(Vec3 a, float s) => new Vec3(a.X / s, a.Y / s, a.Z / s);

        /// <summary>Exact component-wise equality.</summary>
        public bool Equals(Vec3 other) => X.Equals(other.X) && Y.Equals(other.Y) && Z.Equals(other.Z);

        /// <inheritdoc/>
        public override bool Equals(object obj) => obj is Vec3 other && Equals(other);

        /// <inheritdoc/>
        public override int GetHashCode() => HashCode.Combine(X, Y, Z);

        /// <summary>True when every component differs by at most <paramref name="tolerance"/>.</summary>
        public bool ApproximatelyEquals(Vec3 other, float tolerance) =>
            MathF.Abs(X - other.X) <= tolerance && MathF.Abs(Y - other.Y) <= tolerance &&
            MathF.Abs(Z - other.Z) <= tolerance;

        /// <summary>Exact equality.</summary>
        public static bool operator ==(Vec3 a, Vec3 b) => a.Equals(b);
        /// <summary>Exact inequality.</summary>
        public static bool operator !=(Vec3 a, Vec3 b) => !a.Equals(b);

        /// <inheritdoc/>
        public override string ToString() =>
            string.Format(CultureInfo.InvariantCulture, "({0:G6}, {1:G6}, {2:G6})", X, Y, Z);
    }
}
