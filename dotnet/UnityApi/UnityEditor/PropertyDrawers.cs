// Declarations only (see ../README.md): custom property drawers and the serialized-property GUI.
using System;
using System.Reflection;
using UnityEngine;

namespace UnityEditor
{
    [AttributeUsage(AttributeTargets.Class, AllowMultiple = true, Inherited = false)]
    public sealed partial class CustomPropertyDrawer : Attribute
    {
        public CustomPropertyDrawer(Type type) => throw null;
        public CustomPropertyDrawer(Type type, bool useForChildren) => throw null;
    }

    public abstract partial class GUIDrawer { }

    public abstract partial class DecoratorDrawer : GUIDrawer
    {
        public PropertyAttribute attribute => throw null;
        public virtual void OnGUI(Rect position) => throw null;
        public virtual float GetHeight() => throw null;
    }

    public abstract partial class PropertyDrawer : GUIDrawer
    {
        public PropertyAttribute attribute => throw null;
        public FieldInfo fieldInfo => throw null;
        public string preferredLabel => throw null;
        public virtual void OnGUI(Rect position, SerializedProperty property, GUIContent label) => throw null;
        public virtual float GetPropertyHeight(SerializedProperty property, GUIContent label) => throw null;
        public virtual bool CanCacheInspectorGUI(SerializedProperty property) => throw null;
    }

    public enum SerializedPropertyType
    {
        Generic = -1, Integer = 0, Boolean = 1, Float = 2, String = 3, Color = 4, ObjectReference = 5,
        LayerMask = 6, Enum = 7, Vector2 = 8, Vector3 = 9, Vector4 = 10, Rect = 11, ArraySize = 12,
        Character = 13, AnimationCurve = 14, Bounds = 15, Gradient = 16, Quaternion = 17,
        ExposedReference = 18, FixedBufferSize = 19, Vector2Int = 20, Vector3Int = 21, RectInt = 22,
        BoundsInt = 23, ManagedReference = 24, Hash128 = 25,
    }

    public partial class SerializedProperty
    {
        public SerializedPropertyType propertyType => throw null;
        public string displayName => throw null;
        public string tooltip => throw null;
        public bool isArray => throw null;
        public int arraySize { get => throw null; set => throw null; }
        public SerializedObject serializedObject => throw null;
        public SerializedProperty FindPropertyRelative(string relativePropertyPath) => throw null;
        public SerializedProperty GetArrayElementAtIndex(int index) => throw null;
    }

    public sealed partial class EditorGUI
    {
        public static float GetPropertyHeight(SerializedProperty property, bool includeChildren) => throw null;
        public static float GetPropertyHeight(SerializedProperty property, GUIContent label = null, bool includeChildren = true) => throw null;
        public static bool PropertyField(Rect position, SerializedProperty property, bool includeChildren = false) => throw null;
        public static bool PropertyField(Rect position, SerializedProperty property, GUIContent label, bool includeChildren = false) => throw null;
        public static void LabelField(Rect position, GUIContent label) => throw null;
        public static void LabelField(Rect position, string label, GUIStyle style) => throw null;
        public static void LabelField(Rect position, GUIContent label, GUIStyle style) => throw null;
        public static void LabelField(Rect position, string label, string label2) => throw null;
        public static void SelectableLabel(Rect position, string text) => throw null;
        public static void SelectableLabel(Rect position, string text, GUIStyle style) => throw null;
        public static Rect PrefixLabel(Rect totalPosition, GUIContent label) => throw null;
        public static GUIContent BeginProperty(Rect totalPosition, GUIContent label, SerializedProperty property) => throw null;
        public static void EndProperty() => throw null;
    }

    public sealed partial class EditorGUIUtility
    {
        public static float standardVerticalSpacing => throw null;
    }
}
