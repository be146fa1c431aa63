// Declarations only (see ../README.md): Mecanim humanoids, avatars, clips and curves.
using System;

namespace UnityEngine
{
    public enum HumanBodyBones
    {
        Hips = 0, LeftUpperLeg = 1, RightUpperLeg = 2, LeftLowerLeg = 3, RightLowerLeg = 4, LeftFoot = 5, RightFoot = 6,
        Spine = 7, Chest = 8, Neck = 9, Head = 10, LeftShoulder = 11, RightShoulder = 12, LeftUpperArm = 13, RightUpperArm = 14,
        LeftLowerArm = 15, RightLowerArm = 16, LeftHand = 17, RightHand = 18, LeftToes = 19, RightToes = 20,
        LeftEye = 21, RightEye = 22, Jaw = 23,
        LeftThumbProximal = 24, LeftThumbIntermediate = 25, LeftThumbDistal = 26,
        LeftIndexProximal = 27, LeftIndexIntermediate = 28, LeftIndexDistal = 29,
        LeftMiddleProximal = 30, LeftMiddleIntermediate = 31, LeftMiddleDistal = 32,
        LeftRingProximal = 33, LeftRingIntermediate = 34, LeftRingDistal = 35,
        LeftLittleProximal = 36, LeftLittleIntermediate = 37, LeftLittleDistal = 38,
        RightThumbProximal = 39, RightThumbIntermediate = 40, RightThumbDistal = 41,
        RightIndexProximal = 42, RightIndexIntermediate = 43, RightIndexDistal = 44,
        RightMiddleProximal = 45, RightMiddleIntermediate = 46, RightMiddleDistal = 47,
        RightRingProximal = 48, RightRingIntermediate = 49, RightRingDistal = 50,
        RightLittleProximal = 51, RightLittleIntermediate = 52, RightLittleDistal = 53,
        UpperChest = 54, LastBone = 55,
    }

    public partial class Avatar : Object
    {
        public bool isValid => throw null;
        public bool isHuman => throw null;
        public HumanDescription humanDescription => throw null;
    }

    public partial class AvatarBuilder
    {
        public static Avatar BuildHumanAvatar(GameObject go, HumanDescription humanDescription) => throw null;
        public static Avatar BuildGenericAvatar(GameObject go, string rootMotionTransformName) => throw null;
    }

    public partial struct HumanLimit
    {
        public bool useDefaultValues { get => throw null; set => throw null; }
        public Vector3 min { get => throw null; set => throw null; }
        public Vector3 max { get => throw null; set => throw null; }
        public Vector3 center { get => throw null; set => throw null; }
        public float axisLength { get => throw null; set => throw null; }
    }

    public partial struct HumanBone
    {
        public HumanLimit limit;
        public string boneName { get => throw null; set => throw null; }
        public string humanName { get => throw null; set => throw null; }
    }

    public partial struct SkeletonBone
    {
        public string name;
        public Vector3 position;
        public Quaternion rotation;
        public Vector3 scale;
    }

    public partial struct HumanDescription
    {
        public HumanBone[] human;
        public SkeletonBone[] skeleton;
        public float upperArmTwist { get => throw null; set => throw null; }
        public float lowerArmTwist { get => throw null; set => throw null; }
        public float upperLegTwist { get => throw null; set => throw null; }
        public float lowerLegTwist { get => throw null; set => throw null; }
        public float armStretch { get => throw null; set => throw null; }
        public float legStretch { get => throw null; set => throw null; }
        public float feetSpacing { get => throw null; set => throw null; }
        public bool hasTranslationDoF { get => throw null; set => throw null; }
    }

    public partial class HumanTrait
    {
        public static int MuscleCount => throw null;
        public static string[] MuscleName => throw null;
        public static int BoneCount => throw null;
        public static string[] BoneName => throw null;
        public static int RequiredBoneCount => throw null;
        public static int MuscleFromBone(int i, int dofIndex) => throw null;
        public static int BoneFromMuscle(int i) => throw null;
        public static bool RequiredBone(int i) => throw null;
        public static int GetParentBone(int i) => throw null;
        public static float GetMuscleDefaultMin(int i) => throw null;
        public static float GetMuscleDefaultMax(int i) => throw null;
    }

    public partial struct HumanPose
    {
        public Vector3 bodyPosition;
        public Quaternion bodyRotation;
        public float[] muscles;
    }

    public partial class HumanPoseHandler : IDisposable
    {
        public HumanPoseHandler(Avatar avatar, Transform root) => throw null;
        public void GetHumanPose(ref HumanPose humanPose) => throw null;
        public void SetHumanPose(ref HumanPose humanPose) => throw null;
        public void Dispose() => throw null;
    }

    public partial class RuntimeAnimatorController : Object { }

    public enum AnimatorCullingMode { AlwaysAnimate = 0, CullUpdateTransforms = 1, CullCompletely = 2 }
    public partial class Animator : Behaviour
    {
        public Avatar avatar { get => throw null; set => throw null; }
        public bool isHuman => throw null;
        public bool hasRootMotion => throw null;
        public bool applyRootMotion { get => throw null; set => throw null; }
        public bool isInitialized => throw null;
        public float humanScale => throw null;
        public float speed { get => throw null; set => throw null; }
        public AnimatorCullingMode cullingMode { get => throw null; set => throw null; }
        public RuntimeAnimatorController runtimeAnimatorController { get => throw null; set => throw null; }
        public Transform GetBoneTransform(HumanBodyBones humanBoneId) => throw null;
        public void Rebind() => throw null;
        public void Update(float deltaTime) => throw null;
    }

    public enum WrapMode { Once = 1, Loop = 2, PingPong = 4, Default = 0, ClampForever = 8, Clamp = 1 }

    public partial struct Keyframe
    {
        public Keyframe(float time, float value) => throw null;
        public Keyframe(float time, float value, float inTangent, float outTangent) => throw null;
        public float time { get => throw null; set => throw null; }
        public float value { get => throw null; set => throw null; }
        public float inTangent { get => throw null; set => throw null; }
        public float outTangent { get => throw null; set => throw null; }
    }

    public partial class AnimationCurve : IEquatable<AnimationCurve>
    {
        public AnimationCurve() => throw null;
        public AnimationCurve(params Keyframe[] keys) => throw null;
        public Keyframe[] keys { get => throw null; set => throw null; }
        public Keyframe this[int index] => throw null;
        public int length => throw null;
        public WrapMode preWrapMode { get => throw null; set => throw null; }
        public WrapMode postWrapMode { get => throw null; set => throw null; }
        public float Evaluate(float time) => throw null;
        public int AddKey(float time, float value) => throw null;
        public int AddKey(Keyframe key) => throw null;
        public int MoveKey(int index, Keyframe key) => throw null;
        public void RemoveKey(int index) => throw null;
        public void SmoothTangents(int index, float weight) => throw null;
        public static AnimationCurve Constant(float timeStart, float timeEnd, float value) => throw null;
        public static AnimationCurve Linear(float timeStart, float valueStart, float timeEnd, float valueEnd) => throw null;
        public bool Equals(AnimationCurve other) => throw null;
        public override bool Equals(object o) => throw null;
        public override int GetHashCode() => throw null;
    }

    public partial class Motion : Object
    {
        public bool isLooping => throw null;
        public float averageDuration => throw null;
    }

    public sealed partial class AnimationClip : Motion
    {
        public AnimationClip() => throw null;
        public float length => throw null;
        public float frameRate { get => throw null; set => throw null; }
        public bool legacy { get => throw null; set => throw null; }
        public WrapMode wrapMode { get => throw null; set => throw null; }
        public bool empty => throw null;
        public bool humanMotion => throw null;
        public Bounds localBounds { get => throw null; set => throw null; }
        public void SetCurve(string relativePath, Type type, string propertyName, AnimationCurve curve) => throw null;
        public void EnsureQuaternionContinuity() => throw null;
        public void ClearCurves() => throw null;
        public void SampleAnimation(GameObject go, float time) => throw null;
    }

    public partial struct Bounds
    {
        public Bounds(Vector3 center, Vector3 size) => throw null;
        public Vector3 center { get => throw null; set => throw null; }
        public Vector3 size { get => throw null; set => throw null; }
        public Vector3 extents { get => throw null; set => throw null; }
        public Vector3 min { get => throw null; set => throw null; }
        public Vector3 max { get => throw null; set => throw null; }
        public void Encapsulate(Vector3 point) => throw null;
    }
}
