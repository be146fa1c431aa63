using System;
using System.Collections.Generic;
using System.IO;
using System.Linq;
using System.Text.Json;

namespace Mocap.Imu.CompileGate
{
    /// <summary>One .asmdef of the package, with the sources it owns.</summary>
    sealed class Asmdef
    {
        public string Name, Path, Folder, Guid;
        public string[] References = Array.Empty<string>();
        public string[] IncludePlatforms = Array.Empty<string>();
        public string[] ExcludePlatforms = Array.Empty<string>();
        public string[] PrecompiledReferences = Array.Empty<string>();
        public string[] DefineConstraints = Array.Empty<string>();
        public bool AllowUnsafeCode, OverrideReferences, NoEngineReferences, AutoReferenced = true;
        public bool HasVersionDefines;
        public readonly List<string> Sources = new List<string>();

        // Unity's rule: an empty include list means every platform except the excluded ones.
        public bool BuildsFor(Target target) =>
            IncludePlatforms.Length > 0
                ? IncludePlatforms.Contains(target.AsmdefPlatform)
                : !ExcludePlatforms.Contains(target.AsmdefPlatform);

        // Every constraint must hold; "!SYMBOL" holds when SYMBOL is undefined, and "A || B" when either does.
        public bool ConstraintsHold(ISet<string> defines) =>
            DefineConstraints.All(c => c.Split("||").Any(term =>
            {
                var t = term.Trim();
                return t.StartsWith("!", StringComparison.Ordinal) ? !defines.Contains(t.Substring(1)) : defines.Contains(t);
            }));
    }

    /// <summary>
    /// A sample of package.json's "samples", compiled as a user's project that imported only it:
    /// its own asmdefs, and the scripts outside them as Assembly-CSharp (Assembly-CSharp-Editor
    /// under an Editor/ folder).
    /// </summary>
    sealed class Sample
    {
        public string DisplayName, Folder;
        public readonly List<Asmdef> Asmdefs = new List<Asmdef>();
        public readonly List<string> RuntimeSources = new List<string>();
        public readonly List<string> EditorSources = new List<string>();

        public bool HasScripts => RuntimeSources.Count > 0 || EditorSources.Count > 0 || Asmdefs.Any(a => a.Sources.Count > 0);
    }

    sealed class Package
    {
        public string Root;
        public readonly List<Asmdef> Asmdefs = new List<Asmdef>();
        public readonly List<Sample> Samples = new List<Sample>();

        public string Relative(string path) => System.IO.Path.GetRelativePath(Root, path).Replace('\\', '/');

        public static Package Load(string root)
        {
            var package = new Package { Root = System.IO.Path.GetFullPath(root) };
            var files = UnitySources(package.Root).ToList();
            foreach (var asmdefPath in files.Where(f => f.EndsWith(".asmdef", StringComparison.Ordinal)))
                package.Asmdefs.Add(ReadAsmdef(asmdefPath));
            var duplicate = package.Asmdefs.GroupBy(a => a.Name).FirstOrDefault(g => g.Count() > 1);
            if (duplicate != null) throw new GateException($"two asmdefs are named {duplicate.Key}");
            foreach (var source in files.Where(f => f.EndsWith(".cs", StringComparison.Ordinal)))
            {
                var owner = OwningAsmdef(package.Asmdefs, source);
                if (owner == null)
                    throw new GateException($"{package.Relative(source)} belongs to no asmdef (a package's scripts need one)");
                owner.Sources.Add(source);
            }
            package.LoadSamples();
            // A user may import several samples next to the package: every name must stay unique.
            var everyName = package.Asmdefs.Select(a => (a.Name, Where: package.Relative(a.Path)))
                .Concat(package.Samples.SelectMany(s => s.Asmdefs.Select(a => (a.Name, Where: package.Relative(a.Path)))));
            var clash = everyName.GroupBy(n => n.Name).FirstOrDefault(g => g.Count() > 1);
            if (clash != null)
                throw new GateException($"two asmdefs are named {clash.Key} ({string.Join(", ", clash.Select(n => n.Where))})");
            return package;
        }

        // Unity imports neither hidden folders nor those whose name ends in '~' (Samples~, Native~).
        static IEnumerable<string> UnitySources(string folder)
        {
            foreach (var file in Directory.GetFiles(folder).OrderBy(f => f, StringComparer.Ordinal))
                if (!System.IO.Path.GetFileName(file).StartsWith(".", StringComparison.Ordinal)) yield return file;
            foreach (var sub in Directory.GetDirectories(folder).OrderBy(f => f, StringComparer.Ordinal))
            {
                var name = System.IO.Path.GetFileName(sub);
                if (name.StartsWith(".", StringComparison.Ordinal) || name.EndsWith("~", StringComparison.Ordinal)) continue;
                foreach (var f in UnitySources(sub)) yield return f;
            }
        }

        // A script belongs to the asmdef in the nearest folder above it.
        static Asmdef OwningAsmdef(IEnumerable<Asmdef> asmdefs, string source) =>
            asmdefs.Where(a => source.StartsWith(a.Folder + System.IO.Path.DirectorySeparatorChar, StringComparison.Ordinal))
                   .OrderByDescending(a => a.Folder.Length).FirstOrDefault();

        static Asmdef ReadAsmdef(string path)
        {
            try
            {
                using var doc = JsonDocument.Parse(File.ReadAllText(path));
                var root = doc.RootElement;
                string[] Strings(string key) => root.TryGetProperty(key, out var v) && v.ValueKind == JsonValueKind.Array
                    ? v.EnumerateArray().Select(e => e.GetString()).ToArray() : Array.Empty<string>();
                bool Bool(string key, bool fallback) => root.TryGetProperty(key, out var v) ? v.GetBoolean() : fallback;
                var asmdef = new Asmdef
                {
                    Name = root.GetProperty("name").GetString(),
                    Path = path,
                    Folder = System.IO.Path.GetDirectoryName(path),
                    Guid = ReadGuid(path + ".meta"),
                    References = Strings("references"),
                    IncludePlatforms = Strings("includePlatforms"),
                    ExcludePlatforms = Strings("excludePlatforms"),
                    PrecompiledReferences = Strings("precompiledReferences"),
                    DefineConstraints = Strings("defineConstraints"),
                    AllowUnsafeCode = Bool("allowUnsafeCode", false),
                    OverrideReferences = Bool("overrideReferences", false),
                    NoEngineReferences = Bool("noEngineReferences", false),
                    AutoReferenced = Bool("autoReferenced", true),
                    HasVersionDefines = Strings("versionDefines").Length > 0 ||
                        (root.TryGetProperty("versionDefines", out var vd) && vd.ValueKind == JsonValueKind.Array && vd.GetArrayLength() > 0),
                };
                if (asmdef.HasVersionDefines)
                    throw new GateException($"{path}: versionDefines are not modelled by the compile gate");
                return asmdef;
            }
            catch (Exception e) when (e is JsonException || e is KeyNotFoundException || e is InvalidOperationException)
            {
                throw new GateException($"{path}: not a readable asmdef ({e.Message})");
            }
        }

        static string ReadGuid(string metaPath)
        {
            if (!File.Exists(metaPath)) return null;
            var line = File.ReadLines(metaPath).FirstOrDefault(l => l.StartsWith("guid:", StringComparison.Ordinal));
            return line?.Substring(5).Trim();
        }

        void LoadSamples()
        {
            using var doc = JsonDocument.Parse(File.ReadAllText(System.IO.Path.Combine(Root, "package.json")));
            if (!doc.RootElement.TryGetProperty("samples", out var samples)) return;
            foreach (var entry in samples.EnumerateArray())
            {
                var folder = System.IO.Path.GetFullPath(System.IO.Path.Combine(Root, entry.GetProperty("path").GetString()));
                if (!Directory.Exists(folder)) throw new GateException($"sample folder {Relative(folder)} does not exist");
                var sample = new Sample { DisplayName = entry.GetProperty("displayName").GetString(), Folder = folder };
                // Once imported the sample lives under Assets/, where every folder is imported
                // (its own '~' folders aside). A script belongs to the nearest asmdef above it; an
                // Editor/ folder makes editor scripts only outside every asmdef.
                var files = UnitySources(folder).ToList();
                foreach (var asmdefPath in files.Where(f => f.EndsWith(".asmdef", StringComparison.Ordinal)))
                    sample.Asmdefs.Add(ReadAsmdef(asmdefPath));
                foreach (var file in files.Where(f => f.EndsWith(".cs", StringComparison.Ordinal)))
                {
                    var owner = OwningAsmdef(sample.Asmdefs, file);
                    if (owner != null)
                    {
                        owner.Sources.Add(file);
                        continue;
                    }
                    var parts = System.IO.Path.GetRelativePath(folder, file).Split(System.IO.Path.DirectorySeparatorChar);
                    (parts.Take(parts.Length - 1).Contains("Editor") ? sample.EditorSources : sample.RuntimeSources).Add(file);
                }
                Samples.Add(sample);
            }
        }

        /// <summary>The package's asmdefs Unity compiles for a target, dependencies first.</summary>
        public IEnumerable<Asmdef> AssembliesFor(Target target, UnityVersion version) =>
            BuildOrder(Asmdefs, target, version, Resolve);

        /// <summary>A sample's own asmdefs Unity compiles for a target, dependencies first.</summary>
        public IEnumerable<Asmdef> AssembliesFor(Sample sample, Target target, UnityVersion version) =>
            BuildOrder(sample.Asmdefs, target, version, r => Resolve(sample, r));

        static IEnumerable<Asmdef> BuildOrder(IEnumerable<Asmdef> asmdefs, Target target, UnityVersion version,
                                              Func<string, Asmdef> resolve)
        {
            var defines = new HashSet<string>(target.Defines.Concat(version.Defines));
            var included = asmdefs.Where(a => a.BuildsFor(target) && a.ConstraintsHold(defines)).ToList();
            var ordered = new List<Asmdef>();
            var visiting = new HashSet<Asmdef>();
            void Visit(Asmdef a)
            {
                if (ordered.Contains(a)) return;
                if (!visiting.Add(a)) throw new GateException($"asmdef reference cycle through {a.Name}");
                foreach (var r in a.References)
                {
                    var dep = resolve(r);
                    if (dep != null && included.Contains(dep)) Visit(dep);
                }
                ordered.Add(a);
            }
            foreach (var a in included) Visit(a);
            return ordered;
        }

        /// <summary>An asmdef of this package named by a reference ("Name" or "GUID:..."), or null.</summary>
        public Asmdef Resolve(string reference) => Find(Asmdefs, reference);

        /// <summary>
        /// An asmdef a sample's asmdef can reach: one of the sample's own, else one of the package
        /// (never another sample's: a project may have imported only this one), or null.
        /// </summary>
        public Asmdef Resolve(Sample sample, string reference) => Find(sample.Asmdefs, reference) ?? Resolve(reference);

        // A sample's asmdefs have no committed .meta (Unity does not track ~ folders), so no GUID.
        static Asmdef Find(IEnumerable<Asmdef> asmdefs, string reference) =>
            reference.StartsWith("GUID:", StringComparison.Ordinal)
                ? asmdefs.FirstOrDefault(a => a.Guid != null && a.Guid == reference.Substring(5))
                : asmdefs.FirstOrDefault(a => a.Name == reference);
    }
}
