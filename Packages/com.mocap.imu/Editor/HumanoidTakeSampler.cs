// Reads a driven avatar into the core's HumanoidTake once per solved pose: the Humanoid pose
// through Unity's HumanPoseHandler (body position and rotation, muscles) and every bone's local
// rotation, then writes the take's curves into AnimationClips. Thin: timing, names, quaternion
// continuity, key reduction and tangents live in the core (Recording/HumanoidTake.cs).

using System;
using System.Collections.Generic;
using Mocap.Imu.Maths;
using Mocap.Imu.Recording;
using UnityEditor;
using UnityEngine;

namespace Mocap.Imu.Editor
{
    /// <summary>Samples one avatar into a <see cref="HumanoidTake"/> and saves its clips.</summary>
    internal sealed class HumanoidTakeSampler : IDisposable
    {
        readonly Transform[] _bones;
        readonly Quat[] _rotations;
        readonly HumanPoseHandler _handler;
        HumanPose _humanPose;

        /// <summary>
        /// A sampler of every Transform under <paramref name="root"/> (the hips first when the root
        /// has a Humanoid Animator, whose pose then also gives the Humanoid curves).
        /// </summary>
        public HumanoidTakeSampler(GameObject root, float frameRate)
        {
            var animator = root.GetComponentInChildren<Animator>();
            bool human = animator != null && animator.avatar != null && animator.avatar.isHuman && animator.avatar.isValid;
            var bones = new List<Transform>(root.GetComponentsInChildren<Transform>(true));
            bones.Remove(root.transform);
            if (human)
            {
                var hips = animator.GetBoneTransform(HumanBodyBones.Hips);
                if (hips != null && bones.Remove(hips)) bones.Insert(0, hips);
                _handler = new HumanPoseHandler(animator.avatar, animator.transform);
                _humanPose.muscles = new float[HumanTrait.MuscleCount];
            }
            _bones = bones.ToArray();
            _rotations = new Quat[_bones.Length];
            var paths = new string[_bones.Length];
            for (int i = 0; i < _bones.Length; i++) paths[i] = AnimationUtility.CalculateTransformPath(_bones[i], root.transform);
            IsHuman = human;
            Take = new HumanoidTake(frameRate, human ? HumanTrait.MuscleName : Array.Empty<string>(), paths,
                                    capacityFrames: Mathf.CeilToInt(frameRate * 120f));
        }

        /// <summary>The samples so far.</summary>
        public HumanoidTake Take { get; }

        /// <summary>The avatar is Humanoid: the take has a Humanoid clip.</summary>
        public bool IsHuman { get; }

        /// <summary>Read the avatar as it stands now, as model frame <paramref name="sequence"/>.</summary>
        public bool Sample(ulong sequence)
        {
            if (_handler != null) _handler.GetHumanPose(ref _humanPose);
            for (int i = 0; i < _bones.Length; i++)
            {
                var q = _bones[i].localRotation;
                _rotations[i] = new Quat(q.x, q.y, q.z, q.w);
            }
            var hips = _bones.Length > 0 ? _bones[0].localPosition : Vector3.zero;
            var body = _humanPose.bodyPosition;
            var rotation = _handler != null ? _humanPose.bodyRotation : Quaternion.identity;
            return Take.Add(sequence, new Vec3(body.x, body.y, body.z), new Quat(rotation.x, rotation.y, rotation.z, rotation.w),
                            _handler != null ? _humanPose.muscles : Array.Empty<float>(), new Vec3(hips.x, hips.y, hips.z), _rotations);
        }

        /// <summary>The Humanoid clip (RootT, RootQ, muscles), or null for a non-Humanoid avatar.</summary>
        public AnimationClip HumanoidClip(string name, KeyReduction reduction) =>
            IsHuman ? Clip(name, Take.HumanoidCurves(reduction)) : null;

        /// <summary>The Generic clip (the hips' position, every bone's local rotation).</summary>
        public AnimationClip GenericClip(string name, KeyReduction reduction) => Clip(name, Take.GenericCurves(reduction));

        AnimationClip Clip(string name, List<TakeCurve> curves)
        {
            var clip = new AnimationClip { name = name, frameRate = Take.FrameRate };
            foreach (var curve in curves)
            {
                var keys = new Keyframe[curve.Times.Length];
                for (int k = 0; k < keys.Length; k++)
                {
                    curve.LinearTangents(k, out float inTangent, out float outTangent);
                    keys[k] = new Keyframe(curve.Times[k], curve.Values[k], inTangent, outTangent);
                }
                var type = curve.Target == CurveTarget.Animator ? typeof(Animator) : typeof(Transform);
                AnimationUtility.SetEditorCurve(clip, EditorCurveBinding.FloatCurve(curve.Path, type, curve.Property), new AnimationCurve(keys));
            }
            return clip;
        }

        public void Dispose() => _handler?.Dispose();
    }
}
