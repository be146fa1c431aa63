using System;
using System.Collections.Generic;
using System.Globalization;
using Mocap.Imu.Maths;

namespace Mocap.Imu.Skeleton
{
    /// <summary>
    /// The model's 24-joint SMPL-topology skeleton: names, parents and rest offsets, all in the
    /// model frame (right-handed, Y up, the character faces +Z, X is the character's left; metres),
    /// plus forward kinematics. Immutable.
    /// </summary>
    /// <remarks>
    /// Names and parents are fixed by model contract version 1; only the proportions (rest offsets)
    /// vary between models. At rest every joint rotation is identity and every bone frame is
    /// parallel to the model frame (a T-pose: arms along +-X, legs down -Y).
    /// </remarks>
    public sealed class SmplSkeleton
    {
        /// <summary>Number of joints.</summary>
        public const int JointCount = 24;

        /// <summary>Metadata key holding the 24 comma-separated joint names.</summary>
        public const string JointNamesKey = "mocap.joint_names";
        /// <summary>Metadata key holding the 24 comma-separated parent indices (-1 for the root).</summary>
        public const string JointParentsKey = "mocap.joint_parents";
        /// <summary>Metadata key holding the 72 comma-separated rest offset components.</summary>
        public const string RestOffsetsKey = "mocap.rest_offsets";

        private static readonly string[] ContractNames =
        {
            "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
            "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck",
            "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder",
            "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hand", "right_hand",
        };

        private static readonly int[] ContractParents =
        {
            -1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21,
        };

        // Shortest bone we accept from metadata. Bone directions feed the retargeter; a zero-length
        // bone has none, and anything under a millimetre is a broken export rather than anatomy.
        private const float MinBoneLength = 1e-3f;

        private readonly Vec3[] _offsets;
        private readonly Vec3[] _restPositions;

        private SmplSkeleton(Vec3[] offsets)
        {
            _offsets = offsets;
            _restPositions = new Vec3[JointCount];
            _restPositions[0] = offsets[0];
            for (int j = 1; j < JointCount; j++)
                _restPositions[j] = _restPositions[ContractParents[j]] + offsets[j];
        }

        /// <summary>The contract's joint names, index = joint number.</summary>
        public static IReadOnlyList<string> JointNames => ContractNames;

        /// <summary>The contract's parent indices, -1 for the root.</summary>
        public static IReadOnlyList<int> Parents => ContractParents;

        /// <summary>
        /// The project's default proportions (an adult of 1.75 m, training/skeleton.py's
        /// DEFAULT_OFFSETS), for tests and for use before a model is loaded.
        /// </summary>
        public static SmplSkeleton Default { get; } = new SmplSkeleton(DefaultOffsets());

        /// <summary>The parent of <paramref name="joint"/>, -1 for the pelvis.</summary>
        public static int ParentOf(int joint) => ContractParents[joint];

        /// <summary>The contract name of <paramref name="joint"/> (e.g. "left_wrist").</summary>
        public static string NameOf(int joint) => ContractNames[joint];

        /// <summary>The joint with contract name <paramref name="name"/>, or -1.</summary>
        public static int IndexOf(string name) => Array.IndexOf(ContractNames, name);

        /// <summary>
        /// Joint <paramref name="joint"/>'s offset from its parent at rest, model frame, metres.
        /// Joint 0's offset is the pelvis position at rest (its height above the floor).
        /// </summary>
        public Vec3 RestOffset(int joint) => _offsets[joint];

        /// <summary>
        /// Whether <paramref name="other"/> has exactly these rest offsets: a character retargeted
        /// for one needs no rebuild for the other (the same model file opened again).
        /// </summary>
        public bool HasSameProportions(SmplSkeleton other)
        {
            if (other == null) return false;
            if (ReferenceEquals(other, this)) return true;
            for (int j = 0; j < JointCount; j++)
            {
                Vec3 a = _offsets[j], b = other._offsets[j];
                if (a.X != b.X || a.Y != b.Y || a.Z != b.Z) return false;
            }
            return true;
        }

        /// <summary>Joint <paramref name="joint"/>'s position at rest, model frame, floor at y = 0.</summary>
        public Vec3 RestPosition(int joint) => _restPositions[joint];

        /// <summary>
        /// Creates a skeleton with the given rest offsets (24, model frame, metres).
        /// </summary>
        /// <exception cref="ArgumentException">Not 24 offsets, a non-finite value, a non-positive pelvis height or a bone shorter than 1 mm.</exception>
        public static SmplSkeleton FromRestOffsets(IReadOnlyList<Vec3> offsets)
        {
            if (offsets == null) throw new ArgumentNullException(nameof(offsets));
            string error = ValidateOffsets(offsets);
            if (error != null) throw new ArgumentException(error, nameof(offsets));
            var copy = new Vec3[JointCount];
            for (int j = 0; j < JointCount; j++) copy[j] = offsets[j];
            return new SmplSkeleton(copy);
        }

        /// <summary>
        /// Reads the skeleton from the model's metadata (<c>mocap.joint_names</c>, <c>mocap.joint_parents</c>,
        /// <c>mocap.rest_offsets</c>; comma-separated strings) and checks it against the contract.
        /// </summary>
        /// <exception cref="FormatException">
        /// A key is missing, a value does not parse, the names or parents differ from the contract, or
        /// an offset is unusable; the message names the key and the first difference.
        /// </exception>
        public static SmplSkeleton FromMetadata(IReadOnlyDictionary<string, string> metadata)
        {
            if (metadata == null) throw new ArgumentNullException(nameof(metadata));

            string[] names = SplitList(metadata, JointNamesKey, JointCount);
            for (int j = 0; j < JointCount; j++)
            {
                if (names[j] != ContractNames[j])
                    throw new FormatException(
                        $"{JointNamesKey}: joint {j} is '{names[j]}', the contract expects '{ContractNames[j]}'");
            }

            string[] parents = SplitList(metadata, JointParentsKey, JointCount);
            for (int j = 0; j < JointCount; j++)
            {
                if (!int.TryParse(parents[j], NumberStyles.AllowLeadingSign, CultureInfo.InvariantCulture, out int p))
                    throw new FormatException($"{JointParentsKey}: item {j} '{parents[j]}' is not an integer");
                if (p != ContractParents[j])
                    throw new FormatException(
                        $"{JointParentsKey}: joint {j} ({ContractNames[j]}) has parent {p}, the contract expects {ContractParents[j]}");
            }

            string[] numbers = SplitList(metadata, RestOffsetsKey, 3 * JointCount);
            var values = new float[3 * JointCount];
            for (int i = 0; i < values.Length; i++)
            {
                if (!float.TryParse(numbers[i], NumberStyles.Float, CultureInfo.InvariantCulture, out values[i]) ||
                    !float.IsFinite(values[i]))
                    throw new FormatException(
                        $"{RestOffsetsKey}: item {i} (joint {i / 3} {ContractNames[i / 3]}, {"xyz"[i % 3]}) '{numbers[i]}' is not a finite number");
            }
            var offsets = new Vec3[JointCount];
            for (int j = 0; j < JointCount; j++)
                offsets[j] = new Vec3(values[3 * j], values[3 * j + 1], values[3 * j + 2]);
            string error = ValidateOffsets(offsets);
            if (error != null) throw new FormatException($"{RestOffsetsKey}: {error}");
            return new SmplSkeleton(offsets);
        }

        /// <summary>
        /// Forward kinematics in the model frame. <paramref name="localRotations"/> follow the contract
        /// (joint 0 global, the others relative to their parent and to the rest pose);
        /// <paramref name="rootPosition"/> is the pelvis position. Writes each joint's global rotation
        /// and position. Allocates nothing.
        /// </summary>
        /// <exception cref="ArgumentException">A span shorter than 24.</exception>
        public void ForwardKinematics(ReadOnlySpan<Quat> localRotations, Vec3 rootPosition,
            Span<Quat> globalRotations, Span<Vec3> positions)
        {
            if (localRotations.Length < JointCount || globalRotations.Length < JointCount || positions.Length < JointCount)
                throw new ArgumentException("forward kinematics needs spans of 24 joints");
            globalRotations[0] = localRotations[0];
            positions[0] = rootPosition;
            for (int j = 1; j < JointCount; j++)
            {
                int p = ContractParents[j];
                // Rotations are renormalised on the way down so float round-off cannot accumulate
                // over the six-deep chains into visibly scaled bones.
                globalRotations[j] = (globalRotations[p] * localRotations[j]).Normalized;
                positions[j] = positions[p] + globalRotations[p] * _offsets[j];
            }
        }

        private static string[] SplitList(IReadOnlyDictionary<string, string> metadata, string key, int count)
        {
            if (!metadata.TryGetValue(key, out string raw) || raw == null)
                throw new FormatException($"metadata key '{key}' is missing");
            string[] items = raw.Split(',');
            if (items.Length != count)
                throw new FormatException($"{key}: expected {count} comma-separated items, got {items.Length}");
            for (int i = 0; i < items.Length; i++) items[i] = items[i].Trim();
            return items;
        }

        private static string ValidateOffsets(IReadOnlyList<Vec3> offsets)
        {
            if (offsets.Count != JointCount) return $"expected {JointCount} offsets, got {offsets.Count}";
            for (int j = 0; j < JointCount; j++)
            {
                if (!offsets[j].IsFinite) return $"joint {j} ({ContractNames[j]}) offset {offsets[j]} is not finite";
                if (j > 0 && offsets[j].Length < MinBoneLength)
                    return $"joint {j} ({ContractNames[j]}) offset {offsets[j]} is shorter than {MinBoneLength} m";
            }
            // The pelvis height scales root motion onto rigs; zero or below-floor is unusable.
            if (!(offsets[0].Y > 0f)) return $"joint 0 (pelvis) height {offsets[0].Y} must be above the floor (> 0)";
            return null;
        }

        private static Vec3[] DefaultOffsets()
        {
            // training/skeleton.py DEFAULT_OFFSETS (stature 1.75 m; see its comments for sources).
            const float H = 1.75f, pelvisY = 0.93f, hipY = 0.87f;
            const float kneeY = 0.285f * H, ankleY = 0.039f * H, shoulderY = 0.818f * H;
            const float upperArm = 0.186f * H, forearm = 0.146f * H, hand = 0.45f * 0.108f * H;
            const float footFwd = 0.53f * 0.152f * H, ballY = 0.02f;
            return new[]
            {
                new Vec3(0f, pelvisY, 0f),
                new Vec3(0.085f, hipY - pelvisY, 0f),
                new Vec3(-0.085f, hipY - pelvisY, 0f),
                new Vec3(0f, 0.11f, 0f),
                new Vec3(0f, kneeY - hipY, 0f),
                new Vec3(0f, kneeY - hipY, 0f),
                new Vec3(0f, 0.13f, 0f),
                new Vec3(0f, ankleY - kneeY, 0f),
                new Vec3(0f, ankleY - kneeY, 0f),
                new Vec3(0f, 0.12f, 0f),
                new Vec3(0f, ballY - ankleY, footFwd),
                new Vec3(0f, ballY - ankleY, footFwd),
                new Vec3(0f, 0.16f, 0f),
                new Vec3(0.07f, 0.11f, 0f),
                new Vec3(-0.07f, 0.11f, 0f),
                new Vec3(0f, 0.10f, 0f),
                new Vec3(0.11f, shoulderY - 1.40f, 0f),
                new Vec3(-0.11f, shoulderY - 1.40f, 0f),
                new Vec3(upperArm, 0f, 0f),
                new Vec3(-upperArm, 0f, 0f),
                new Vec3(forearm, 0f, 0f),
                new Vec3(-forearm, 0f, 0f),
                new Vec3(hand, 0f, 0f),
                new Vec3(-hand, 0f, 0f),
            };
        }
    }
}
