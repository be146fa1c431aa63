// Declarations only (see ../README.md): 3D text (TextMesh), fonts and built-in resources.
namespace UnityEngine
{
    public enum TextAlignment { Left = 0, Center = 1, Right = 2 }

    public sealed partial class Font : Object
    {
        public Material material { get => throw null; set => throw null; }
    }

    public sealed partial class TextMesh : Component
    {
        public string text { get => throw null; set => throw null; }
        public Font font { get => throw null; set => throw null; }
        public int fontSize { get => throw null; set => throw null; }
        public float characterSize { get => throw null; set => throw null; }
        public float lineSpacing { get => throw null; set => throw null; }
        public TextAnchor anchor { get => throw null; set => throw null; }
        public TextAlignment alignment { get => throw null; set => throw null; }
        public bool richText { get => throw null; set => throw null; }
        public Color color { get => throw null; set => throw null; }
    }

    public sealed partial class Resources
    {
        public static T GetBuiltinResource<T>(string path) where T : Object => throw null;
    }
}
