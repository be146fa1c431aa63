using Mocap.Imu.Maths;

namespace Mocap.Imu.Retarget
{
    /// <summary>
    /// Converts between the model frame (right-handed, Y up, the character faces +Z, +X is the
    /// character's left) and Unity's frame (left-handed, Y up, Z forward, +X right).
    /// </summary>
    /// <remarks>
    /// <para>Both frames share Y (up) and Z (the character's forward); they differ only in X, which
    /// points to the character's left in the model frame and to its right in Unity. The change of
    /// frame is therefore the mirror M = diag(-1, 1, 1): a point maps to (-x, y, z), a rotation
    /// matrix R to M R M.</para>
    /// <para>For a quaternion, the rotation axis is a pseudo-vector: under a mirror it maps to
    /// det(M) M a = (a.x, -a.y, -a.z) while the angle is kept, so (x, y, z, w) maps to
    /// (x, -y, -z, w). A turn to the character's left stays a turn to its left; the number on the
    /// Y axis changes sign because a positive angle about Y turns counter-clockwise seen from above
    /// in the right-handed frame and clockwise in Unity's.</para>
    /// <para>The mirror is its own inverse; both directions are provided so call sites read right.
    /// Directions and offsets convert like positions.</para>
    /// </remarks>
    public static class CoordinateConversion
    {
        /// <summary>A model-frame position or direction in Unity's frame.</summary>
        public static Vec3 ModelToUnity(Vec3 v) => new Vec3(-v.X, v.Y, v.Z);

        /// <summary>A Unity-frame position or direction in the model frame.</summary>
        public static Vec3 UnityToModel(Vec3 v) => new Vec3(-v.X, v.Y, v.Z);

        /// <summary>A model-frame rotation in Unity's frame.</summary>
        public static Quat ModelToUnity(Quat q) => new Quat(q.X, -q.Y, -q.Z, q.W);

        /// <summary>A Unity-frame rotation in the model frame.</summary>
        public static Quat UnityToModel(Quat q) => new Quat(q.X, -q.Y, -q.Z, q.W);

        /// <summary>A model-frame rotation matrix in Unity's frame (M R M: entries mixing X with Y or Z change sign).</summary>
        public static Mat3 ModelToUnity(Mat3 m) => new Mat3(
            m.M00, -m.M01, -m.M02,
            -m.M10, m.M11, m.M12,
            -m.M20, m.M21, m.M22);

        /// <summary>A Unity-frame rotation matrix in the model frame.</summary>
        public static Mat3 UnityToModel(Mat3 m) => ModelToUnity(m);
    }
}
