// Syntax check of every .cs file under a folder, as Unity 2022.3 parses it (C# 9), once with
// the symbols of an editor build and once with those of a Linux player, so both sides of every
// #if are read. Semantic checks need UnityEngine's assemblies, which this machine cannot get.
// Prints one line per file with errors and a closing "N passed, N failed" over the files.
using System;
using System.IO;
using System.Linq;
using Microsoft.CodeAnalysis;
using Microsoft.CodeAnalysis.CSharp;

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
            if (errors.Count == 0) { passed++; continue; }
            failed++;
            foreach (var e in errors) Console.WriteLine(e);
        }
        Console.WriteLine($"syntax check of {files.Length} C# files (C# 9, editor and player symbols)");
        Console.WriteLine($"{passed} passed, {failed} failed");
        return failed == 0 && files.Length > 0 ? 0 : 1;
    }
}
