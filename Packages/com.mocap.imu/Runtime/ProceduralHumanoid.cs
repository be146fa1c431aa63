using System.Collections.Generic;
using Mocap.Imu.Retarget;
using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>
    /// Builds a Humanoid avatar from code with the model's proportions in its T-pose (the core's
    /// <see cref="HumanoidLayout"/>): a transform per driven bone, an Animator with a human Avatar
    /// made by AvatarBuilder (destroyed with the character, see <see cref="RuntimeAvatarOwner"/>),
    /// and optional primitive visuals. For samples and PlayMode tests that must run without an
    /// avatar asset; any real Humanoid avatar works the same way.
    /// </summary>
    public static class ProceduralHumanoid
    {
        /// <summary>
        /// Create the avatar at <paramref name="position"/>. Returns its Animator (valid human
        /// Avatar, bind pose = T-pose). Add a <see cref="HumanoidPoseDriver"/> afterwards.
        /// </summary>
        public static Animator Create(string name, Vector3 position, bool visuals = true, Skeleton.SmplSkeleton skeleton = null)
        {
            var layout = HumanoidLayout.FromSkeleton(skeleton ?? Skeleton.SmplSkeleton.Default);
            var root = new GameObject(name);
            root.transform.position = position;
            var transforms = new Dictionary<Skeleton.HumanBone, Transform>();
            var human = new List<HumanBone>(layout.Length);
            var skeletonBones = new List<SkeletonBone>(layout.Length + 1)
            {
                new SkeletonBone { name = root.name, position = Vector3.zero, rotation = Quaternion.identity, scale = Vector3.one },
            };
            foreach (var bone in layout)
            {
                var t = new GameObject(bone.Id.ToString()).transform;
                t.SetParent(bone.Parent == Skeleton.HumanBone.LastBone ? root.transform : transforms[bone.Parent], false);
                t.localPosition = bone.LocalPosition.ToUnity();
                t.localRotation = Quaternion.identity;
                transforms[bone.Id] = t;
                human.Add(new HumanBone
                {
                    boneName = t.name,
                    humanName = HumanTrait.BoneName[(int)bone.Id],
                    limit = new HumanLimit { useDefaultValues = true },
                });
                skeletonBones.Add(new SkeletonBone
                {
                    name = t.name, position = t.localPosition, rotation = t.localRotation, scale = Vector3.one,
                });
            }
            var description = new HumanDescription
            {
                human = human.ToArray(),
                skeleton = skeletonBones.ToArray(),
                upperArmTwist = 0.5f, lowerArmTwist = 0.5f, upperLegTwist = 0.5f, lowerLegTwist = 0.5f,
                armStretch = 0.05f, legStretch = 0.05f, feetSpacing = 0f, hasTranslationDoF = false,
            };
            var avatar = AvatarBuilder.BuildHumanAvatar(root, description);
            avatar.name = name + " Avatar";
            if (!avatar.isValid || !avatar.isHuman)
                Debug.LogError($"[Mocap IMU] the procedural avatar '{name}' is not a valid humanoid");
            var animator = root.AddComponent<Animator>();
            animator.avatar = avatar;
            animator.applyRootMotion = false;
            animator.Rebind();
            // The Avatar is not a component: without an owner it outlives the character.
            root.AddComponent<RuntimeAvatarOwner>().Owned = avatar;

            if (visuals)
            {
                foreach (var bone in layout)
                {
                    var t = transforms[bone.Id];
                    var joint = GameObject.CreatePrimitive(PrimitiveType.Sphere);
                    DestroyNow(joint.GetComponent<Collider>());
                    joint.name = "visual";
                    joint.transform.SetParent(t, false);
                    joint.transform.localScale = Vector3.one * (bone.Id == Skeleton.HumanBone.Head ? 0.18f : 0.07f);
                    if (bone.Parent == Skeleton.HumanBone.LastBone) continue;
                    // A limb segment from the parent joint to this one, parented to the parent.
                    var parent = transforms[bone.Parent];
                    var limb = GameObject.CreatePrimitive(PrimitiveType.Capsule);
                    DestroyNow(limb.GetComponent<Collider>());
                    limb.name = "visual " + bone.Id;
                    limb.transform.SetParent(parent, false);
                    Vector3 offset = bone.LocalPosition.ToUnity();
                    limb.transform.localPosition = offset * 0.5f;
                    limb.transform.localRotation = Quaternion.FromToRotation(Vector3.up, offset.normalized);
                    limb.transform.localScale = new Vector3(0.05f, offset.magnitude * 0.5f, 0.05f);
                }
            }
            return animator;
        }

        // Destroy is refused outside Play Mode (editor scripts, EditMode tests build characters too).
        static void DestroyNow(UnityEngine.Object target)
        {
            if (Application.isPlaying) UnityEngine.Object.Destroy(target);
            else UnityEngine.Object.DestroyImmediate(target);
        }
    }
}
