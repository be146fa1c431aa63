using System;
using System.Collections.Generic;
using System.IO;
using System.Linq;
using System.Text;
using Microsoft.CodeAnalysis;
using Microsoft.CodeAnalysis.CSharp;

namespace Mocap.Imu.CompileGate
{
    /// <summary>The reference assemblies that are not Unity's: .NET Standard 2.1 and NUnit.</summary>
    sealed class FrameworkReferences
    {
        public readonly MetadataReference[] NetStandard;
        public readonly MetadataReference NUnit;

        public FrameworkReferences(string netStandardDir, string nunitDll)
        {
            if (netStandardDir == null || !File.Exists(Path.Combine(netStandardDir, "netstandard.dll")))
                throw new GateException($"netstandard.dll not found in '{netStandardDir}' (restore NETStandard.Library.Ref 2.1.0)");
            if (nunitDll == null || !File.Exists(nunitDll))
                throw new GateException($"nunit.framework.dll not found at '{nunitDll}' (restore NUnit 3.14.0)");
            NetStandard = Directory.GetFiles(netStandardDir, "*.dll").OrderBy(f => f, StringComparer.Ordinal)
                .Select(f => (MetadataReference)MetadataReference.CreateFromFile(f)).ToArray();
            NUnit = MetadataReference.CreateFromFile(nunitDll);
        }
    }

    /// <summary>The Unity API assemblies of one Unity version, compiled from ../UnityApi.</summary>
    sealed class UnityApi
    {
        public MetadataReference Engine, Editor, EngineTestRunner, EditorTestRunner;

        public static UnityApi Compile(string dir, UnityVersion version, FrameworkReferences framework, Report report)
        {
            var api = new UnityApi();
            bool ok = true;
            MetadataReference Build(string name, params MetadataReference[] refs)
            {
                var folder = Path.Combine(dir, name);
                var sources = Directory.Exists(folder)
                    ? Directory.GetFiles(folder, "*.cs", SearchOption.AllDirectories).OrderBy(f => f, StringComparer.Ordinal).ToList()
                    : new List<string>();
                var compilation = UnitCompiler.Create(name, sources, version.Defines, allowUnsafe: false,
                    framework.NetStandard.Concat(refs.Where(r => r != null)));
                var problems = UnitCompiler.Problems(compilation, dir);
                if (sources.Count == 0) problems.Insert(0, $"no sources in {folder}");
                ok &= problems.Count == 0;
                report.Unit($"UnityApi/{name}", version, "api", problems);
                return compilation.ToMetadataReference();
            }
            api.Engine = Build("UnityEngine");
            api.Editor = Build("UnityEditor", api.Engine);
            api.EngineTestRunner = Build("UnityEngine.TestRunner", api.Engine, framework.NUnit);
            api.EditorTestRunner = Build("UnityEditor.TestRunner", api.Engine, api.Editor, api.EngineTestRunner, framework.NUnit);
            return ok ? api : null;
        }
    }

    static class UnitCompiler
    {
        // PlayerSettings.suppressCommonWarnings, on by default in every project, passes these to
        // the compiler as -nowarn: fields never assigned or never used (CS0649, CS0169: the
        // inspector assigns serialised fields) and the assembly-version unification notes
        // (CS1701, CS1702: netstandard2.0 libraries such as nunit.framework under .NET Standard
        // 2.1), and CS0282 (partial struct field order). See the README.
        static readonly string[] CommonWarnings = { "CS0169", "CS0649", "CS0282", "CS1701", "CS1702" };

        /// <summary>
        /// A compilation as Unity's compiler pipeline sets it up: C# 9, a library, warning level 4,
        /// and (the gate's rule) every warning an error.
        /// </summary>
        public static CSharpCompilation Create(string assemblyName, IEnumerable<string> sources, IEnumerable<string> defines,
                                               bool allowUnsafe, IEnumerable<MetadataReference> references)
        {
            var parse = new CSharpParseOptions(LanguageVersion.CSharp9, preprocessorSymbols: defines.Distinct().ToArray());
            var trees = sources.Select(f => CSharpSyntaxTree.ParseText(File.ReadAllText(f), parse, f, Encoding.UTF8));
            var options = new CSharpCompilationOptions(OutputKind.DynamicallyLinkedLibrary,
                allowUnsafe: allowUnsafe, warningLevel: 4, generalDiagnosticOption: ReportDiagnostic.Error,
                nullableContextOptions: NullableContextOptions.Disable, concurrentBuild: false,
                specificDiagnosticOptions: CommonWarnings.ToDictionary(id => id, _ => ReportDiagnostic.Suppress));
            return CSharpCompilation.Create(assemblyName, trees, references, options);
        }

        /// <summary>Errors (warnings included, as errors) as "file:line: error CSxxxx: message".</summary>
        public static List<string> Problems(Compilation compilation, string root) =>
            compilation.GetDiagnostics()
                .Where(d => d.Severity == DiagnosticSeverity.Error && !d.IsSuppressed)
                .Select(d => Format(d, root)).Distinct().ToList();

        static string Format(Diagnostic d, string root)
        {
            if (!d.Location.IsInSource) return $"error {d.Id}: {d.GetMessage()}";
            var span = d.Location.GetLineSpan();
            var path = Path.GetRelativePath(root, span.Path).Replace('\\', '/');
            return $"{path}:{span.StartLinePosition.Line + 1}: error {d.Id}: {d.GetMessage()}";
        }

        static IEnumerable<MetadataReference> EngineReferences(UnityApi api, Target target) =>
            target.IsEditor ? new[] { api.Engine, api.Editor } : new[] { api.Engine };

        /// <summary>
        /// Compiles one asmdef with exactly its references, defines and options. resolve finds the
        /// asmdef a reference names among those it can see; built holds the ones compiled for
        /// this target. unitName: how the report names it.
        /// </summary>
        public static MetadataReference CompileAsmdef(Package package, Func<string, Asmdef> resolve, string unitName,
                                                      Asmdef asmdef, Target target, UnityVersion version,
                                                      UnityApi api, FrameworkReferences framework,
                                                      IReadOnlyDictionary<string, MetadataReference> built, Report report)
        {
            var problems = new List<string>();
            var references = new List<MetadataReference>(framework.NetStandard);
            if (!asmdef.NoEngineReferences) references.AddRange(EngineReferences(api, target));
            foreach (var name in asmdef.References)
            {
                var own = resolve(name);
                if (own != null)
                {
                    // Unity drops a reference to an assembly that is not built for this target.
                    if (built.TryGetValue(own.Name, out var reference)) references.Add(reference);
                    continue;
                }
                switch (name)
                {
                    case "UnityEngine.TestRunner": references.Add(api.EngineTestRunner); break;
                    case "UnityEditor.TestRunner": if (target.IsEditor) references.Add(api.EditorTestRunner); break;
                    default: problems.Add($"{package.Relative(asmdef.Path)}: reference '{name}' is neither an asmdef it can see nor a Unity assembly the gate knows"); break;
                }
            }
            // Without overrideReferences Unity adds every auto-referenced precompiled assembly of
            // the project; the gate's project has none (nunit.framework.dll is not auto-referenced).
            if (asmdef.OverrideReferences)
                foreach (var dll in asmdef.PrecompiledReferences)
                {
                    if (dll == "nunit.framework.dll") references.Add(framework.NUnit);
                    else problems.Add($"{package.Relative(asmdef.Path)}: precompiled reference '{dll}' is not one the gate provides");
                }
            var compilation = Create(asmdef.Name, asmdef.Sources, version.Defines.Concat(target.Defines),
                asmdef.AllowUnsafeCode, references);
            problems.AddRange(Problems(compilation, package.Root));
            if (target.IsEditor) problems.AddRange(InspectorTooltips.Check(compilation, package));
            report.Unit(unitName, version, target.Name, problems);
            return compilation.ToMetadataReference();
        }

        /// <summary>
        /// A project that imported only this sample: its asmdefs built for the target (none of
        /// them is a unit where its platforms leave it out, as with the package's own), then the
        /// scripts outside them as Assembly-CSharp, which sees every auto-referenced assembly.
        /// </summary>
        public static void CompileSample(Package package, Sample sample, Target target, UnityVersion version, UnityApi api,
                                         FrameworkReferences framework, IReadOnlyDictionary<string, MetadataReference> packageBuilt,
                                         Report report)
        {
            var name = package.Relative(sample.Folder);
            var built = new Dictionary<string, MetadataReference>(packageBuilt, StringComparer.Ordinal);
            foreach (var asmdef in package.AssembliesFor(sample, target, version))
                built[asmdef.Name] = CompileAsmdef(package, r => package.Resolve(sample, r), $"{name} {asmdef.Name}",
                    asmdef, target, version, api, framework, built, report);

            bool hasLooseScripts = sample.RuntimeSources.Count > 0 || sample.EditorSources.Count > 0;
            if (sample.HasScripts && !hasLooseScripts) return;
            var autoReferenced = package.Asmdefs.Concat(sample.Asmdefs)
                .Where(a => a.AutoReferenced && built.ContainsKey(a.Name)).Select(a => built[a.Name]);
            var references = framework.NetStandard.Concat(EngineReferences(api, target)).Concat(autoReferenced).ToList();
            var defines = version.Defines.Concat(target.Defines).ToList();

            var runtime = Create("Assembly-CSharp", sample.RuntimeSources, defines, false, references);
            var problems = Problems(runtime, package.Root);
            if (!sample.HasScripts) problems.Add($"{name}: the sample has no scripts");
            if (target.IsEditor) problems.AddRange(InspectorTooltips.Check(runtime, package));
            report.Unit($"{name} Assembly-CSharp", version, target.Name, problems);

            if (!target.IsEditor || sample.EditorSources.Count == 0) return;
            var editor = Create("Assembly-CSharp-Editor", sample.EditorSources, defines, false,
                references.Append(runtime.ToMetadataReference()));
            report.Unit($"{name} Assembly-CSharp-Editor", version, target.Name, Problems(editor, package.Root));
        }
    }
}
