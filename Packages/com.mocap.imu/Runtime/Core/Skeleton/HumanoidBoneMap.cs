using System;
using System.Collections.Generic;

namespace Mocap.Imu.Skeleton
{
    /// <summary>
    /// Which Unity humanoid bone each SMPL joint drives, and which of those bones a rig may lack.
    /// </summary>
    /// <remarks>
    /// <para>A SMPL joint's rotation turns the bone that starts at that joint, which is the Unity bone
    /// of the same place: pelvis -> Hips, spine1/2/3 -> Spine/Chest/UpperChest, neck -> Neck,
    /// head -> Head, collar -> Shoulder, shoulder -> UpperArm, elbow -> LowerArm, wrist -> Hand,
    /// hip -> UpperLeg, knee -> LowerLeg, ankle -> Foot, foot -> Toes.</para>
    /// <para>left_hand / right_hand drive no bone. They are the knuckles, the end point of the Hand
    /// bone (whose rotation is the wrist's); their own rotation would curl all fingers at once, and
    /// six sensors carry no finger information, so the model's value there is a guess we do not
    /// show. The fingers keep their rest pose.</para>
    /// <para>Optional bones follow Unity's Avatar rules (15 bones required): Chest, UpperChest, Neck,
    /// LeftShoulder/RightShoulder and LeftToes/RightToes may be missing on a rig;
    /// <see cref="Retarget.RestPoseRetargeter"/> folds the missing joints into the remaining ones.</para>
    /// </remarks>
    public static class HumanoidBoneMap
    {
        /// <summary>Number of SMPL joints that drive a bone (all but the two hand end points).</summary>
        public const int MappedJointCount = 22;

        // The engine owns the map (mocap_humanoid_bone_name): the VMC stream and this driver must
        // never disagree on which bone a joint turns.
        private static readonly HumanBone[] JointToBone = ReadEngineMap();

        // The joint that continues each joint's bone along the body: the end point that gives a
        // bone its direction when several children exist (spine3 -> neck, not the collars) and the
        // chain to follow when a rig lacks the next bone. -1: the bone's end is not a joint we drive.
        private static readonly int[] ChainSuccessor =
        {
            3, 4, 5, 6, 7, 8, 9, 10, 11, 12, -1, -1, 15, 16, 17, -1, 18, 19, 20, 21, 22, 23, -1, -1,
        };

        private static readonly int[] BoneToJoint = BuildBoneToJoint();
        private static readonly HumanBone[] Mapped = BuildMapped();

        /// <summary>
        /// The humanoid bone SMPL joint <paramref name="joint"/> drives, or <see cref="HumanBone.LastBone"/>
        /// for the two hand end points, which drive none.
        /// </summary>
        public static HumanBone ToHumanBone(SmplJoint joint) => JointToBone[CheckJoint((int)joint)];

        /// <summary>Whether <paramref name="joint"/> drives a humanoid bone.</summary>
        public static bool IsMapped(SmplJoint joint) => ToHumanBone(joint) != HumanBone.LastBone;

        /// <summary>The SMPL joint that drives <paramref name="bone"/>, or -1 when none does (eyes, jaw, fingers).</summary>
        public static int ToSmplJoint(HumanBone bone)
        {
            int i = (int)bone;
            return i >= 0 && i < BoneToJoint.Length ? BoneToJoint[i] : -1;
        }

        /// <summary>The 22 bones the SMPL pose drives, parents before children.</summary>
        public static IReadOnlyList<HumanBone> MappedBones => Mapped;

        /// <summary>
        /// Whether a Unity Avatar may lack <paramref name="bone"/>. Of the bones we drive these are
        /// Chest, UpperChest, Neck, the shoulders and the toes.
        /// </summary>
        public static bool IsOptional(HumanBone bone) => bone switch
        {
            HumanBone.Hips or HumanBone.Spine or HumanBone.Head or
            HumanBone.LeftUpperLeg or HumanBone.RightUpperLeg or HumanBone.LeftLowerLeg or HumanBone.RightLowerLeg or
            HumanBone.LeftFoot or HumanBone.RightFoot or
            HumanBone.LeftUpperArm or HumanBone.RightUpperArm or HumanBone.LeftLowerArm or HumanBone.RightLowerArm or
            HumanBone.LeftHand or HumanBone.RightHand => false,
            _ => true,
        };

        /// <summary>The humanoid bone's name: Unity's <c>HumanBodyBones</c> name, also the VMC bone name.</summary>
        public static string Name(HumanBone bone) => bone.ToString();

        /// <summary>Parses a <c>HumanBodyBones</c> name (case-sensitive, as VMC sends it).</summary>
        public static bool TryParse(string name, out HumanBone bone)
        {
            // Enum.TryParse would also accept numbers and comma lists; VMC names are exact words.
            for (int i = 0; i < (int)HumanBone.LastBone; i++)
            {
                if (string.Equals(((HumanBone)i).ToString(), name, StringComparison.Ordinal))
                {
                    bone = (HumanBone)i;
                    return true;
                }
            }
            bone = HumanBone.LastBone;
            return false;
        }

        /// <summary>
        /// The joint that continues <paramref name="joint"/>'s bone along the body (pelvis -> spine1,
        /// spine3 -> neck, wrist -> hand end point), or -1 at the end of a chain (head, toes).
        /// </summary>
        public static int ChainChild(SmplJoint joint) => ChainSuccessor[CheckJoint((int)joint)];

        private static int CheckJoint(int j)
        {
            if (j < 0 || j >= SmplSkeleton.JointCount)
                throw new ArgumentOutOfRangeException(nameof(j), j, "SMPL joint index must be 0..23");
            return j;
        }

        private static HumanBone[] ReadEngineMap()
        {
            var map = new HumanBone[SmplSkeleton.JointCount];
            int mapped = 0;
            for (int j = 0; j < map.Length; j++)
            {
                IntPtr text;
                try { text = NativeMethods.mocap_humanoid_bone_name(j); }
                catch (EntryPointNotFoundException)
                {
                    throw new MocapException(MocapStatus.Unsupported,
                        $"the native library {NativeMethods.Library} has no mocap_humanoid_bone_name (API 5.1 or newer needed)");
                }
                if (text == IntPtr.Zero) { map[j] = HumanBone.LastBone; continue; }
                string name = NativeText.FromPointer(text);
                if (!TryParse(name, out map[j]))
                    throw new MocapException(MocapStatus.Format,
                        $"the engine maps SMPL joint {j} to '{name}', which is no humanoid bone");
                mapped++;
            }
            if (mapped != MappedJointCount)
                throw new MocapException(MocapStatus.Format,
                    $"the engine maps {mapped} SMPL joints to humanoid bones; these bindings expect {MappedJointCount}");
            return map;
        }

        private static int[] BuildBoneToJoint()
        {
            var map = new int[(int)HumanBone.LastBone];
            for (int i = 0; i < map.Length; i++) map[i] = -1;
            for (int j = 0; j < JointToBone.Length; j++)
                if (JointToBone[j] != HumanBone.LastBone) map[(int)JointToBone[j]] = j;
            return map;
        }

        private static HumanBone[] BuildMapped()
        {
            // SMPL joint order lists parents before children, so this order is topological too.
            var list = new List<HumanBone>(MappedJointCount);
            foreach (HumanBone b in JointToBone)
                if (b != HumanBone.LastBone) list.Add(b);
            return list.ToArray();
        }
    }
}
