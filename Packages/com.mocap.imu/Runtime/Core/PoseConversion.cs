using System;
using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu
{
    /// <summary>
    /// Conversions between the engine's <see cref="MocapPose"/> and the skeleton code's
    /// <see cref="SmplPose"/> (what the retargeter consumes). None allocates.
    /// </summary>
    public static class PoseConversion
    {
        /// <summary>Copy the pose's rotations and root position into <paramref name="target"/>.</summary>
        public static void ToSmplPose(ref MocapPose pose, SmplPose target) => pose.CopyTo(target);

        /// <summary>
        /// Set a <see cref="MocapPose"/>'s rotations and root position from <paramref name="source"/>,
        /// and its joint positions by forward kinematics on <paramref name="skeleton"/>; the
        /// other fields are left as they are.
        /// </summary>
        public static void FromSmplPose(SmplPose source, SmplSkeleton skeleton, ref MocapPose pose)
        {
            if (source == null) throw new ArgumentNullException(nameof(source));
            if (skeleton == null) throw new ArgumentNullException(nameof(skeleton));
            Span<Quat> global = stackalloc Quat[SmplSkeleton.JointCount];
            Span<Vec3> positions = stackalloc Vec3[SmplSkeleton.JointCount];
            skeleton.ForwardKinematics(source.Rotations, source.RootPosition, global, positions);
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
            {
                pose.SetJointRotation(j, source.Rotations[j]);
                pose.SetJointPosition(j, positions[j]);
            }
            pose.RootPosition = source.RootPosition;
        }
    }
}
