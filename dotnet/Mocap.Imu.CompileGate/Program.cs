// The Unity compile gate: compiles the package the way a Unity project would, without Unity.
// For each Unity version (2022.3, 6000.0) it first compiles the declaration-only Unity API of
// ../UnityApi, then one compilation per asmdef of the package and per target (the Linux editor,
// the Windows / Linux / macOS players, and the Android player, where the package is left out),
// with exactly the references, defines and options the asmdef gives it, then each sample alone,
// as a project that imported only that sample: the sample's own asmdefs, and its other scripts
// as Assembly-CSharp (Assembly-CSharp-Editor for its Editor/ folders).
// Prints one line per compile unit, the diagnostics of failed ones below it, and closes with
// "N compile units ok, N failed". Exit code 0 only when every unit compiled warning-free.
using System;
using System.Collections.Generic;
using System.IO;
using System.Linq;
using System.Reflection;
using Microsoft.CodeAnalysis;
using Microsoft.CodeAnalysis.CSharp;

namespace Mocap.Imu.CompileGate
{
    static class Program
    {
        static int Main(string[] args)
        {
            string packageDir = null;
            string unityApiDir = BuildMetadata("UnityApiDir");
            for (int i = 0; i < args.Length; i++)
            {
                if (args[i] == "--unity-api" && i + 1 < args.Length) unityApiDir = args[++i];
                else if (packageDir == null && !args[i].StartsWith("--", StringComparison.Ordinal)) packageDir = args[i];
                else return Usage($"unexpected argument '{args[i]}'");
            }
            if (packageDir == null) return Usage("no package folder given");
            if (!File.Exists(Path.Combine(packageDir, "package.json")))
                return Usage($"'{packageDir}' holds no package.json");
            if (unityApiDir == null || !Directory.Exists(unityApiDir))
                return Usage($"the Unity API sources '{unityApiDir}' do not exist");

            Package package;
            FrameworkReferences references;
            try
            {
                package = Package.Load(packageDir);
                references = new FrameworkReferences(BuildMetadata("NetStandardReferenceDir"), BuildMetadata("NUnitFrameworkDll"));
            }
            catch (GateException e)
            {
                Console.WriteLine($"error: {e.Message}");
                Console.WriteLine("0 compile units ok, 1 failed");
                return 1;
            }

            var report = new Report();
            foreach (var version in UnityVersion.All)
            {
                var api = UnityApi.Compile(unityApiDir, version, references, report);
                if (api == null) continue;
                foreach (var target in Target.All)
                {
                    var built = new Dictionary<string, MetadataReference>(StringComparer.Ordinal);
                    var packageAssemblies = package.AssembliesFor(target, version).ToList();
                    foreach (var asmdef in packageAssemblies)
                        built[asmdef.Name] = UnitCompiler.CompileAsmdef(package, package.Resolve, asmdef.Name, asmdef, target,
                            version, api, references, built, report);
                    var leftOut = package.Asmdefs.Except(packageAssemblies).Select(a => a.Name).ToList();
                    foreach (var sample in package.Samples)
                    {
                        UnitCompiler.CompileSample(package, sample, target, version, api, references, built, report);
                        var sampleAssemblies = package.AssembliesFor(sample, target, version);
                        leftOut.AddRange(sample.Asmdefs.Except(sampleAssemblies)
                            .Select(a => $"{package.Relative(sample.Folder)} {a.Name}"));
                    }
                    // Not units (Unity builds nothing of them there), but said, so that a target
                    // with few units shows why.
                    if (leftOut.Count > 0)
                        Console.WriteLine($"not built for [unity-{version.Name} {target.Name}] (platforms or " +
                                          $"defineConstraints): {string.Join(", ", leftOut)}");
                }
            }
            Console.WriteLine($"{report.Ok} compile units ok, {report.Failed} failed");
            return report.Failed == 0 && report.Ok > 0 ? 0 : 1;
        }

        static int Usage(string problem)
        {
            Console.Error.WriteLine($"error: {problem}");
            Console.Error.WriteLine("usage: Mocap.Imu.CompileGate PACKAGE_DIR [--unity-api UNITY_API_DIR]");
            return 2;
        }

        // Paths MSBuild knows (NuGet package folder, this project's folder), baked in at build time.
        static string BuildMetadata(string key) =>
            typeof(Program).Assembly.GetCustomAttributes<AssemblyMetadataAttribute>().FirstOrDefault(a => a.Key == key)?.Value;
    }

    sealed class GateException : Exception
    {
        public GateException(string message) : base(message) { }
    }

    sealed class Report
    {
        public int Ok, Failed;

        public void Unit(string name, UnityVersion version, string targetName, IReadOnlyList<string> problems)
        {
            string label = $"compile unit {name} [unity-{version.Name} {targetName}]";
            if (problems.Count == 0)
            {
                Ok++;
                Console.WriteLine($"{label}: ok");
                return;
            }
            Failed++;
            Console.WriteLine($"{label}: FAILED");
            foreach (var p in problems) Console.WriteLine($"  {p}");
        }
    }
}
