using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu.Retarget
{
    /// <summary>
    /// One humanoid bone of a target rig at rest, in Unity's frame, as the Unity glue reads it from
    /// the avatar's transforms. "Rig space" is the space of the avatar's root (the Animator's
    /// transform): rotations and positions relative to it, so the avatar may stand anywhere.
    /// </summary>
    public readonly struct RigBone
    {
        /// <summary>The bone.</summary>
        public readonly HumanBone Bone;

        /// <summary>
        /// The nearest humanoid ancestor in the rig's hierarchy that is also described
        /// (<see cref="HumanBone.LastBone"/> for Hips). Non-humanoid transforms in between are fine:
        /// they are assumed to keep their rest pose.
        /// </summary>
        public readonly HumanBone Parent;

        /// <summary>The transform's rest local rotation (relative to its own transform parent, humanoid or not).</summary>
        public readonly Quat RestLocalRotation;

        /// <summary>The transform's rest rotation in rig space.</summary>
        public readonly Quat RestRotation;

        /// <summary>The transform's rest position in rig space (metres, Unity frame).</summary>
        public readonly Vec3 RestPosition;

        /// <summary>Describes one bone; rotations are normalised by <see cref="HumanoidRig"/>.</summary>
        public RigBone(HumanBone bone, HumanBone parent, Quat restLocalRotation, Quat restRotation, Vec3 restPosition)
        {
            Bone = bone;
            Parent = parent;
            RestLocalRotation = restLocalRotation;
            RestRotation = restRotation;
            RestPosition = restPosition;
        }

        /// <inheritdoc/>
        public override string ToString() => $"{Bone} (parent {Parent})";
    }
}
