// Declarations only (see ../README.md): the immediate-mode GUI (OnGUI).
using System;

namespace UnityEngine
{
    public enum TextAnchor { UpperLeft = 0, UpperCenter = 1, UpperRight = 2, MiddleLeft = 3, MiddleCenter = 4, MiddleRight = 5, LowerLeft = 6, LowerCenter = 7, LowerRight = 8 }
    public enum FontStyle { Normal = 0, Bold = 1, Italic = 2, BoldAndItalic = 3 }

    public partial class GUIContent
    {
        public GUIContent() => throw null;
        public GUIContent(string text) => throw null;
        public GUIContent(string text, string tooltip) => throw null;
        public string text { get => throw null; set => throw null; }
        public string tooltip { get => throw null; set => throw null; }
        public static GUIContent none => throw null;
    }

    public partial class GUIStyleState
    {
        public Color textColor { get => throw null; set => throw null; }
    }

    public partial class GUIStyle
    {
        public GUIStyle() => throw null;
        public GUIStyle(GUIStyle other) => throw null;
        public TextAnchor alignment { get => throw null; set => throw null; }
        public FontStyle fontStyle { get => throw null; set => throw null; }
        public int fontSize { get => throw null; set => throw null; }
        public bool wordWrap { get => throw null; set => throw null; }
        public bool richText { get => throw null; set => throw null; }
        public GUIStyleState normal { get => throw null; set => throw null; }
        public float fixedHeight { get => throw null; set => throw null; }
        public float fixedWidth { get => throw null; set => throw null; }
        public float CalcHeight(GUIContent content, float width) => throw null;
        public Vector2 CalcSize(GUIContent content) => throw null;
        public static GUIStyle none => throw null;
        public static implicit operator GUIStyle(string str) => throw null;
    }

    public sealed partial class GUISkin : ScriptableObject
    {
        public GUIStyle box { get => throw null; set => throw null; }
        public GUIStyle label { get => throw null; set => throw null; }
        public GUIStyle button { get => throw null; set => throw null; }
        public GUIStyle toggle { get => throw null; set => throw null; }
        public GUIStyle textField { get => throw null; set => throw null; }
        public GUIStyle window { get => throw null; set => throw null; }
    }

    public sealed partial class GUILayoutOption { }

    public partial class GUI
    {
        public abstract partial class Scope : IDisposable
        {
            protected abstract void CloseScope();
            public void Dispose() => throw null;
        }

        public static GUISkin skin { get => throw null; set => throw null; }
        public static Color color { get => throw null; set => throw null; }
        public static Color backgroundColor { get => throw null; set => throw null; }
        public static Color contentColor { get => throw null; set => throw null; }
        public static bool enabled { get => throw null; set => throw null; }
        public static bool changed { get => throw null; set => throw null; }
        public static int depth { get => throw null; set => throw null; }
        public static Matrix4x4 matrix { get => throw null; set => throw null; }
        public static void Label(Rect position, string text) => throw null;
        public static void Label(Rect position, string text, GUIStyle style) => throw null;
        public static void Box(Rect position, string text) => throw null;
        public static bool Button(Rect position, string text) => throw null;
        public static bool Toggle(Rect position, bool value, string text) => throw null;
        public static void DrawTexture(Rect position, Texture image) => throw null;
    }

    public partial class GUILayout
    {
        public static void Label(string text, params GUILayoutOption[] options) => throw null;
        public static void Label(string text, GUIStyle style, params GUILayoutOption[] options) => throw null;
        public static void Label(GUIContent content, params GUILayoutOption[] options) => throw null;
        public static void Label(GUIContent content, GUIStyle style, params GUILayoutOption[] options) => throw null;
        public static void Box(string text, params GUILayoutOption[] options) => throw null;
        public static bool Button(string text, params GUILayoutOption[] options) => throw null;
        public static bool Button(string text, GUIStyle style, params GUILayoutOption[] options) => throw null;
        public static bool Button(GUIContent content, params GUILayoutOption[] options) => throw null;
        public static bool Toggle(bool value, string text, params GUILayoutOption[] options) => throw null;
        public static string TextField(string text, params GUILayoutOption[] options) => throw null;
        public static float HorizontalSlider(float value, float leftValue, float rightValue, params GUILayoutOption[] options) => throw null;
        public static void Space(float pixels) => throw null;
        public static void FlexibleSpace() => throw null;
        public static void BeginArea(Rect screenRect) => throw null;
        public static void BeginArea(Rect screenRect, GUIStyle style) => throw null;
        public static void BeginArea(Rect screenRect, string text) => throw null;
        public static void BeginArea(Rect screenRect, string text, GUIStyle style) => throw null;
        public static void EndArea() => throw null;
        public static void BeginHorizontal(params GUILayoutOption[] options) => throw null;
        public static void BeginHorizontal(GUIStyle style, params GUILayoutOption[] options) => throw null;
        public static void EndHorizontal() => throw null;
        public static void BeginVertical(params GUILayoutOption[] options) => throw null;
        public static void BeginVertical(GUIStyle style, params GUILayoutOption[] options) => throw null;
        public static void EndVertical() => throw null;
        public static Vector2 BeginScrollView(Vector2 scrollPosition, params GUILayoutOption[] options) => throw null;
        public static void EndScrollView() => throw null;
        public static GUILayoutOption Width(float width) => throw null;
        public static GUILayoutOption Height(float height) => throw null;
        public static GUILayoutOption MinWidth(float minWidth) => throw null;
        public static GUILayoutOption MaxWidth(float maxWidth) => throw null;
        public static GUILayoutOption MinHeight(float minHeight) => throw null;
        public static GUILayoutOption MaxHeight(float maxHeight) => throw null;
        public static GUILayoutOption ExpandWidth(bool expand) => throw null;
        public static GUILayoutOption ExpandHeight(bool expand) => throw null;
    }

    public partial class GUIUtility
    {
        public static void ExitGUI() => throw null;
        public static int hotControl { get => throw null; set => throw null; }
        public static int keyboardControl { get => throw null; set => throw null; }
        public static void ScaleAroundPivot(Vector2 scale, Vector2 pivotPoint) => throw null;
    }

    public enum EventType { MouseDown = 0, MouseUp = 1, MouseMove = 2, MouseDrag = 3, KeyDown = 4, KeyUp = 5, ScrollWheel = 6, Repaint = 7, Layout = 8 }

    public sealed partial class Event
    {
        public static Event current { get => throw null; set => throw null; }
        public EventType type { get => throw null; set => throw null; }
        public KeyCode keyCode { get => throw null; set => throw null; }
        public void Use() => throw null;
    }
}
