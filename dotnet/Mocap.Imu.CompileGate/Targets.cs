using System.Collections.Generic;
using System.Linq;

namespace Mocap.Imu.CompileGate
{
    /// <summary>A Unity version the gate compiles for, with the version defines Unity sets for it.</summary>
    sealed class UnityVersion
    {
        public readonly string Name;
        public readonly string[] Defines;

        UnityVersion(string name, int major, int minor)
        {
            Name = name;
            Defines = VersionDefines(major, minor).ToArray();
        }

        public static readonly UnityVersion[] All = { new UnityVersion("2022.3", 2022, 3), new UnityVersion("6000.0", 6000, 0) };

        // Unity defines UNITY_X_Y_OR_NEWER for every release up to this one (5.3 on), and
        // UNITY_X, UNITY_X_Y for this one.
        static IEnumerable<string> VersionDefines(int major, int minor)
        {
            for (int m = 3; m <= 6; m++) yield return $"UNITY_5_{m}_OR_NEWER";
            var releases = new List<(int, int)>();
            for (int year = 2017; year <= 2023; year++)
            {
                int lastMinor = year <= 2019 ? 4 : year <= 2022 ? 3 : 2;
                for (int m = 1; m <= lastMinor; m++) releases.Add((year, m));
            }
            releases.Add((6000, 0));
            foreach (var (y, m) in releases)
            {
                if (y > major || (y == major && m > minor)) break;
                yield return $"UNITY_{y}_{m}_OR_NEWER";
            }
            yield return $"UNITY_{major}";
            yield return $"UNITY_{major}_{minor}";
        }
    }

    /// <summary>
    /// A compile target: the Linux editor, a standalone player, or the Android player (a platform
    /// without the native plugin). Its asmdef platform name, the defines Unity sets for it, and
    /// whether editor-only assemblies and UnityEditor exist there.
    /// </summary>
    sealed class Target
    {
        public readonly string Name;
        public readonly string AsmdefPlatform;
        public readonly bool IsEditor;
        public readonly string[] Defines;

        Target(string name, string asmdefPlatform, bool isEditor, params string[] defines)
        {
            Name = name;
            AsmdefPlatform = asmdefPlatform;
            IsEditor = isEditor;
            Defines = Common.Concat(defines).ToArray();
        }

        static readonly string[] Common =
        {
            "NET_STANDARD_2_1", "NET_STANDARD", "NETSTANDARD2_1", "NETSTANDARD", "CSHARP_7_3_OR_NEWER", "UNITY_64",
        };

        // The editor runs on Linux with the Linux player as active build target, the test framework
        // present (UNITY_INCLUDE_TESTS) and the old input manager; the players vary the scripting
        // backend and the active input handling so that both sides of those #ifs compile. Android
        // (ARM64, so IL2CPP) stands for every platform outside the package's includePlatforms, as
        // a Quest or phone project builds it: what the package leaves out there must not be needed.
        public static readonly Target[] All =
        {
            new Target("editor", "Editor", true, "UNITY_EDITOR", "UNITY_EDITOR_64", "UNITY_EDITOR_LINUX",
                "UNITY_STANDALONE", "UNITY_STANDALONE_LINUX", "UNITY_INCLUDE_TESTS", "UNITY_ASSERTIONS", "ENABLE_MONO",
                "ENABLE_LEGACY_INPUT_MANAGER", "DEBUG", "TRACE"),
            new Target("player-windows", "WindowsStandalone64", false, "UNITY_STANDALONE", "UNITY_STANDALONE_WIN",
                "ENABLE_IL2CPP", "ENABLE_LEGACY_INPUT_MANAGER"),
            new Target("player-linux", "LinuxStandalone64", false, "UNITY_STANDALONE", "UNITY_STANDALONE_LINUX",
                "ENABLE_MONO", "ENABLE_INPUT_SYSTEM"),
            new Target("player-macos", "macOSStandalone", false, "UNITY_STANDALONE", "UNITY_STANDALONE_OSX",
                "ENABLE_IL2CPP", "ENABLE_LEGACY_INPUT_MANAGER", "ENABLE_INPUT_SYSTEM"),
            new Target("player-android", "Android", false, "UNITY_ANDROID", "ENABLE_IL2CPP", "ENABLE_INPUT_SYSTEM"),
        };
    }
}
