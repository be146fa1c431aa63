// Declarations only (see ../README.md): cameras, lights, primitives, textures, canvases.
using System;

namespace UnityEngine
{
    public enum PrimitiveType { Sphere = 0, Capsule = 1, Cylinder = 2, Cube = 3, Plane = 4, Quad = 5 }
    public enum LightType
    {
        Spot = 0, Directional = 1, Point = 2,
#if UNITY_6000_0_OR_NEWER
        Rectangle = 3,
#endif
        Area = 3, Disc = 4,
    }
    public enum LightShadows { None = 0, Hard = 1, Soft = 2 }
    public enum RenderMode { ScreenSpaceOverlay = 0, ScreenSpaceCamera = 1, WorldSpace = 2 }

    public partial class Texture : Object
    {
        public virtual int width { get => throw null; set => throw null; }
        public virtual int height { get => throw null; set => throw null; }
    }

    public sealed partial class Texture2D : Texture
    {
        public Texture2D(int width, int height) => throw null;
        public void SetPixel(int x, int y, Color color) => throw null;
        public void Apply() => throw null;
        public static Texture2D whiteTexture => throw null;
    }

    public partial class Shader : Object
    {
        public static Shader Find(string name) => throw null;
    }

    public partial class Material : Object
    {
        public Material(Shader shader) => throw null;
        public Material(Material source) => throw null;
        public Color color { get => throw null; set => throw null; }
    }

    public partial class Renderer : Component
    {
        public bool enabled { get => throw null; set => throw null; }
        public Material material { get => throw null; set => throw null; }
        public Material sharedMaterial { get => throw null; set => throw null; }
    }

    public partial class MeshRenderer : Renderer { }

    public partial class Camera : Behaviour
    {
        public static Camera main => throw null;
        public float fieldOfView { get => throw null; set => throw null; }
        public float nearClipPlane { get => throw null; set => throw null; }
        public float farClipPlane { get => throw null; set => throw null; }
        public Color backgroundColor { get => throw null; set => throw null; }
        public Vector3 WorldToScreenPoint(Vector3 position) => throw null;
        public Vector3 ScreenToWorldPoint(Vector3 position) => throw null;
    }

    public sealed partial class Light : Behaviour
    {
        public LightType type { get => throw null; set => throw null; }
        public Color color { get => throw null; set => throw null; }
        public float intensity { get => throw null; set => throw null; }
        public LightShadows shadows { get => throw null; set => throw null; }
    }

    public sealed partial class Canvas : Behaviour
    {
        public RenderMode renderMode { get => throw null; set => throw null; }
        public Camera worldCamera { get => throw null; set => throw null; }
        public float scaleFactor { get => throw null; set => throw null; }
        public int sortingOrder { get => throw null; set => throw null; }
    }

    public partial class RectTransform : Transform
    {
        public Vector2 sizeDelta { get => throw null; set => throw null; }
        public Vector2 anchoredPosition { get => throw null; set => throw null; }
        public Vector2 anchorMin { get => throw null; set => throw null; }
        public Vector2 anchorMax { get => throw null; set => throw null; }
        public Vector2 pivot { get => throw null; set => throw null; }
    }
}

namespace UnityEngine.XR
{
    public static partial class XRSettings
    {
        public static bool enabled { get => throw null; set => throw null; }
        public static bool isDeviceActive => throw null;
        public static string loadedDeviceName => throw null;
    }
}

namespace UnityEngine.LowLevel
{
    public partial struct PlayerLoopSystem
    {
        public Type type;
        public PlayerLoopSystem[] subSystemList;
        public UpdateFunction updateDelegate;
        public IntPtr updateFunction;
        public IntPtr loopConditionFunction;
        public delegate void UpdateFunction();
        public override string ToString() => throw null;
    }

    public partial class PlayerLoop
    {
        public static PlayerLoopSystem GetDefaultPlayerLoop() => throw null;
        public static PlayerLoopSystem GetCurrentPlayerLoop() => throw null;
        public static void SetPlayerLoop(PlayerLoopSystem loop) => throw null;
    }
}

namespace UnityEngine.PlayerLoop
{
    public partial struct Initialization { }
    public partial struct EarlyUpdate { }
    public partial struct FixedUpdate { }
    public partial struct PreUpdate { }
    public partial struct Update { }
    public partial struct PreLateUpdate { }
    public partial struct PostLateUpdate { }
    public partial struct TimeUpdate { }
}

namespace UnityEngine.SceneManagement
{
    public partial struct Scene
    {
        public string name => throw null;
        public string path => throw null;
        public bool isLoaded => throw null;
        public GameObject[] GetRootGameObjects() => throw null;
    }

    public partial class SceneManager
    {
        public static Scene GetActiveScene() => throw null;
        public static void LoadScene(string sceneName) => throw null;
    }
}
