using System;
using System.Collections.Generic;
using Mocap.Imu.Retarget;
using UnityEngine;
using CoreBone = Mocap.Imu.Skeleton.HumanBone;
using BoneMap = Mocap.Imu.Skeleton.HumanoidBoneMap;

namespace Mocap.Imu
{
    /// <summary>
    /// Applies one character's poses to a Humanoid avatar (Animator with a human Avatar) through
    /// the core's SMPL -> HumanBodyBones rest-pose retarget. Optional bones the avatar lacks
    /// (Chest, UpperChest, Neck, shoulders, toes) are folded in by the core.
    /// </summary>
    /// <remarks>
    /// <para><b>The avatar must be in its bind pose when this component awakes</b>: the rest
    /// rotations are read from the transforms then. With <see cref="RigRestPose.TPose"/> the bind
    /// pose must be a T-pose; for an A-pose or any other bind pose use
    /// <see cref="RigRestPose.AlignToSmplTPose"/>. Leave the Animator without a controller (or
    /// disable it): the pose is written in LateUpdate, after the Animator.</para>
    /// <para>Nothing is allocated per frame.</para>
    /// </remarks>
    [RequireComponent(typeof(Animator))]
    [DisallowMultipleComponent]
    [AddComponentMenu("Mocap IMU/Humanoid Pose Driver")]
    public sealed class HumanoidPoseDriver : MonoBehaviour
    {
        [Tooltip("The session whose poses drive this avatar.")]
        public MocapSessionComponent session;
        [Tooltip("Index of the character in the session's settings.")]
        [Min(0)] public int character;
        [Tooltip("TPose: the bind pose is a T-pose. AlignToSmplTPose: any bind pose (A-pose...), straightened to the model's T-pose.")]
        public RigRestPose restPose = RigRestPose.TPose;
        [Tooltip("InPlace: only the hips height follows. MoveHips: the hips carry the motion. MoveRoot: this transform travels.")]
        public RootMotionMode rootMotion = RootMotionMode.MoveHips;

        Animator _animator;
        Transform[] _bones = Array.Empty<Transform>();
        RestPoseRetargeter _retargeter;
        readonly Skeleton.SmplPose _smpl = new Skeleton.SmplPose();
        Vector3 _restHips;
        Vector3 _rootStartPosition;
        Quaternion _rootStartRotation;
        bool _hasTarget;
        string _error = "";
        MocapModel _builtFor;

        // Bind pose captured at Awake, per rig bone.
        Quaternion[] _bindLocal = Array.Empty<Quaternion>();
        Vector3 _bindHipsLocalPosition;

        /// <summary>When false the pose is computed but not written (a PhysicsCharacter writes instead).</summary>
        public bool WriteTransforms { get; set; } = true;

        /// <summary>Why the driver is idle ("" when fine).</summary>
        public string Error => _error;

        /// <summary>The rig the avatar was read as (null when it could not be).</summary>
        public HumanoidRig Rig => _retargeter?.Rig;

        /// <summary>Number of driven bones; index as in <see cref="Rig"/> (0 = Hips, parents first).</summary>
        public int BoneCount => _bones.Length;

        /// <summary>The avatar transform of rig bone <paramref name="index"/>.</summary>
        public Transform GetBone(int index) => _bones[index];

        /// <summary>A pose has been retargeted at least once.</summary>
        public bool HasTarget => _hasTarget;

        /// <summary>The retargeted local rotation of a bone (the bind local rotation before the first pose).</summary>
        public Quaternion GetTargetLocalRotation(int index) =>
            _hasTarget ? _retargeter.LocalRotations[index].ToUnity() : _bindLocal[index];

        /// <summary>The bone's local rotation in the bind pose captured at Awake.</summary>
        public Quaternion GetBindLocalRotation(int index) => _bindLocal[index];

        /// <summary>The retargeted world position of the Hips (root motion applied).</summary>
        public Vector3 TargetHipsWorldPosition { get; private set; }

        /// <summary>The retargeted world rotation of the Hips.</summary>
        public Quaternion TargetHipsWorldRotation { get; private set; }

        void Awake()
        {
            _animator = GetComponent<Animator>();
            _rootStartPosition = transform.position;
            _rootStartRotation = transform.rotation;
            TargetHipsWorldRotation = Quaternion.identity;
            Rebuild();
        }

        /// <summary>
        /// Read the avatar's bones and bind pose again (after assigning an Avatar at run time;
        /// the avatar must be in its bind pose).
        /// </summary>
        public void Rebuild()
        {
            _retargeter = null;
            _hasTarget = false;
            _error = "";
            // Set before any early return: Update rebuilds when the model differs from this, and a
            // failed rebuild must not be retried (and logged) every frame.
            _builtFor = session != null ? session.Model : null;
            if (_animator == null) _animator = GetComponent<Animator>();
            if (_animator.avatar == null || !_animator.isHuman)
            {
                _error = "the Animator has no valid Humanoid avatar";
                Debug.LogError($"[Mocap IMU] {name}: {_error}", this);
                return;
            }
            var root = transform;
            var found = new Dictionary<Transform, CoreBone>();
            var bones = new List<(CoreBone bone, Transform t)>();
            foreach (CoreBone b in BoneMap.MappedBones)
            {
                // Same values as UnityEngine.HumanBodyBones (pinned by a core test).
                var t = _animator.GetBoneTransform((HumanBodyBones)(int)b);
                if (t == null) continue; // optional bone absent: the core folds it in
                found[t] = b;
                bones.Add((b, t));
            }
            var description = new List<RigBone>(bones.Count);
            Quaternion rootInverse = Quaternion.Inverse(root.rotation);
            foreach (var (bone, t) in bones)
            {
                // Nearest ancestor that is a driven bone; non-humanoid transforms in between keep their pose.
                var parent = CoreBone.LastBone;
                if (bone != CoreBone.Hips)
                    for (var p = t.parent; p != null && p != root; p = p.parent)
                        if (found.TryGetValue(p, out var pb)) { parent = pb; break; }
                description.Add(new RigBone(bone, parent,
                    t.localRotation.ToCore(),
                    (rootInverse * t.rotation).ToCore(),
                    root.InverseTransformPoint(t.position).ToCore()));
            }
            try
            {
                var model = _builtFor;
                var skeleton = model != null ? model.Info.Skeleton : Skeleton.SmplSkeleton.Default;
                _retargeter = new RestPoseRetargeter(skeleton, new HumanoidRig(description), restPose);
            }
            catch (ArgumentException e)
            {
                _error = "the avatar cannot be driven: " + e.Message;
                Debug.LogError($"[Mocap IMU] {name}: {_error}", this);
                return;
            }
            var rig = _retargeter.Rig;
            _bones = new Transform[rig.Count];
            _bindLocal = new Quaternion[rig.Count];
            for (int i = 0; i < rig.Count; i++)
            {
                _bones[i] = _animator.GetBoneTransform((HumanBodyBones)(int)rig[i].Bone);
                _bindLocal[i] = _bones[i].localRotation;
            }
            _bindHipsLocalPosition = _bones[0].localPosition;
            _restHips = rig[0].RestPosition.ToUnity();
            TargetHipsWorldPosition = _bones[0].position;
            TargetHipsWorldRotation = _bones[0].rotation;
        }

        /// <summary>Put the avatar back into the bind pose captured at Awake.</summary>
        public void RestoreBindPose()
        {
            for (int i = 0; i < _bones.Length; i++) _bones[i].localRotation = _bindLocal[i];
            if (_bones.Length > 0) _bones[0].localPosition = _bindHipsLocalPosition;
        }

        void Update()
        {
            if (session == null) return;
            // The model's own proportions replace the default skeleton once the model is loaded.
            var model = session.Model;
            if (model != null && model != _builtFor)
            {
                // The session reopens (loop playback, starting or stopping a recording) with the
                // same model file: keep the retargeter and the last pose instead of showing the
                // bind pose until the new engine's first pose.
                if (_retargeter != null && _builtFor != null && model.Info.Skeleton.HasSameProportions(_builtFor.Info.Skeleton))
                {
                    _builtFor = model;
                }
                else
                {
                    if (_retargeter != null) RestoreBindPose();
                    Rebuild();
                }
            }
            if (_retargeter == null) return;
            if (!session.TryGetLatestPose(character, out var pose)) return;
            pose.CopyTo(_smpl);
            _retargeter.Retarget(_smpl);
            _hasTarget = true;

            RootMotion.Split(rootMotion, _retargeter.HipsPosition, _restHips.ToCore(), out var hipsRig, out var rootMove);
            if (rootMotion == RootMotionMode.MoveRoot)
                transform.position = _rootStartPosition + _rootStartRotation * Vector3.Scale(transform.lossyScale, rootMove.ToUnity());
            TargetHipsWorldPosition = transform.TransformPoint(hipsRig.ToUnity());
            // Rig-space rotations are the transforms' rotations relative to the avatar root.
            TargetHipsWorldRotation = transform.rotation * _retargeter.Rotations[0].ToUnity();
        }

        void LateUpdate()
        {
            if (!_hasTarget || !WriteTransforms) return;
            var local = _retargeter.LocalRotations;
            for (int i = 0; i < _bones.Length; i++) _bones[i].localRotation = local[i].ToUnity();
            _bones[0].position = TargetHipsWorldPosition;
        }
    }
}
