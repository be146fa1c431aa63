using System;
using System.Collections.Generic;
using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu.Retarget
{
    /// <summary>
    /// A validated target rig: the humanoid bones the SMPL pose drives that the rig has, parents
    /// before children. Immutable.
    /// </summary>
    public sealed class HumanoidRig
    {
        private readonly RigBone[] _bones;
        private readonly int[] _parentIndex;
        private readonly int[] _indexOfBone;

        /// <summary>
        /// Validates and orders <paramref name="bones"/>. Bones the SMPL pose does not drive (eyes,
        /// jaw, fingers) are rejected so a caller notices it passed the wrong list.
        /// </summary>
        /// <exception cref="ArgumentException">
        /// A required bone is missing, a bone is listed twice or is not driven, a parent is absent
        /// or is not an ancestor in the humanoid hierarchy, or a value is not finite.
        /// </exception>
        public HumanoidRig(IEnumerable<RigBone> bones)
        {
            if (bones == null) throw new ArgumentNullException(nameof(bones));
            var byBone = new RigBone?[(int)HumanBone.LastBone];
            foreach (RigBone b in bones)
            {
                if (HumanoidBoneMap.ToSmplJoint(b.Bone) < 0)
                    throw new ArgumentException($"{b.Bone} is not driven by the SMPL pose; leave it out of the rig description");
                if (byBone[(int)b.Bone] != null) throw new ArgumentException($"{b.Bone} is listed twice");
                if (!b.RestLocalRotation.IsFinite || !b.RestRotation.IsFinite || !b.RestPosition.IsFinite)
                    throw new ArgumentException($"{b.Bone} has a non-finite rest value");
                if (b.RestLocalRotation.LengthSquared < 1e-6f || b.RestRotation.LengthSquared < 1e-6f)
                    throw new ArgumentException($"{b.Bone} has a zero rest rotation quaternion");
                byBone[(int)b.Bone] = new RigBone(b.Bone, b.Parent, b.RestLocalRotation.Normalized,
                    b.RestRotation.Normalized, b.RestPosition);
            }

            var missing = new List<string>();
            foreach (HumanBone m in HumanoidBoneMap.MappedBones)
                if (!HumanoidBoneMap.IsOptional(m) && byBone[(int)m] == null) missing.Add(m.ToString());
            if (missing.Count > 0) throw new ArgumentException("the rig lacks required bones: " + string.Join(", ", missing));

            // Canonical order (SMPL joint order) is topological for any rig whose parents are
            // humanoid ancestors, which is checked below.
            var ordered = new List<RigBone>();
            foreach (HumanBone m in HumanoidBoneMap.MappedBones)
                if (byBone[(int)m] != null) ordered.Add(byBone[(int)m].Value);
            _bones = ordered.ToArray();
            _indexOfBone = new int[(int)HumanBone.LastBone];
            for (int i = 0; i < _indexOfBone.Length; i++) _indexOfBone[i] = -1;
            for (int i = 0; i < _bones.Length; i++) _indexOfBone[(int)_bones[i].Bone] = i;

            _parentIndex = new int[_bones.Length];
            for (int i = 0; i < _bones.Length; i++)
            {
                RigBone b = _bones[i];
                if (b.Bone == HumanBone.Hips)
                {
                    if (b.Parent != HumanBone.LastBone)
                        throw new ArgumentException($"Hips is the root of the humanoid; its parent must be LastBone, got {b.Parent}");
                    _parentIndex[i] = -1;
                    continue;
                }
                int p = (int)b.Parent >= 0 && (int)b.Parent < _indexOfBone.Length ? _indexOfBone[(int)b.Parent] : -1;
                if (p < 0) throw new ArgumentException($"{b.Bone}'s parent {b.Parent} is not in the rig description");
                if (!IsAncestorJoint(HumanoidBoneMap.ToSmplJoint(b.Parent), HumanoidBoneMap.ToSmplJoint(b.Bone)))
                    throw new ArgumentException($"{b.Bone}'s parent {b.Parent} is not above it in the humanoid hierarchy");
                _parentIndex[i] = p;
            }
        }

        /// <summary>Number of bones described.</summary>
        public int Count => _bones.Length;

        /// <summary>Bone <paramref name="index"/> (0 is Hips; parents come before children).</summary>
        public RigBone this[int index] => _bones[index];

        /// <summary>Index of <paramref name="index"/>'s parent bone, -1 for Hips.</summary>
        public int ParentIndex(int index) => _parentIndex[index];

        /// <summary>Index of <paramref name="bone"/> in this rig, or -1 when the rig lacks it.</summary>
        public int IndexOf(HumanBone bone) =>
            (int)bone >= 0 && (int)bone < _indexOfBone.Length ? _indexOfBone[(int)bone] : -1;

        /// <summary>Whether the rig has <paramref name="bone"/>.</summary>
        public bool Has(HumanBone bone) => IndexOf(bone) >= 0;

        private static bool IsAncestorJoint(int ancestor, int joint)
        {
            for (int j = SmplSkeleton.ParentOf(joint); j >= 0; j = SmplSkeleton.ParentOf(j))
                if (j == ancestor) return true;
            return false;
        }
    }
}
