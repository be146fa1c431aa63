// Declarations only (see ../README.md): editor windows, inspectors, menus, editor GUI.
using System;
using UnityEngine;

namespace UnityEditor
{
    public static class EditorJsonUtility
    {
        public static string ToJson(object obj) => throw null;
        public static string ToJson(object obj, bool prettyPrint) => throw null;
        public static void FromJsonOverwrite(string json, object objectToOverwrite) => throw null;
    }

    [AttributeUsage(AttributeTargets.Method, AllowMultiple = true)]
    public sealed partial class MenuItem : Attribute
    {
        public MenuItem(string itemName) => throw null;
        public MenuItem(string itemName, bool isValidateFunction) => throw null;
        public MenuItem(string itemName, bool isValidateFunction, int priority) => throw null;
        public string menuItem;
        public bool validate;
        public int priority;
    }

    [AttributeUsage(AttributeTargets.Class, AllowMultiple = true, Inherited = false)]
    public partial class CustomEditor : Attribute
    {
        public CustomEditor(Type inspectedType) => throw null;
        public CustomEditor(Type inspectedType, bool editorForChildClasses) => throw null;
        public bool isFallback { get => throw null; set => throw null; }
    }

    [AttributeUsage(AttributeTargets.Class, Inherited = false)]
    public sealed partial class CanEditMultipleObjects : Attribute { }

    [AttributeUsage(AttributeTargets.Class)]
    public partial class InitializeOnLoadAttribute : Attribute { }

    [AttributeUsage(AttributeTargets.Method)]
    public partial class InitializeOnLoadMethodAttribute : Attribute { }

    public partial class EditorWindow : ScriptableObject
    {
        public GUIContent titleContent { get => throw null; set => throw null; }
        public Vector2 minSize { get => throw null; set => throw null; }
        public Vector2 maxSize { get => throw null; set => throw null; }
        public Rect position { get => throw null; set => throw null; }
        public bool hasFocus => throw null;
        public static T GetWindow<T>() where T : EditorWindow => throw null;
        public static T GetWindow<T>(string title) where T : EditorWindow => throw null;
        public static T GetWindow<T>(bool utility, string title) where T : EditorWindow => throw null;
        public void Show() => throw null;
        public void Close() => throw null;
        public void Repaint() => throw null;
        public void Focus() => throw null;
    }

    public partial class SerializedObject : IDisposable
    {
        public SerializedObject(UnityEngine.Object obj) => throw null;
        public UnityEngine.Object targetObject => throw null;
        public SerializedProperty FindProperty(string propertyPath) => throw null;
        public bool ApplyModifiedProperties() => throw null;
        public void Update() => throw null;
        public void Dispose() => throw null;
    }

    public partial class SerializedProperty
    {
        public string name => throw null;
        public string propertyPath => throw null;
        public int intValue { get => throw null; set => throw null; }
        public float floatValue { get => throw null; set => throw null; }
        public bool boolValue { get => throw null; set => throw null; }
        public string stringValue { get => throw null; set => throw null; }
        public UnityEngine.Object objectReferenceValue { get => throw null; set => throw null; }
    }

    public partial class Editor : ScriptableObject
    {
        public UnityEngine.Object target { get => throw null; set => throw null; }
        public UnityEngine.Object[] targets => throw null;
        public SerializedObject serializedObject => throw null;
        public virtual void OnInspectorGUI() => throw null;
        public virtual bool RequiresConstantRepaint() => throw null;
        public bool DrawDefaultInspector() => throw null;
        public void Repaint() => throw null;
    }

    public enum MessageType { None = 0, Info = 1, Warning = 2, Error = 3 }

    public sealed partial class EditorStyles
    {
        public static GUIStyle label => throw null;
        public static GUIStyle miniLabel => throw null;
        public static GUIStyle boldLabel => throw null;
        public static GUIStyle miniBoldLabel => throw null;
        public static GUIStyle wordWrappedLabel => throw null;
        public static GUIStyle wordWrappedMiniLabel => throw null;
        public static GUIStyle helpBox => throw null;
        public static GUIStyle largeLabel => throw null;
        public static GUIStyle miniButton => throw null;
        public static GUIStyle textArea => throw null;
        public static GUIStyle foldout => throw null;
    }

    public sealed partial class EditorGUILayout
    {
        public static void LabelField(string label, params GUILayoutOption[] options) => throw null;
        public static void LabelField(string label, GUIStyle style, params GUILayoutOption[] options) => throw null;
        public static void LabelField(string label, string label2, params GUILayoutOption[] options) => throw null;
        public static void LabelField(string label, string label2, GUIStyle style, params GUILayoutOption[] options) => throw null;
        public static void LabelField(GUIContent label, params GUILayoutOption[] options) => throw null;
        public static void HelpBox(string message, MessageType type) => throw null;
        public static void HelpBox(string message, MessageType type, bool wide) => throw null;
        public static void Space() => throw null;
        public static void Space(float width) => throw null;
        public static bool Foldout(bool foldout, string content) => throw null;
        public static bool Toggle(string label, bool value, params GUILayoutOption[] options) => throw null;
        public static int IntField(string label, int value, params GUILayoutOption[] options) => throw null;
        public static float FloatField(string label, float value, params GUILayoutOption[] options) => throw null;
        public static string TextField(string label, string text, params GUILayoutOption[] options) => throw null;
        public static int IntSlider(string label, int value, int leftValue, int rightValue, params GUILayoutOption[] options) => throw null;
        public static float Slider(string label, float value, float leftValue, float rightValue, params GUILayoutOption[] options) => throw null;
        public static Enum EnumPopup(string label, Enum selected, params GUILayoutOption[] options) => throw null;
        public static int Popup(string label, int selectedIndex, string[] displayedOptions, params GUILayoutOption[] options) => throw null;
        [Obsolete("Check the docs for the usage of the new parameter 'allowSceneObjects'.")]
        public static UnityEngine.Object ObjectField(string label, UnityEngine.Object obj, Type objType, params GUILayoutOption[] options) => throw null;
        public static UnityEngine.Object ObjectField(string label, UnityEngine.Object obj, Type objType, bool allowSceneObjects, params GUILayoutOption[] options) => throw null;
        public static bool PropertyField(SerializedProperty property, params GUILayoutOption[] options) => throw null;
        public static Rect GetControlRect(params GUILayoutOption[] options) => throw null;
        public static Rect GetControlRect(bool hasLabel, params GUILayoutOption[] options) => throw null;
        public static Rect GetControlRect(bool hasLabel, float height, params GUILayoutOption[] options) => throw null;
        public static Vector2 BeginScrollView(Vector2 scrollPosition, params GUILayoutOption[] options) => throw null;
        public static void EndScrollView() => throw null;
        public static Rect BeginHorizontal(params GUILayoutOption[] options) => throw null;
        public static void EndHorizontal() => throw null;
        public static Rect BeginVertical(params GUILayoutOption[] options) => throw null;
        public static void EndVertical() => throw null;

        public partial class HorizontalScope : GUI.Scope
        {
            public HorizontalScope(params GUILayoutOption[] options) => throw null;
            public HorizontalScope(GUIStyle style, params GUILayoutOption[] options) => throw null;
            public Rect rect => throw null;
            protected override void CloseScope() => throw null;
        }

        public partial class VerticalScope : GUI.Scope
        {
            public VerticalScope(params GUILayoutOption[] options) => throw null;
            public VerticalScope(GUIStyle style, params GUILayoutOption[] options) => throw null;
            public Rect rect => throw null;
            protected override void CloseScope() => throw null;
        }

        public partial class ScrollViewScope : GUI.Scope
        {
            public ScrollViewScope(Vector2 scrollPosition, params GUILayoutOption[] options) => throw null;
            public Vector2 scrollPosition => throw null;
            protected override void CloseScope() => throw null;
        }
    }

    public sealed partial class EditorGUI
    {
        public static int indentLevel { get => throw null; set => throw null; }
        public static void ProgressBar(Rect position, float value, string text) => throw null;
        public static void LabelField(Rect position, string label) => throw null;
        public static void HelpBox(Rect position, string message, MessageType type) => throw null;
        public static void BeginDisabledGroup(bool disabled) => throw null;
        public static void EndDisabledGroup() => throw null;
        public static void BeginChangeCheck() => throw null;
        public static bool EndChangeCheck() => throw null;

        public partial struct DisabledScope : IDisposable
        {
            public DisabledScope(bool disabled) => throw null;
            public void Dispose() => throw null;
        }

        public partial class IndentLevelScope : GUI.Scope
        {
            public IndentLevelScope() => throw null;
            public IndentLevelScope(int increment) => throw null;
            protected override void CloseScope() => throw null;
        }

        public partial class ChangeCheckScope : GUI.Scope
        {
            public ChangeCheckScope() => throw null;
            public bool changed => throw null;
            protected override void CloseScope() => throw null;
        }
    }

    public sealed partial class EditorGUIUtility
    {
        public static void PingObject(UnityEngine.Object obj) => throw null;
        public static float singleLineHeight => throw null;
        public static float labelWidth { get => throw null; set => throw null; }
        public static bool isProSkin => throw null;
    }

    public sealed partial class EditorUtility
    {
        public static bool DisplayDialog(string title, string message, string ok) => throw null;
        public static bool DisplayDialog(string title, string message, string ok, string cancel) => throw null;
        public static string SaveFilePanel(string title, string directory, string defaultName, string extension) => throw null;
        public static string SaveFilePanelInProject(string title, string defaultName, string extension, string message) => throw null;
        public static string OpenFilePanel(string title, string directory, string extension) => throw null;
        public static void SetDirty(UnityEngine.Object target) => throw null;
        public static void DisplayProgressBar(string title, string info, float progress) => throw null;
        public static void ClearProgressBar() => throw null;
        public static void RevealInFinder(string path) => throw null;
    }

    public enum PlayModeStateChange { EnteredEditMode = 0, ExitingEditMode = 1, EnteredPlayMode = 2, ExitingPlayMode = 3 }

    public sealed partial class EditorApplication
    {
        public delegate void CallbackFunction();
        public static CallbackFunction update;
        public static CallbackFunction delayCall;
        public static bool isPlaying { get => throw null; set => throw null; }
        public static bool isPaused { get => throw null; set => throw null; }
        public static bool isCompiling => throw null;
        public static bool isPlayingOrWillChangePlaymode => throw null;
        public static double timeSinceStartup => throw null;
        public static event Action<PlayModeStateChange> playModeStateChanged { add => throw null; remove => throw null; }
        public static void QueuePlayerLoopUpdate() => throw null;
    }

    public sealed partial class Selection
    {
        public static UnityEngine.Object activeObject { get => throw null; set => throw null; }
        public static GameObject activeGameObject { get => throw null; set => throw null; }
        public static Transform activeTransform { get => throw null; set => throw null; }
        public static UnityEngine.Object[] objects { get => throw null; set => throw null; }
        public static event Action selectionChanged { add => throw null; remove => throw null; }
    }

    public sealed partial class AssetDatabase
    {
        public static void Refresh() => throw null;
        public static void SaveAssets() => throw null;
        public static void ImportAsset(string path) => throw null;
        public static void CreateAsset(UnityEngine.Object asset, string path) => throw null;
        public static string CreateFolder(string parentFolder, string newFolderName) => throw null;
        public static bool DeleteAsset(string path) => throw null;
        public static bool IsValidFolder(string path) => throw null;
        public static string GetAssetPath(UnityEngine.Object assetObject) => throw null;
        public static T LoadAssetAtPath<T>(string assetPath) where T : UnityEngine.Object => throw null;
        public static UnityEngine.Object LoadAssetAtPath(string assetPath, Type type) => throw null;
        public static UnityEngine.Object LoadMainAssetAtPath(string assetPath) => throw null;
        public static string[] FindAssets(string filter) => throw null;
        public static string GUIDToAssetPath(string guid) => throw null;
        public static string AssetPathToGUID(string path) => throw null;
    }

    public enum BuildTarget
    {
        StandaloneOSX = 2,
        StandaloneWindows = 5,
        iOS = 9,
        Android = 13,
        StandaloneWindows64 = 19,
        WebGL = 20,
        WSAPlayer = 21,
        StandaloneLinux64 = 24,
        PS4 = 31,
        XboxOne = 33,
        tvOS = 37,
        Switch = 38,
        NoTarget = -2,
    }

    public enum BuildTargetGroup { Unknown = 0, Standalone = 1, iOS = 4, Android = 7, WebGL = 13 }

    public sealed partial class EditorUserBuildSettings
    {
        public static BuildTarget activeBuildTarget => throw null;
    }
}
