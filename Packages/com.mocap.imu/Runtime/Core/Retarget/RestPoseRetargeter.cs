using System;
using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu.Retarget
{
    /// <summary>
    /// Drives a humanoid rig from SMPL poses, whatever the rig's rest orientations: each bone's
    /// rig-space rotation becomes (the SMPL joint's global rotation since the T-pose, in Unity's
    /// frame) * (the bone's T-pose rotation), then turns into the local rotation its transform needs.
    /// </summary>
    /// <remarks>
    /// <para>Working with world-space deltas from the T-pose is what makes any rig work: a bone's
    /// own axes (Mixamo's Y along the bone, VRM's identity, Blender's roll) never enter the delta,
    /// and its direction after retargeting is the SMPL bone's direction whatever its rest rotation.</para>
    /// <para>Missing optional bones: every present bone's rig-space rotation is set directly, so
    /// the children of a missing bone still point right. A bone whose end lies past a missing bone
    /// (Chest without UpperChest reaches to the neck; UpperChest without Neck reaches to the head)
    /// takes its SMPL joint's rotation plus the smallest extra turn that points it where the SMPL
    /// joints it spans point, which folds the missing joint's bend into it.</para>
    /// <para>Per frame nothing is allocated: every buffer is made in the constructor.</para>
    /// </remarks>
    public sealed class RestPoseRetargeter
    {
        private readonly SmplSkeleton _skeleton;
        private readonly HumanoidRig _rig;

        // Per rig bone, fixed at construction.
        private readonly int[] _joint;          // SMPL joint driving the bone
        private readonly int[] _endJoint;       // SMPL joint at the bone's end when it spans a missing bone, else -1
        private readonly Vec3[] _restSpan;      // Unity frame: SMPL rest vector joint -> end joint (when spanning)
        private readonly Quat[] _tPose;         // the bone's rig-space rotation in the T-pose
        private readonly Quat[] _restToParent;  // rest rotation of the transform parent relative to the humanoid parent (or rig space for Hips)
        private readonly Vec3 _hipsRestPosition;

        // Per frame.
        private readonly Quat[] _smplGlobal = new Quat[SmplSkeleton.JointCount];
        private readonly Vec3[] _smplPositions = new Vec3[SmplSkeleton.JointCount];
        private readonly Quat[] _rotation;
        private readonly Quat[] _local;

        /// <summary>
        /// Prepares retargeting from <paramref name="skeleton"/> onto <paramref name="rig"/>.
        /// </summary>
        /// <param name="skeleton">The model's skeleton (rest offsets give SMPL's T-pose directions).</param>
        /// <param name="rig">The target rig at rest.</param>
        /// <param name="restPose">Whether the rig's described rest is already a T-pose.</param>
        public RestPoseRetargeter(SmplSkeleton skeleton, HumanoidRig rig, RigRestPose restPose = RigRestPose.TPose)
        {
            _skeleton = skeleton ?? throw new ArgumentNullException(nameof(skeleton));
            _rig = rig ?? throw new ArgumentNullException(nameof(rig));
            int n = rig.Count;
            _joint = new int[n];
            _endJoint = new int[n];
            _restSpan = new Vec3[n];
            _tPose = new Quat[n];
            _restToParent = new Quat[n];
            _rotation = new Quat[n];
            _local = new Quat[n];

            var endBone = new int[n]; // rig index of the bone at this bone's end, -1 for none
            for (int i = 0; i < n; i++)
            {
                RigBone b = rig[i];
                _joint[i] = HumanoidBoneMap.ToSmplJoint(b.Bone);
                endBone[i] = -1;
                _endJoint[i] = -1;
                // Follow the body's chain from this joint to the first joint whose bone the rig has.
                for (int j = HumanoidBoneMap.ChainChild((SmplJoint)_joint[i]); j >= 0; j = HumanoidBoneMap.ChainChild((SmplJoint)j))
                {
                    int k = rig.IndexOf(HumanoidBoneMap.ToHumanBone((SmplJoint)j));
                    if (k < 0) continue;
                    endBone[i] = k;
                    if (j != HumanoidBoneMap.ChainChild((SmplJoint)_joint[i]))
                    {
                        _endJoint[i] = j;
                        _restSpan[i] = CoordinateConversion.ModelToUnity(skeleton.RestPosition(j) - skeleton.RestPosition(_joint[i]));
                    }
                    break;
                }

                int p = rig.ParentIndex(i);
                // The transform parent's rest rotation is RestRotation * RestLocal^-1; relative to the
                // humanoid parent it never changes, because in-between transforms are not animated.
                Quat transformParent = b.RestRotation * b.RestLocalRotation.Inverse;
                _restToParent[i] = (p < 0 ? transformParent : rig[p].RestRotation.Inverse * transformParent).Normalized;
            }

            if (restPose == RigRestPose.TPose)
            {
                for (int i = 0; i < n; i++) _tPose[i] = rig[i].RestRotation;
            }
            else
            {
                ComputeAlignedTPose(endBone);
            }

            _hipsRestPosition = rig[0].RestPosition;
            float pelvisHeight = skeleton.RestOffset(0).Y;
            RootScale = _hipsRestPosition.Y > 0f ? _hipsRestPosition.Y / pelvisHeight : 1f;
            for (int i = 0; i < n; i++)
            {
                _rotation[i] = _tPose[i];
                int p = rig.ParentIndex(i);
                Quat parent = p < 0 ? _restToParent[i] : _tPose[p] * _restToParent[i];
                _local[i] = (parent.Inverse * _tPose[i]).Normalized;
            }
            HipsPosition = _hipsRestPosition;
        }

        /// <summary>The rig this retargeter drives.</summary>
        public HumanoidRig Rig => _rig;

        /// <summary>
        /// Scale from the model's metres to rig-space units for root motion. Defaults to the rig's
        /// rest hips height over the model's pelvis height, so a smaller avatar takes smaller steps.
        /// </summary>
        public float RootScale { get; set; }

        /// <summary>Rig-space Hips position of the last retargeted frame.</summary>
        public Vec3 HipsPosition { get; private set; }

        /// <summary>
        /// Local rotation for each rig bone (index as in <see cref="Rig"/>) after the last
        /// <see cref="Retarget"/>: the value to assign to the transform's <c>localRotation</c>.
        /// Before the first frame it holds the T-pose.
        /// </summary>
        public ReadOnlySpan<Quat> LocalRotations => _local;

        /// <summary>Rig-space rotation for each rig bone after the last <see cref="Retarget"/>.</summary>
        public ReadOnlySpan<Quat> Rotations => _rotation;

        /// <summary>The rig-space rotation of bone <paramref name="index"/> in the rig's T-pose.</summary>
        public Quat TPoseRotation(int index) => _tPose[index];

        /// <summary>The local rotation for <paramref name="bone"/>, or false when the rig lacks it.</summary>
        public bool TryGetLocalRotation(HumanBone bone, out Quat rotation)
        {
            int i = _rig.IndexOf(bone);
            rotation = i >= 0 ? _local[i] : Quat.Identity;
            return i >= 0;
        }

        /// <summary>
        /// Retargets one frame (model frame in, rig space out). Results are in
        /// <see cref="LocalRotations"/>, <see cref="Rotations"/> and <see cref="HipsPosition"/>.
        /// Allocates nothing.
        /// </summary>
        public void Retarget(SmplPose pose)
        {
            if (pose == null) throw new ArgumentNullException(nameof(pose));
            _skeleton.ForwardKinematics(pose.Rotations, pose.RootPosition, _smplGlobal, _smplPositions);

            for (int i = 0; i < _rotation.Length; i++)
            {
                int j = _joint[i];
                Quat delta = CoordinateConversion.ModelToUnity(_smplGlobal[j]);
                int end = _endJoint[i];
                if (end >= 0)
                {
                    // The bone spans a missing joint: add the turn that carries where the joint's own
                    // rotation would point the span onto where the SMPL joints actually are.
                    Vec3 actual = CoordinateConversion.ModelToUnity(_smplPositions[end] - _smplPositions[j]);
                    delta = (Quat.FromToRotation(delta * _restSpan[i], actual) * delta).Normalized;
                }
                _rotation[i] = (delta * _tPose[i]).Normalized;

                int p = _rig.ParentIndex(i);
                Quat parent = p < 0 ? _restToParent[i] : _rotation[p] * _restToParent[i];
                _local[i] = (parent.Inverse * _rotation[i]).Normalized;
            }

            HipsPosition = _hipsRestPosition +
                RootScale * CoordinateConversion.ModelToUnity(pose.RootPosition - _skeleton.RestOffset(0));
        }

        private void ComputeAlignedTPose(int[] endBone)
        {
            int n = _rig.Count;
            var correction = new Quat[n]; // rig-space turn from the described rest to the T-pose
            for (int i = 0; i < n; i++)
            {
                RigBone b = _rig[i];
                int p = _rig.ParentIndex(i);
                Quat inherited = p < 0 ? Quat.Identity : correction[p];
                if (p < 0)
                {
                    correction[i] = HipsCorrection();
                }
                else if (endBone[i] >= 0)
                {
                    int e = endBone[i];
                    int endJoint = _endJoint[i] >= 0 ? _endJoint[i] : HumanoidBoneMap.ChainChild((SmplJoint)_joint[i]);
                    Vec3 target = CoordinateConversion.ModelToUnity(
                        _skeleton.RestPosition(endJoint) - _skeleton.RestPosition(_joint[i]));
                    // Where the bone points once its parent is corrected, then the smallest turn to the target.
                    Vec3 current = inherited * (_rig[e].RestPosition - b.RestPosition);
                    correction[i] = (Quat.FromToRotation(current, target) * inherited).Normalized;
                }
                else
                {
                    correction[i] = inherited;
                }
                _tPose[i] = (correction[i] * b.RestRotation).Normalized;
            }
        }

        private Quat HipsCorrection()
        {
            // Two lines fix the pelvis: left hip -> right hip (primary) and hips -> head (the body's up).
            // The head rather than the spine keeps a rig's slightly forward spine root from tilting it.
            Vec3 rigAcross = _rig[_rig.IndexOf(HumanBone.RightUpperLeg)].RestPosition - _rig[_rig.IndexOf(HumanBone.LeftUpperLeg)].RestPosition;
            Vec3 rigUp = _rig[_rig.IndexOf(HumanBone.Head)].RestPosition - _rig[0].RestPosition;
            Vec3 smplAcross = CoordinateConversion.ModelToUnity(
                _skeleton.RestPosition((int)SmplJoint.RightHip) - _skeleton.RestPosition((int)SmplJoint.LeftHip));
            Vec3 smplUp = CoordinateConversion.ModelToUnity(
                _skeleton.RestPosition((int)SmplJoint.Head) - _skeleton.RestPosition((int)SmplJoint.Pelvis));
            Quat rigFrame = FrameFrom(rigAcross, rigUp);
            Quat smplFrame = FrameFrom(smplAcross, smplUp);
            return (smplFrame * rigFrame.Inverse).Normalized;
        }

        private static Quat FrameFrom(Vec3 primary, Vec3 secondary)
        {
            // Orthonormal frame: x along primary, y the part of secondary perpendicular to it.
            Vec3 x = primary.Normalized;
            Vec3 z = Vec3.Cross(x, secondary).Normalized;
            if (z.LengthSquared == 0f)
                throw new ArgumentException("the rig's hip line is parallel to its hips-to-head line");
            Vec3 y = Vec3.Cross(z, x);
            return new Mat3(x.X, y.X, z.X, x.Y, y.Y, z.Y, x.Z, y.Z, z.Z).ToQuat();
        }
    }
}
