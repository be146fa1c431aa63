// Declarations only (see ../README.md): the Unity Test Framework's runtime side.
using System;
using System.Text.RegularExpressions;
using UnityEngine;

namespace UnityEngine.TestTools
{
    [AttributeUsage(AttributeTargets.Method, AllowMultiple = false)]
    public partial class UnityTestAttribute : Attribute { }

    [AttributeUsage(AttributeTargets.Method, AllowMultiple = false)]
    public partial class UnitySetUpAttribute : Attribute { }

    [AttributeUsage(AttributeTargets.Method, AllowMultiple = false)]
    public partial class UnityTearDownAttribute : Attribute { }

    [AttributeUsage(AttributeTargets.Class | AttributeTargets.Method | AttributeTargets.Assembly, AllowMultiple = true)]
    public partial class UnityPlatformAttribute : Attribute
    {
        public UnityPlatformAttribute() => throw null;
        public UnityPlatformAttribute(params RuntimePlatform[] include) => throw null;
        public RuntimePlatform[] include { get => throw null; set => throw null; }
        public RuntimePlatform[] exclude { get => throw null; set => throw null; }
    }

    public static partial class LogAssert
    {
        public static void Expect(LogType type, string message) => throw null;
        public static void Expect(LogType type, Regex message) => throw null;
        public static void NoUnexpectedReceived() => throw null;
        public static bool ignoreFailingMessages { get => throw null; set => throw null; }
    }
}
