// Declarations only (see ../README.md): the attributes scripts put on components and fields.
using System;

namespace UnityEngine
{
    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public abstract partial class PropertyAttribute : Attribute
    {
        protected PropertyAttribute() => throw null;
        public int order { get => throw null; set => throw null; }
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public partial class TooltipAttribute : PropertyAttribute
    {
        public readonly string tooltip;
        public TooltipAttribute(string tooltip) => throw null;
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = true)]
    public partial class HeaderAttribute : PropertyAttribute
    {
        public readonly string header;
        public HeaderAttribute(string header) => throw null;
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = true)]
    public partial class SpaceAttribute : PropertyAttribute
    {
        public readonly float height;
        public SpaceAttribute() => throw null;
        public SpaceAttribute(float height) => throw null;
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public sealed partial class RangeAttribute : PropertyAttribute
    {
        public readonly float min;
        public readonly float max;
        public RangeAttribute(float min, float max) => throw null;
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public sealed partial class MinAttribute : PropertyAttribute
    {
        public readonly float min;
        public MinAttribute(float min) => throw null;
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public partial class TextAreaAttribute : PropertyAttribute
    {
        public readonly int minLines;
        public readonly int maxLines;
        public TextAreaAttribute() => throw null;
        public TextAreaAttribute(int minLines, int maxLines) => throw null;
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public partial class MultilineAttribute : PropertyAttribute
    {
        public MultilineAttribute() => throw null;
        public MultilineAttribute(int lines) => throw null;
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public sealed partial class SerializeField : Attribute { }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public sealed partial class SerializeReference : Attribute { }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public sealed partial class HideInInspector : Attribute { }

    [AttributeUsage(AttributeTargets.Class, Inherited = true, AllowMultiple = false)]
    public sealed partial class AddComponentMenu : Attribute
    {
        public AddComponentMenu(string menuName) => throw null;
        public AddComponentMenu(string menuName, int order) => throw null;
        public string componentMenu => throw null;
        public int componentOrder => throw null;
    }

    [AttributeUsage(AttributeTargets.Class, Inherited = false, AllowMultiple = false)]
    public sealed partial class CreateAssetMenuAttribute : Attribute
    {
        public string menuName { get => throw null; set => throw null; }
        public string fileName { get => throw null; set => throw null; }
        public int order { get => throw null; set => throw null; }
    }

    [AttributeUsage(AttributeTargets.Class, Inherited = true, AllowMultiple = true)]
    public partial class RequireComponent : Attribute
    {
        public Type m_Type0;
        public Type m_Type1;
        public Type m_Type2;
        public RequireComponent(Type requiredComponent) => throw null;
        public RequireComponent(Type requiredComponent, Type requiredComponent2) => throw null;
        public RequireComponent(Type requiredComponent, Type requiredComponent2, Type requiredComponent3) => throw null;
    }

    [AttributeUsage(AttributeTargets.Class, Inherited = false, AllowMultiple = false)]
    public sealed partial class DisallowMultipleComponent : Attribute { }

    [AttributeUsage(AttributeTargets.Class, Inherited = false, AllowMultiple = false)]
    public sealed partial class ExecuteAlways : Attribute { }

    [AttributeUsage(AttributeTargets.Class, Inherited = false, AllowMultiple = false)]
    public sealed partial class ExecuteInEditMode : Attribute { }

    [AttributeUsage(AttributeTargets.Class, Inherited = false, AllowMultiple = false)]
    public partial class DefaultExecutionOrder : Attribute
    {
        public DefaultExecutionOrder(int order) => throw null;
        public int order => throw null;
    }

    [AttributeUsage(AttributeTargets.Class, Inherited = false, AllowMultiple = false)]
    public partial class HelpURLAttribute : Attribute
    {
        public HelpURLAttribute(string url) => throw null;
        public virtual string URL => throw null;
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = true)]
    public partial class ContextMenuItemAttribute : PropertyAttribute
    {
        public readonly string name;
        public readonly string function;
        public ContextMenuItemAttribute(string name, string function) => throw null;
    }

    [AttributeUsage(AttributeTargets.Method, AllowMultiple = true)]
    public sealed partial class ContextMenu : Attribute
    {
        public ContextMenu(string itemName) => throw null;
    }

    public enum RuntimeInitializeLoadType { AfterSceneLoad = 0, BeforeSceneLoad = 1, AfterAssembliesLoaded = 2, BeforeSplashScreen = 3, SubsystemRegistration = 4 }

    [AttributeUsage(AttributeTargets.Method, AllowMultiple = false)]
    public partial class RuntimeInitializeOnLoadMethodAttribute : Attribute
    {
        public RuntimeInitializeOnLoadMethodAttribute() => throw null;
        public RuntimeInitializeOnLoadMethodAttribute(RuntimeInitializeLoadType loadType) => throw null;
        public RuntimeInitializeLoadType loadType { get => throw null; }
    }
}

namespace UnityEngine
{
    public partial interface ISerializationCallbackReceiver
    {
        void OnBeforeSerialize();
        void OnAfterDeserialize();
    }
}
