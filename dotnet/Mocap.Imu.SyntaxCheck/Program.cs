// Syntax check of every .cs file under a folder, as Unity 2022.3 parses it (C# 9), once with
// the symbols of an editor build and once with those of a Linux player, so both sides of every
// #if are read. Semantic checks need UnityEngine's assemblies, which this machine cannot get.
// It also holds the inspector to what the documentation promises: every field Unity shows in
// the inspector of a component, settings asset or serialisable class (Runtime glue and samples)
// has a [Tooltip].
// Prints one line per file with errors and a closing "N passed, N failed" over the files.
using System;
using System.Collections.Generic;
using System.IO;
using System.Linq;
using Microsoft.CodeAnalysis;
using Microsoft.CodeAnalysis.CSharp;
using Microsoft.CodeAnalysis.CSharp.Syntax;

static class Program
{
    static readonly string[][] SymbolSets =
    {
        new[] { "UNITY_EDITOR", "UNITY_2022_3_OR_NEWER", "UNITY_INCLUDE_TESTS", "ENABLE_LEGACY_INPUT_MANAGER", "UNITY_EDITOR_LINUX" },
        new[] { "UNITY_2022_3_OR_NEWER", "UNITY_STANDALONE_LINUX", "ENABLE_INPUT_SYSTEM", "ENABLE_IL2CPP" },
    };

    static int Main(string[] args)
    {
        if (args.Length != 1 || !Directory.Exists(args[0]))
        {
            Console.Error.WriteLine("usage: Mocap.Imu.SyntaxCheck PACKAGE_DIR");
            return 2;
        }
        var files = Directory.GetFiles(args[0], "*.cs", SearchOption.AllDirectories)
            .Where(f => !f.Contains($"{Path.DirectorySeparatorChar}obj{Path.DirectorySeparatorChar}"))
            .OrderBy(f => f, StringComparer.Ordinal).ToArray();
        int passed = 0, failed = 0;
        foreach (var file in files)
        {
            string text = File.ReadAllText(file);
            var errors = SymbolSets
                .SelectMany(symbols => CSharpSyntaxTree.ParseText(text,
                    new CSharpParseOptions(LanguageVersion.CSharp9, preprocessorSymbols: symbols), file)
                    .GetDiagnostics())
                .Where(d => d.Severity == DiagnosticSeverity.Error)
                .Select(d => d.ToString())
                .Distinct().ToList();
            if (errors.Count == 0 && ShowsInInspector(args[0], file))
                errors.AddRange(FieldsWithoutTooltip(CSharpSyntaxTree.ParseText(text,
                    new CSharpParseOptions(LanguageVersion.CSharp9, preprocessorSymbols: SymbolSets[0]), file)));
            if (errors.Count == 0) { passed++; continue; }
            failed++;
            foreach (var e in errors) Console.WriteLine(e);
        }
        Console.WriteLine($"syntax check of {files.Length} C# files (C# 9, editor and player symbols)");
        Console.WriteLine($"{passed} passed, {failed} failed");
        return failed == 0 && files.Length > 0 ? 0 : 1;
    }

    // The engine-free core, the tests and editor windows have no inspector of their own.
    static bool ShowsInInspector(string root, string file)
    {
        string rel = Path.GetRelativePath(root, file).Replace(Path.DirectorySeparatorChar, '/');
        if (rel.StartsWith("Runtime/Core/", StringComparison.Ordinal)) return false;
        return rel.StartsWith("Runtime/", StringComparison.Ordinal) || rel.StartsWith("Samples~/", StringComparison.Ordinal);
    }

    static readonly string[] InspectedBases = { "MonoBehaviour", "ScriptableObject" };

    static bool HasAttribute(SyntaxList<AttributeListSyntax> lists, string name) =>
        lists.SelectMany(l => l.Attributes).Any(a =>
        {
            string n = a.Name.ToString();
            int dot = n.LastIndexOf('.');
            if (dot >= 0) n = n.Substring(dot + 1);
            return n == name || n == name + "Attribute";
        });

    // Unity serialises public instance fields and [SerializeField] ones, unless they are static,
    // const, readonly, [NonSerialized] or hidden; only classes it inspects count (components,
    // assets, and [Serializable] classes nested in their fields).
    static IEnumerable<string> FieldsWithoutTooltip(SyntaxTree tree)
    {
        foreach (var type in tree.GetRoot().DescendantNodes().OfType<ClassDeclarationSyntax>())
        {
            bool inspected = HasAttribute(type.AttributeLists, "Serializable") ||
                (type.BaseList?.Types.Any(t => InspectedBases.Contains(t.Type.ToString().Split('.').Last())) ?? false);
            if (!inspected) continue;
            foreach (var field in type.Members.OfType<FieldDeclarationSyntax>())
            {
                var mods = field.Modifiers.Select(m => m.Text).ToList();
                if (mods.Contains("static") || mods.Contains("const") || mods.Contains("readonly")) continue;
                bool serialised = mods.Contains("public") || HasAttribute(field.AttributeLists, "SerializeField");
                if (!serialised || HasAttribute(field.AttributeLists, "NonSerialized") ||
                    HasAttribute(field.AttributeLists, "HideInInspector") || HasAttribute(field.AttributeLists, "Tooltip"))
                    continue;
                var line = field.GetLocation().GetLineSpan();
                foreach (var v in field.Declaration.Variables)
                    yield return $"{line.Path}({line.StartLinePosition.Line + 1}): inspector field '{v.Identifier.Text}' " +
                                 $"of {type.Identifier.Text} has no [Tooltip]";
            }
        }
    }
}
