using System;
using System.Globalization;

namespace Mocap.Imu.Maths
{
    /// <summary>
    /// A 3x3 float matrix, row-major, acting on column vectors (<c>M * v</c>), the layout the model
    /// contract uses for its rotation matrices (<c>[3][3]</c> row-major, bone frame to parent frame).
    /// </summary>
    /// <remarks>
    /// Not <c>System.Numerics.Matrix4x4</c>: that type multiplies row vectors (<c>v * M</c>), so a
    /// contract matrix read into it would silently be its transpose.
    /// </remarks>
    [Serializable]
    public readonly struct Mat3 : IEquatable<Mat3>
    {
        /// <summary>Row 0.</summary>
        public readonly float M00, M01, M02;
        /// <summary>Row 1.</summary>
        public readonly float M10, M11, M12;
        /// <summary>Row 2.</summary>
        public readonly float M20, M21, M22;

        /// <summary>Creates a matrix from its nine entries, row by row.</summary>
        public Mat3(float m00, float m01, float m02, float m10, float m11, float m12, float m20, float m21, float m22)
        {
            M00 = m00; M01 = m01; M02 = m02;
            M10 = m10; M11 = m11; M12 = m12;
            M20 = m20; M21 = m21; M22 = m22;
        }

        /// <summary>The identity matrix.</summary>
        public static Mat3 Identity => new Mat3(1f, 0f, 0f, 0f, 1f, 0f, 0f, 0f, 1f);

        /// <summary>Reads nine row-major values (the contract's layout) starting at <paramref name="values"/>[0].</summary>
        /// <exception cref="ArgumentException">Fewer than nine values.</exception>
        public static Mat3 FromRowMajor(ReadOnlySpan<float> values)
        {
            if (values.Length < 9)
                throw new ArgumentException($"a 3x3 matrix needs 9 values, got {values.Length}", nameof(values));
            return new Mat3(values[0], values[1], values[2], values[3], values[4], values[5], values[6], values[7], values[8]);
        }

        /// <summary>Writes the nine entries row-major into <paramref name="destination"/>.</summary>
        public void CopyToRowMajor(Span<float> destination)
        {
            if (destination.Length < 9)
                throw new ArgumentException($"a 3x3 matrix needs 9 values, got {destination.Length}", nameof(destination));
            destination[0] = M00; destination[1] = M01; destination[2] = M02;
            destination[3] = M10; destination[4] = M11; destination[5] = M12;
            destination[6] = M20; destination[7] = M21; destination[8] = M22;
        }

        /// <summary>Column <paramref name="index"/> (0..2): where the frame's X, Y or Z axis points.</summary>
        public Vec3 Column(int index) => index switch
        {
            0 => new Vec3(M00, M10, M20),
            1 => new Vec3(M01, M11, M21),
            2 => new Vec3(M02, M12, M22),
            _ => throw new ArgumentOutOfRangeException(nameof(index)),
        };

        /// <summary>The transpose (the inverse, for a rotation).</summary>
        public Mat3 Transposed => new Mat3(M00, M10, M20, M01, M11, M21, M02, M12, M22);

        /// <summary>Determinant (+1 for a rotation, -1 for a reflection).</summary>
        public float Determinant =>
            M00 * (M11 * M22 - M12 * M21) - M01 * (M10 * M22 - M12 * M20) + M02 * (M10 * M21 - M11 * M20);

        /// <summary>Matrix product: <c>(a * b) v = a (b v)</c>.</summary>
        public static Mat3 operator *(Mat3 a, Mat3 b) => new Mat3(
            a.M00 * b.M00 + a.M01 * b.M10 + a.M02 * b.M20,
            a.M00 * b.M01 + a.M01 * b.M11 + a.M02 * b.M21,
            a.M00 * b.M02 + a.M01 * b.M12 + a.M02 * b.M22,
            a.M10 * b.M00 + a.M11 * b.M10 + a.M12 * b.M20,
            a.M10 * b.M01 + a.M11 * b.M11 + a.M12 * b.M21,
            a.M10 * b.M02 + a.M11 * b.M12 + a.M12 * b.M22,
            a.M20 * b.M00 + a.M21 * b.M10 + a.M22 * b.M20,
            a.M20 * b.M01 + a.M21 * b.M11 + a.M22 * b.M21,
            a.M20 * b.M02 + a.M21 * b.M12 + a.M22 * b.M22);

        /// <summary>Matrix times column vector.</summary>
        public static Vec3 operator *(Mat3 m, Vec3 v) => new Vec3(
            m.M00 * v.X + m.M01 * v.Y + m.M02 * v.Z,
            m.M10 * v.X + m.M11 * v.Y + m.M12 * v.Z,
            m.M20 * v.X + m.M21 * v.Y + m.M22 * v.Z);

        /// <summary>The rotation matrix of unit quaternion <paramref name="q"/>.</summary>
        public static Mat3 FromQuat(Quat q)
        {
            float xx = q.X * q.X, yy = q.Y * q.Y, zz = q.Z * q.Z;
            float xy = q.X * q.Y, xz = q.X * q.Z, yz = q.Y * q.Z;
            float wx = q.W * q.X, wy = q.W * q.Y, wz = q.W * q.Z;
            return new Mat3(
                1f - 2f * (yy + zz), 2f * (xy - wz), 2f * (xz + wy),
                2f * (xy + wz), 1f - 2f * (xx + zz), 2f * (yz - wx),
                2f * (xz - wy), 2f * (yz + wx), 1f - 2f * (xx + yy));
        }

        /// <summary>
        /// The unit quaternion of this rotation matrix. A slightly non-orthonormal matrix (network
        /// output, float round-off) gives the quaternion of a nearby rotation; the result is normalised.
        /// </summary>
        public Quat ToQuat()
        {
            // Shepperd's method: divide by the largest of the four candidate terms so the square root
            // never sees a small, cancellation-prone argument.
            float trace = M00 + M11 + M22;
            float x, y, z, w;
            if (trace > 0f)
            {
                float s = 2f * MathF.Sqrt(1f + trace);
                w = 0.25f * s;
                x = (M21 - M12) / s;
                y = (M02 - M20) / s;
                z = (M10 - M01) / s;
            }
            else if (M00 > M11 && M00 > M22)
            {
                float s = 2f * MathF.Sqrt(MathF.Max(1e-12f, 1f + M00 - M11 - M22));
                w = (M21 - M12) / s;
                x = 0.25f * s;
                y = (M01 + M10) / s;
                z = (M02 + M20) / s;
            }
            else if (M11 > M22)
            {
                float s = 2f * MathF.Sqrt(MathF.Max(1e-12f, 1f + M11 - M00 - M22));
                w = (M02 - M20) / s;
                x = (M01 + M10) / s;
                y = 0.25f * s;
                z = (M12 + M21) / s;
            }
            else
            {
                float s = 2f * MathF.Sqrt(MathF.Max(1e-12f, 1f + M22 - M00 - M11));
                w = (M10 - M01) / s;
                x = (M02 + M20) / s;
                y = (M12 + M21) / s;
                z = 0.25f * s;
            }
            return new Quat(x, y, z, w).Normalized;
        }

        /// <summary>True when every entry differs by at most <paramref name="tolerance"/>.</summary>
        public bool ApproximatelyEquals(Mat3 o, float tolerance) =>
            MathF.Abs(M00 - o.M00) <= tolerance && MathF.Abs(M01 - o.M01) <= tolerance && MathF.Abs(M02 - o.M02) <= tolerance &&
            MathF.Abs(M10 - o.M10) <= tolerance && MathF.Abs(M11 - o.M11) <= tolerance && MathF.Abs(M12 - o.M12) <= tolerance &&
            MathF.Abs(M20 - o.M20) <= tolerance && MathF.Abs(M21 - o.M21) <= tolerance && MathF.Abs(M22 - o.M22) <= tolerance;

        /// <summary>Exact equality.</summary>
        public bool Equals(Mat3 o) =>
            M00.Equals(o.M00) && M01.Equals(o.M01) && M02.Equals(o.M02) &&
            M10.Equals(o.M10) && M11.Equals(o.M11) && M12.Equals(o.M12) &&
            M20.Equals(o.M20) && M21.Equals(o.M21) && M22.Equals(o.M22);

        /// <inheritdoc/>
        public override bool Equals(object obj) => obj is Mat3 other && Equals(other);

        /// <inheritdoc/>
        public override int GetHashCode() =>
            HashCode.Combine(HashCode.Combine(M00, M01, M02, M10, M11), HashCode.Combine(M12, M20, M21, M22));

        /// <inheritdoc/>
        public override string ToString() => string.Format(CultureInfo.InvariantCulture,
            "[[{0:G6}, {1:G6}, {2:G6}], [{3:G6}, {4:G6}, {5:G6}], [{6:G6}, {7:G6}, {8:G6}]]",
            M00, M01, M02, M10, M11, M12, M20, M21, M22);
    }
}
