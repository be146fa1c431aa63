using System.Collections.Generic;
using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu.Retarget
{
    /// <summary>
    /// A humanoid with the model's own proportions, standing in its T-pose on the floor under the
    /// avatar root: what the Unity glue builds when no avatar is given (samples, PlayMode tests),
    /// and a rig whose retargeted pose equals the model's forward kinematics.
    /// </summary>
    public static class HumanoidLayout
    {
        /// <summary>One bone: its humanoid parent (LastBone for Hips) and its offset from it, Unity frame, metres.</summary>
        public readonly struct Bone
        {
            /// <summary>The bone.</summary>
            public readonly HumanBone Id;
            /// <summary>Its parent bone, <see cref="HumanBone.LastBone"/> (the avatar root) for Hips.</summary>
            public readonly HumanBone Parent;
            /// <summary>Offset from the parent (for Hips: from the root on the floor), identity rotations.</summary>
            public readonly Vec3 LocalPosition;
            /// <summary>Position relative to the avatar root.</summary>
            public readonly Vec3 RootPosition;

            internal Bone(HumanBone id, HumanBone parent, Vec3 local, Vec3 root)
            {
                Id = id;
                Parent = parent;
                LocalPosition = local;
                RootPosition = root;
            }
        }

        /// <summary>The 22 driven bones, parents first, for <paramref name="skeleton"/>.</summary>
        public static Bone[] FromSkeleton(SmplSkeleton skeleton)
        {
            var bones = new List<Bone>(HumanoidBoneMap.MappedJointCount);
            foreach (HumanBone b in HumanoidBoneMap.MappedBones)
            {
                int j = HumanoidBoneMap.ToSmplJoint(b);
                int p = SmplSkeleton.ParentOf(j);
                HumanBone parent = p < 0 ? HumanBone.LastBone : HumanoidBoneMap.ToHumanBone((SmplJoint)p);
                bones.Add(new Bone(b, parent, CoordinateConversion.ModelToUnity(skeleton.RestOffset(j)),
                                   CoordinateConversion.ModelToUnity(skeleton.RestPosition(j))));
            }
            return bones.ToArray();
        }

        /// <summary>The rig description of <see cref="FromSkeleton"/> (identity rest rotations: a T-pose).</summary>
        public static HumanoidRig ToRig(Bone[] bones)
        {
            var rig = new List<RigBone>(bones.Length);
            foreach (var b in bones)
                rig.Add(new RigBone(b.Id, b.Parent, Quat.Identity, Quat.Identity, b.RootPosition));
            return new HumanoidRig(rig);
        }
    }

    /// <summary>Where an avatar's root motion goes (the Unity glue's choice, decided here).</summary>
    public enum RootMotionMode
    {
        /// <summary>The Hips stay above the root; only their height follows the pose.</summary>
        InPlace = 0,
        /// <summary>The Hips carry the whole motion; the avatar's root stays where it is.</summary>
        MoveHips = 1,
        /// <summary>The root travels horizontally; the Hips keep their rest spot above it and follow the height.</summary>
        MoveRoot = 2,
    }

    /// <summary>Splits the retargeted Hips position into a Hips position and a root translation.</summary>
    public static class RootMotion
    {
        /// <summary>
        /// For retargeted rig-space <paramref name="hips"/> and the rig's rest Hips position:
        /// the Hips position to set (rig space) and the horizontal translation of the root
        /// (rig space, Y = 0; zero unless <see cref="RootMotionMode.MoveRoot"/>).
        /// </summary>
        public static void Split(RootMotionMode mode, Vec3 hips, Vec3 restHips, out Vec3 hipsPosition, out Vec3 rootTranslation)
        {
            switch (mode)
            {
                case RootMotionMode.MoveHips:
                    hipsPosition = hips;
                    rootTranslation = Vec3.Zero;
                    break;
                case RootMotionMode.MoveRoot:
                    hipsPosition = new Vec3(restHips.X, hips.Y, restHips.Z);
                    rootTranslation = new Vec3(hips.X - restHips.X, 0f, hips.Z - restHips.Z);
                    break;
                default:
                    hipsPosition = new Vec3(restHips.X, hips.Y, restHips.Z);
                    rootTranslation = Vec3.Zero;
                    break;
            }
        }
    }

    /// <summary>Joint drive targets for physics joints (ArticulationBody spherical joints).</summary>
    public static class DriveTargets
    {
        /// <summary>
        /// The rotation vector (axis times angle, degrees) of <paramref name="relative"/>, the
        /// joint's rotation from its rest in the joint frame: the X component is the twist target,
        /// Y and Z the swing targets of a spherical joint. The shorter way round (|angle| &lt;= 180).
        /// </summary>
        public static Vec3 RotationVectorDegrees(Quat relative)
        {
            Quat q = relative.Normalized;
            if (q.W < 0f) q = new Quat(-q.X, -q.Y, -q.Z, -q.W);
            float s = System.MathF.Sqrt(q.X * q.X + q.Y * q.Y + q.Z * q.Z);
            if (s < 1e-7f) return new Vec3(2f * q.X, 2f * q.Y, 2f * q.Z) * (180f / System.MathF.PI);
            float angle = 2f * System.MathF.Atan2(s, q.W) * (180f / System.MathF.PI);
            return new Vec3(q.X, q.Y, q.Z) * (angle / s);
        }
    }
}
