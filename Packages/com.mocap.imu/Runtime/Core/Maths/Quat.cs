using System;
using System.Globalization;

namespace Mocap.Imu.Maths
{
    /// <summary>
    /// A rotation quaternion (Hamilton convention, scalar <see cref="W"/>), float precision.
    /// </summary>
    /// <remarks>
    /// The constructor takes (x, y, z, w), the same order as <c>UnityEngine.Quaternion</c>, so the glue
    /// converts with <c>new Quaternion(q.X, q.Y, q.Z, q.W)</c>. Products compose like Unity's:
    /// <c>a * b</c> applies <c>b</c> first, then <c>a</c>; <c>q * v</c> rotates a vector. The formulas are
    /// the same in a right-handed and a left-handed frame (only the visual sense of a positive angle
    /// differs), so one type serves the model frame and Unity's frame; converting between the two
    /// frames is <see cref="Retarget.CoordinateConversion"/>'s job, never implicit.
    /// </remarks>
    [Serializable]
    public readonly struct Quat : IEquatable<Quat>
    {
        /// <summary>Vector part, x.</summary>
        public readonly float X;
        /// <summary>Vector part, y.</summary>
        public readonly float Y;
        /// <summary>Vector part, z.</summary>
        public readonly float Z;
        /// <summary>Scalar part.</summary>
        public readonly float W;

        /// <summary>Creates a quaternion from its components, in Unity's (x, y, z, w) order.</summary>
        public Quat(float x, float y, float z, float w)
        {
            X = x;
            Y = y;
            Z = z;
            W = w;
        }

        /// <summary>
        /// Creates a quaternion from components in scalar-first (w, x, y, z) order, the order of the
        /// native engine's quaternions and of the maths literature; named so the order is never guessed.
        /// </summary>
        public static Quat FromWxyz(float w, float x, float y, float z) => new Quat(x, y, z, w);

        /// <summary>The identity rotation.</summary>
        public static Quat Identity => new Quat(0f, 0f, 0f, 1f);

        /// <summary>Squared norm (1 for a rotation).</summary>
        public float LengthSquared => X * X + Y * Y + Z * Z + W * W;

        /// <summary>True when every component is a finite number.</summary>
        public bool IsFinite => float.IsFinite(X) && float.IsFinite(Y) && float.IsFinite(Z) && float.IsFinite(W);

        /// <summary>The conjugate; for a unit quaternion this is the inverse rotation.</summary>
        public Quat Conjugate => new Quat(-X, -Y, -Z, W);

        /// <summary>
        /// The inverse rotation. Rotations here are unit quaternions, so this is the conjugate;
        /// dividing by the norm would only hide a bug upstream.
        /// </summary>
        public Quat Inverse => new Quat(-X, -Y, -Z, W);

        /// <summary>This quaternion scaled to unit norm; a zero quaternion becomes the identity.</summary>
        public Quat Normalized
        {
            get
            {
                float n2 = LengthSquared;
                // A zero quaternion has no meaningful direction; identity is the least surprising answer.
                if (!(n2 > 0f)) return Identity;
                float inv = 1f / MathF.Sqrt(n2);
                return new Quat(X * inv, Y * inv, Z * inv, W * inv);
            }
        }

        /// <summary>Rotation of <paramref name="radians"/> about <paramref name="axis"/> (need not be unit length).</summary>
        public static Quat AxisAngle(Vec3 axis, float radians)
        {
            Vec3 n = axis.Normalized;
            float s = MathF.Sin(0.5f * radians);
            return new Quat(n.X * s, n.Y * s, n.Z * s, MathF.Cos(0.5f * radians));
        }

        /// <summary>
        /// The smallest rotation that turns direction <paramref name="from"/> into direction
        /// <paramref name="to"/> (a "swing": no twist about either vector). Neither needs unit length.
        /// Opposite vectors give a half turn about an axis perpendicular to <paramref name="from"/>;
        /// a zero vector gives the identity.
        /// </summary>
        public static Quat FromToRotation(Vec3 from, Vec3 to)
        {
            Vec3 a = from.Normalized;
            Vec3 b = to.Normalized;
            if (a.LengthSquared == 0f || b.LengthSquared == 0f) return Identity;
            float d = Vec3.Dot(a, b);
            if (d < -0.999999f)
            {
                // Half turn: any axis perpendicular to a works; pick the one best conditioned.
                Vec3 axis = Vec3.Cross(MathF.Abs(a.X) < 0.9f ? Vec3.UnitX : Vec3.UnitY, a).Normalized;
                return new Quat(axis.X, axis.Y, axis.Z, 0f);
            }
            // Half-angle form: q = (a x b, 1 + a.b) normalised; stable except near the half turn above.
            Vec3 c = Vec3.Cross(a, b);
            return new Quat(c.X, c.Y, c.Z, 1f + d).Normalized;
        }

        /// <summary>Composition: the result applies <paramref name="b"/> first, then <paramref name="a"/>.</summary>
        public static Quat operator *(Quat a, Quat b) => new Quat(
            a.W * b.X + a.X * b.W + a.Y * b.Z - a.Z * b.Y,
            a.W * b.Y - a.X * b.Z + a.Y * b.W + a.Z * b.X,
            a.W * b.Z + a.X * b.Y - a.Y * b.X + a.Z * b.W,
            a.W * b.W - a.X * b.X - a.Y * b.Y - a.Z * b.Z);

        /// <summary>Rotates vector <paramref name="v"/> by unit quaternion <paramref name="q"/>.</summary>
        public static Vec3 operator *(Quat q, Vec3 v)
        {
            // v' = v + 2w (u x v) + 2 u x (u x v), u = vector part; cheaper than q v q*.
            var u = new Vec3(q.X, q.Y, q.Z);
            Vec3 t = 2f * Vec3.Cross(u, v);
            return v + q.W * t + Vec3.Cross(u, t);
        }

        /// <summary>4D dot product; |dot| = 1 means the same rotation.</summary>
        public static float Dot(Quat a, Quat b) => a.X * b.X + a.Y * b.Y + a.Z * b.Z + a.W * b.W;

        /// <summary>Angle in radians of the rotation that takes <paramref name="a"/> to <paramref name="b"/> (0..pi).</summary>
        public static float Angle(Quat a, Quat b)
        {
            // atan2 of the relative rotation's parts rather than acos of a dot product: acos loses
            // half the float digits near 0, exactly where tolerances are checked.
            Quat r = a.Normalized.Inverse * b.Normalized;
            float s = MathF.Sqrt(r.X * r.X + r.Y * r.Y + r.Z * r.Z);
            return 2f * MathF.Atan2(s, MathF.Abs(r.W));
        }

        /// <summary>
        /// True when both represent the same rotation within <paramref name="toleranceRadians"/>
        /// (q and -q are the same rotation).
        /// </summary>
        public bool ApproximatelyEquals(Quat other, float toleranceRadians) => Angle(this, other) <= toleranceRadians;

        /// <summary>Exact component-wise equality (q and -q are different here; see <see cref="ApproximatelyEquals"/>).</summary>
        public bool Equals(Quat other) =>
            X.Equals(other.X) && Y.Equals(other.Y) && Z.Equals(other.Z) && W.Equals(other.W);

        /// <inheritdoc/>
        public override bool Equals(object obj) => obj is Quat other && Equals(other);

        /// <inheritdoc/>
        public override int GetHashCode() => HashCode.Combine(X, Y, Z, W);

        /// <summary>Exact equality.</summary>
        public static bool operator ==(Quat a, Quat b) => a.Equals(b);
        /// <summary>Exact inequality.</summary>
        public static bool operator !=(Quat a, Quat b) => !a.Equals(b);

        /// <inheritdoc/>
        public override string ToString() =>
            string.Format(CultureInfo.InvariantCulture, "(x {0:G6}, y {1:G6}, z {2:G6}, w {3:G6})", X, Y, Z, W);
    }
}
