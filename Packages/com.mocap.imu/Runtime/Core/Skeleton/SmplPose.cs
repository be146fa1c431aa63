using System;
using Mocap.Imu.Maths;

namespace Mocap.Imu.Skeleton
{
    /// <summary>
    /// One frame of the model's output in the model frame: 24 joint rotations (joint 0 global, the
    /// others local and relative to the T-pose rest) and the pelvis position. Reused frame after
    /// frame so streaming allocates nothing.
    /// </summary>
    public sealed class SmplPose
    {
        /// <summary>Joint rotations, index = <see cref="SmplJoint"/>; the array is owned by this pose and reused.</summary>
        public Quat[] Rotations { get; } = new Quat[SmplSkeleton.JointCount];

        /// <summary>Pelvis position, model frame, metres (floor at y = 0).</summary>
        public Vec3 RootPosition { get; set; }

        /// <summary>Creates the rest pose (all rotations identity) with the pelvis at the origin.</summary>
        public SmplPose() => SetRest(Vec3.Zero);

        /// <summary>Sets every rotation to identity (the T-pose) and the pelvis to <paramref name="rootPosition"/>.</summary>
        public void SetRest(Vec3 rootPosition)
        {
            for (int j = 0; j < Rotations.Length; j++) Rotations[j] = Quat.Identity;
            RootPosition = rootPosition;
        }

        /// <summary>
        /// Reads the contract's <c>joint_rotations</c> for one frame: 24 row-major 3x3 matrices
        /// (216 floats). Allocates nothing.
        /// </summary>
        /// <exception cref="ArgumentException">Fewer than 216 values.</exception>
        public void SetFromRowMajorMatrices(ReadOnlySpan<float> matrices, Vec3 rootPosition)
        {
            if (matrices.Length < 9 * SmplSkeleton.JointCount)
                throw new ArgumentException($"expected {9 * SmplSkeleton.JointCount} floats, got {matrices.Length}", nameof(matrices));
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
                Rotations[j] = Mat3.FromRowMajor(matrices.Slice(9 * j, 9)).ToQuat();
            RootPosition = rootPosition;
        }

        /// <summary>Copies another pose into this one.</summary>
        public void CopyFrom(SmplPose other)
        {
            if (other == null) throw new ArgumentNullException(nameof(other));
            Array.Copy(other.Rotations, Rotations, Rotations.Length);
            RootPosition = other.RootPosition;
        }
    }
}
