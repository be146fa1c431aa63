// Declarations only (see ../README.md): logging, application, time, input, screen.
using System;

namespace UnityEngine
{
    public enum LogType { Error = 0, Assert = 1, Warning = 2, Log = 3, Exception = 4 }

    public partial class Debug
    {
        public static void Log(object message) => throw null;
        public static void Log(object message, Object context) => throw null;
        public static void LogFormat(string format, params object[] args) => throw null;
        public static void LogWarning(object message) => throw null;
        public static void LogWarning(object message, Object context) => throw null;
        public static void LogWarningFormat(string format, params object[] args) => throw null;
        public static void LogError(object message) => throw null;
        public static void LogError(object message, Object context) => throw null;
        public static void LogErrorFormat(string format, params object[] args) => throw null;
        public static void LogException(Exception exception) => throw null;
        public static void LogException(Exception exception, Object context) => throw null;
        public static void Assert(bool condition) => throw null;
        public static void Assert(bool condition, string message) => throw null;
        public static void DrawLine(Vector3 start, Vector3 end, Color color) => throw null;
        public static void DrawRay(Vector3 start, Vector3 dir, Color color) => throw null;
        public static bool isDebugBuild => throw null;
    }

    // The platform values of the targets the package supports, as Unity numbers them.
    public enum RuntimePlatform
    {
        OSXEditor = 0,
        OSXPlayer = 1,
        WindowsPlayer = 2,
        WindowsEditor = 7,
        IPhonePlayer = 8,
        Android = 11,
        LinuxPlayer = 13,
        LinuxEditor = 16,
        WebGLPlayer = 17,
        WSAPlayerX86 = 18,
        WSAPlayerX64 = 19,
        WSAPlayerARM = 20,
        PS4 = 25,
        XboxOne = 27,
        tvOS = 31,
        Switch = 32,
    }

    public sealed partial class Application
    {
        public static string dataPath => throw null;
        public static string streamingAssetsPath => throw null;
        public static string persistentDataPath => throw null;
        public static string temporaryCachePath => throw null;
        public static RuntimePlatform platform => throw null;
        public static bool isEditor => throw null;
        public static bool isPlaying => throw null;
        public static bool isFocused => throw null;
        public static bool isBatchMode => throw null;
        public static bool runInBackground { get => throw null; set => throw null; }
        public static int targetFrameRate { get => throw null; set => throw null; }
        public static string productName => throw null;
        public static string companyName => throw null;
        public static string version => throw null;
        public static string unityVersion => throw null;
        public static void Quit() => throw null;
        public static void OpenURL(string url) => throw null;
        public delegate void LogCallback(string condition, string stackTrace, LogType type);
        public static event LogCallback logMessageReceived { add => throw null; remove => throw null; }
        public static event LogCallback logMessageReceivedThreaded { add => throw null; remove => throw null; }
        public static event Action quitting { add => throw null; remove => throw null; }
    }

    public partial class Time
    {
        public static float time => throw null;
        public static double timeAsDouble => throw null;
        public static float deltaTime => throw null;
        public static float unscaledTime => throw null;
        public static double unscaledTimeAsDouble => throw null;
        public static float unscaledDeltaTime => throw null;
        public static float fixedDeltaTime { get => throw null; set => throw null; }
        public static float fixedTime => throw null;
        public static float timeScale { get => throw null; set => throw null; }
        public static int frameCount => throw null;
        public static float realtimeSinceStartup => throw null;
        public static double realtimeSinceStartupAsDouble => throw null;
    }

    public sealed partial class Screen
    {
        public static int width => throw null;
        public static int height => throw null;
        public static float dpi => throw null;
    }

    public sealed partial class Input
    {
        public static bool GetKeyDown(KeyCode key) => throw null;
        public static bool GetKeyDown(string name) => throw null;
        public static bool GetKey(KeyCode key) => throw null;
        public static bool GetKeyUp(KeyCode key) => throw null;
        public static bool GetMouseButtonDown(int button) => throw null;
        public static Vector3 mousePosition => throw null;
        public static bool anyKeyDown => throw null;
    }

    // The keys most scripts bind, with Unity's values.
    public enum KeyCode
    {
        None = 0, Backspace = 8, Tab = 9, Clear = 12, Return = 13, Pause = 19, Escape = 27, Space = 32,
        Alpha0 = 48, Alpha1 = 49, Alpha2 = 50, Alpha3 = 51, Alpha4 = 52, Alpha5 = 53, Alpha6 = 54, Alpha7 = 55, Alpha8 = 56, Alpha9 = 57,
        A = 97, B = 98, C = 99, D = 100, E = 101, F = 102, G = 103, H = 104, I = 105, J = 106, K = 107, L = 108, M = 109,
        N = 110, O = 111, P = 112, Q = 113, R = 114, S = 115, T = 116, U = 117, V = 118, W = 119, X = 120, Y = 121, Z = 122,
        Delete = 127, UpArrow = 273, DownArrow = 274, RightArrow = 275, LeftArrow = 276, Insert = 277, Home = 278, End = 279,
        PageUp = 280, PageDown = 281,
        F1 = 282, F2 = 283, F3 = 284, F4 = 285, F5 = 286, F6 = 287, F7 = 288, F8 = 289, F9 = 290, F10 = 291, F11 = 292, F12 = 293,
        F13 = 294, F14 = 295, F15 = 296,
        RightShift = 303, LeftShift = 304, RightControl = 305, LeftControl = 306, RightAlt = 307, LeftAlt = 308,
        Mouse0 = 323, Mouse1 = 324, Mouse2 = 325,
    }
}

namespace UnityEngine
{
    public static partial class JsonUtility
    {
        public static string ToJson(object obj) => throw null;
        public static string ToJson(object obj, bool prettyPrint) => throw null;
        public static T FromJson<T>(string json) => throw null;
        public static object FromJson(string json, System.Type type) => throw null;
        public static void FromJsonOverwrite(string json, object objectToOverwrite) => throw null;
    }
}
