using UnityEditor;
using UnityEngine;

namespace Mocap.Imu.Editor
{
    /// <summary>Draws a <see cref="ReadOnlyFieldAttribute"/> field disabled; long strings as a selectable box.</summary>
    [CustomPropertyDrawer(typeof(ReadOnlyFieldAttribute))]
    sealed class ReadOnlyFieldDrawer : PropertyDrawer
    {
        int TextLines(SerializedProperty property) =>
            property.propertyType == SerializedPropertyType.String ? ((ReadOnlyFieldAttribute)attribute).Lines : 1;

        public override float GetPropertyHeight(SerializedProperty property, GUIContent label)
        {
            int lines = TextLines(property);
            if (lines <= 1) return EditorGUI.GetPropertyHeight(property, label, true);
            return EditorGUIUtility.singleLineHeight + EditorGUIUtility.standardVerticalSpacing +
                   lines * EditorGUIUtility.singleLineHeight;
        }

        public override void OnGUI(Rect position, SerializedProperty property, GUIContent label)
        {
            int lines = TextLines(property);
            if (lines <= 1)
            {
                using (new EditorGUI.DisabledScope(true))
                    EditorGUI.PropertyField(position, property, label, true);
                return;
            }
            var labelRect = new Rect(position.x, position.y, position.width, EditorGUIUtility.singleLineHeight);
            EditorGUI.LabelField(labelRect, label);
            float top = labelRect.yMax + EditorGUIUtility.standardVerticalSpacing;
            var box = new Rect(position.x, top, position.width, position.yMax - top);
            // Selectable, not editable: the text can be copied (an error to report), not changed.
            EditorGUI.SelectableLabel(box, property.stringValue, EditorStyles.textArea);
        }
    }
}
