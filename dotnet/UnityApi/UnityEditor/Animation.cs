// Declarations only (see ../README.md): editor-side animation clip access and recording.
using System;
using UnityEngine;

namespace UnityEditor
{
    public partial struct EditorCurveBinding : IEquatable<EditorCurveBinding>
    {
        public string path;
        public string propertyName;
        public Type type { get => throw null; set => throw null; }
        public bool isPPtrCurve => throw null;
        public static EditorCurveBinding FloatCurve(string inPath, Type inType, string inPropertyName) => throw null;
        public bool Equals(EditorCurveBinding other) => throw null;
        public override bool Equals(object other) => throw null;
        public override int GetHashCode() => throw null;
        public static bool operator ==(EditorCurveBinding lhs, EditorCurveBinding rhs) => throw null;
        public static bool operator !=(EditorCurveBinding lhs, EditorCurveBinding rhs) => throw null;
    }

    public partial class AnimationClipSettings
    {
        public AnimationClip additiveReferencePoseClip;
        public float additiveReferencePoseTime;
        public float startTime;
        public float stopTime;
        public float orientationOffsetY;
        public float level;
        public float cycleOffset;
        public bool hasAdditiveReferencePose;
        public bool loopTime;
        public bool loopBlend;
        public bool loopBlendOrientation;
        public bool loopBlendPositionY;
        public bool loopBlendPositionXZ;
        public bool keepOriginalOrientation;
        public bool keepOriginalPositionY;
        public bool keepOriginalPositionXZ;
        public bool heightFromFeet;
        public bool mirror;
    }

    public partial class AnimationUtility
    {
        public static EditorCurveBinding[] GetCurveBindings(AnimationClip clip) => throw null;
        public static AnimationCurve GetEditorCurve(AnimationClip clip, EditorCurveBinding binding) => throw null;
        public static void SetEditorCurve(AnimationClip clip, EditorCurveBinding binding, AnimationCurve curve) => throw null;
        public static void SetEditorCurves(AnimationClip clip, EditorCurveBinding[] bindings, AnimationCurve[] curves) => throw null;
        public static AnimationClipSettings GetAnimationClipSettings(AnimationClip clip) => throw null;
        public static void SetAnimationClipSettings(AnimationClip clip, AnimationClipSettings srcClipInfo) => throw null;
        public static string CalculateTransformPath(Transform targetTransform, Transform root) => throw null;
    }
}

namespace UnityEditor.Animations
{
    public partial class GameObjectRecorder : UnityEngine.Object
    {
        public GameObjectRecorder(GameObject root) => throw null;
        public GameObject root => throw null;
        public float currentTime => throw null;
        public bool isRecording => throw null;
        public void BindComponentsOfType<T>(GameObject target, bool recursive) where T : Component => throw null;
        public void BindComponent<T>(T component) where T : Component => throw null;
        public void BindAll(GameObject target, bool recursive) => throw null;
        public void TakeSnapshot(float dt) => throw null;
        public void SaveToClip(AnimationClip clip) => throw null;
        public void SaveToClip(AnimationClip clip, float fps) => throw null;
        public void ResetRecording() => throw null;
    }
}

namespace UnityEditor.ShortcutManagement
{
    [Flags]
    public enum ShortcutModifiers { None = 0, Alt = 1, Action = 2, Shift = 4, Control = 8 }

    [AttributeUsage(AttributeTargets.Method | AttributeTargets.Class, AllowMultiple = true)]
    public partial class ShortcutAttribute : Attribute
    {
        public ShortcutAttribute(string id) => throw null;
        public ShortcutAttribute(string id, KeyCode defaultKeyCode) => throw null;
        public ShortcutAttribute(string id, KeyCode defaultKeyCode, ShortcutModifiers defaultShortcutModifiers) => throw null;
        public ShortcutAttribute(string id, Type context, KeyCode defaultKeyCode) => throw null;
        public string displayName { get => throw null; set => throw null; }
    }
}

namespace UnityEditor.Build
{
    public partial interface IOrderedCallback
    {
        int callbackOrder { get; }
    }

    public partial interface IPreprocessBuildWithReport : IOrderedCallback
    {
        void OnPreprocessBuild(Reporting.BuildReport report);
    }

    public partial interface IPostprocessBuildWithReport : IOrderedCallback
    {
        void OnPostprocessBuild(Reporting.BuildReport report);
    }

    public partial class BuildFailedException : Exception
    {
        public BuildFailedException(string message) => throw null;
        public BuildFailedException(Exception innerException) => throw null;
    }
}

namespace UnityEditor.Build.Reporting
{
    public enum BuildResult { Unknown = 0, Succeeded = 1, Failed = 2, Cancelled = 3 }

    public partial struct BuildSummary
    {
        public BuildTarget platform => throw null;
        public BuildTargetGroup platformGroup => throw null;
        public string outputPath => throw null;
        public BuildResult result => throw null;
        public ulong totalSize => throw null;
        public int totalErrors => throw null;
        public int totalWarnings => throw null;
    }

    public sealed partial class BuildReport : UnityEngine.Object
    {
        public BuildSummary summary => throw null;
    }
}
