using Mocap.Imu.Maths;
using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>
    /// Core maths types to Unity's and back. The core's Retarget types are already in Unity's
    /// frame (left-handed, Y up), so these are plain component copies, no handedness change.
    /// </summary>
    public static class UnityConversions
    {
        /// <summary>A core quaternion as Unity's.</summary>
        public static Quaternion ToUnity(this Quat q) => new Quaternion(q.X, q.Y, q.Z, q.W);

        /// <summary>A core vector as Unity's.</summary>
        public static Vector3 ToUnity(this Vec3 v) => new Vector3(v.X, v.Y, v.Z);

        /// <summary>A Unity quaternion as the core's.</summary>
        public static Quat ToCore(this Quaternion q) => new Quat(q.x, q.y, q.z, q.w);

        /// <summary>A Unity vector as the core's.</summary>
        public static Vec3 ToCore(this Vector3 v) => new Vec3(v.x, v.y, v.z);
    }
}
