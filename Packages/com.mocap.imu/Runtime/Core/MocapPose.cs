using System;
using System.Runtime.InteropServices;
using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu
{
    /// <summary>Flags of a solved pose (MOCAP_POSE_*).</summary>
    [Flags]
    public enum MocapPoseFlags : uint
    {
        None = 0,
        /// <summary>The left foot is planted (its contact probability passed the threshold).</summary>
        ContactLeft = 1u << 0,
        /// <summary>The right foot is planted.</summary>
        ContactRight = 1u << 1,
        /// <summary>Drift correction moved the root this frame.</summary>
        Corrected = 1u << 2,
        /// <summary>Some sensor was held or stale in the input frame.</summary>
        Incomplete = 1u << 3,
    }

    /// <summary>
    /// One solved pose of one character (mocap_pose), in the model frame (right-handed, Y up, the
    /// character faces +Z; metres, seconds). Blittable: the solver copies poses straight into a
    /// caller's <see cref="MocapPose"/> or array of them, so polling allocates nothing.
    /// </summary>
    /// <remarks>
    /// The storage is the layout mirror <see cref="NativePose"/> (checked field by field against
    /// the engine's mocap_struct_layout by NativeLayoutTests); this type adds the public view.
    /// Rotations follow the model contract: joint 0 global, every other joint local to its parent
    /// and relative to the T-pose rest (see <see cref="SmplSkeleton"/>).
    /// </remarks>
    [StructLayout(LayoutKind.Sequential)]
    public unsafe struct MocapPose
    {
        /// <summary>Joints per pose (MOCAP_JOINT_COUNT).</summary>
        public const int JointCount = NativeSolverMethods.JointCount;

        // The only field, so a MocapPose is byte for byte a mocap_pose.
        internal NativePose Native;

        /// <summary>0, 1, 2 ... per character.</summary>
        public ulong Sequence { get => Native.Sequence; set => Native.Sequence = value; }

        /// <summary>The session frame the pose was solved from.</summary>
        public ulong FrameSequence { get => Native.FrameSequence; set => Native.FrameSequence = value; }

        /// <summary>That frame's time on the session clock, seconds.</summary>
        public double TimeSeconds { get => Native.TimeSeconds; set => Native.TimeSeconds = value; }

        /// <summary>The character index the solver gave the session.</summary>
        public int Character { get => (int)Native.Character; set => Native.Character = (uint)value; }

        /// <summary>Contact, drift-correction and input-quality flags.</summary>
        public MocapPoseFlags Flags { get => (MocapPoseFlags)Native.Flags; set => Native.Flags = (uint)value; }

        /// <summary>Pelvis position, model frame, metres (after drift correction).</summary>
        public Vec3 RootPosition
        {
            get => new Vec3(Native.RootPosition[0], Native.RootPosition[1], Native.RootPosition[2]);
            set { Native.RootPosition[0] = value.X; Native.RootPosition[1] = value.Y; Native.RootPosition[2] = value.Z; }
        }

        /// <summary>Root velocity as the model predicted it, m/s, model frame.</summary>
        public Vec3 RootVelocity
        {
            get => new Vec3(Native.RootVelocity[0], Native.RootVelocity[1], Native.RootVelocity[2]);
            set { Native.RootVelocity[0] = value.X; Native.RootVelocity[1] = value.Y; Native.RootVelocity[2] = value.Z; }
        }

        /// <summary>Left foot contact probability, 0..1.</summary>
        public float LeftFootContact { get => Native.FootContact[0]; set => Native.FootContact[0] = value; }

        /// <summary>Right foot contact probability, 0..1.</summary>
        public float RightFootContact { get => Native.FootContact[1]; set => Native.FootContact[1] = value; }

        /// <summary>Session clock (ns) when the bytes that fed the input frame arrived.</summary>
        public long NewestReceiveNs { get => Native.NewestReceiveNs; set => Native.NewestReceiveNs = value; }

        /// <summary>Session clock (ns) when the input frame was assembled.</summary>
        public long FrameEmittedNs { get => Native.FrameEmittedNs; set => Native.FrameEmittedNs = value; }

        /// <summary>Session clock (ns) when the pose became available (latency = this - <see cref="NewestReceiveNs"/>).</summary>
        public long PoseEmittedNs { get => Native.PoseEmittedNs; set => Native.PoseEmittedNs = value; }

        /// <summary>
        /// Rotation of a joint: global (model frame) for joint 0, local to the parent for the others.
        /// </summary>
        public Quat GetJointRotation(int joint)
        {
            int o = 4 * CheckJoint(joint);
            // The engine stores (w, x, y, z).
            return Quat.FromWxyz(Native.JointRotations[o], Native.JointRotations[o + 1],
                                 Native.JointRotations[o + 2], Native.JointRotations[o + 3]);
        }

        /// <summary>Rotation of a joint (see <see cref="GetJointRotation(int)"/>).</summary>
        public Quat GetJointRotation(SmplJoint joint) => GetJointRotation((int)joint);

        /// <summary>Set a joint rotation (for poses built from recordings or tests).</summary>
        public void SetJointRotation(int joint, Quat rotation)
        {
            int o = 4 * CheckJoint(joint);
            Native.JointRotations[o] = rotation.W;
            Native.JointRotations[o + 1] = rotation.X;
            Native.JointRotations[o + 2] = rotation.Y;
            Native.JointRotations[o + 3] = rotation.Z;
        }

        /// <summary>World position of a joint, model frame, metres (the engine's forward kinematics).</summary>
        public Vec3 GetJointPosition(int joint)
        {
            int o = 3 * CheckJoint(joint);
            return new Vec3(Native.JointPositions[o], Native.JointPositions[o + 1], Native.JointPositions[o + 2]);
        }

        /// <summary>World position of a joint (see <see cref="GetJointPosition(int)"/>).</summary>
        public Vec3 GetJointPosition(SmplJoint joint) => GetJointPosition((int)joint);

        /// <summary>Set a joint's world position (for poses built from recordings or tests).</summary>
        public void SetJointPosition(int joint, Vec3 position)
        {
            int o = 3 * CheckJoint(joint);
            Native.JointPositions[o] = position.X;
            Native.JointPositions[o + 1] = position.Y;
            Native.JointPositions[o + 2] = position.Z;
        }

        /// <summary>
        /// Copy the rotations and root position into <paramref name="target"/> (the skeleton code's
        /// reusable pose). Allocates nothing.
        /// </summary>
        public void CopyTo(SmplPose target)
        {
            if (target == null) throw new ArgumentNullException(nameof(target));
            var rotations = target.Rotations;
            for (int j = 0; j < JointCount; j++)
            {
                int o = 4 * j;
                rotations[j] = Quat.FromWxyz(Native.JointRotations[o], Native.JointRotations[o + 1],
                                             Native.JointRotations[o + 2], Native.JointRotations[o + 3]);
            }
            target.RootPosition = RootPosition;
        }

        static int CheckJoint(int joint)
        {
            // Unsigned compare: one branch for both bounds; the fixed buffers are not range checked.
            if ((uint)joint >= JointCount)
                throw new ArgumentOutOfRangeException(nameof(joint), joint, "a pose has joints 0..23");
            return joint;
        }
    }
}
