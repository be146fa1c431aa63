using System;
using System.Collections.Generic;
using System.Linq;
using Microsoft.CodeAnalysis;

namespace Mocap.Imu.CompileGate
{
    /// <summary>
    /// The package's documentation promise: every field the inspector shows in the Runtime glue
    /// and the samples has a [Tooltip]. The engine-free core, the editor code and the tests have
    /// no inspector of their own and are not held to it.
    /// </summary>
    static class InspectorTooltips
    {
        static bool Checked(Package package, string path)
        {
            var rel = package.Relative(path);
            if (rel.StartsWith("Runtime/Core/", StringComparison.Ordinal)) return false;
            return rel.StartsWith("Runtime/", StringComparison.Ordinal) || rel.StartsWith("Samples~/", StringComparison.Ordinal);
        }

        public static IEnumerable<string> Check(Compilation compilation, Package package)
        {
            var problems = new List<string>();
            foreach (var tree in compilation.SyntaxTrees.Where(t => Checked(package, t.FilePath)))
            {
                var model = compilation.GetSemanticModel(tree);
                foreach (var node in tree.GetRoot().DescendantNodes().OfType<Microsoft.CodeAnalysis.CSharp.Syntax.TypeDeclarationSyntax>())
                {
                    if (!(model.GetDeclaredSymbol(node) is INamedTypeSymbol type) || !Inspected(type)) continue;
                    foreach (var field in type.GetMembers().OfType<IFieldSymbol>())
                    {
                        if (!field.DeclaringSyntaxReferences.Any(r => r.SyntaxTree == tree && node.Span.Contains(r.Span))) continue;
                        if (!Serialised(field) || Has(field, "UnityEngine.TooltipAttribute") ||
                            Has(field, "UnityEngine.HideInInspector")) continue;
                        var span = field.Locations[0].GetLineSpan();
                        problems.Add($"{package.Relative(span.Path)}:{span.StartLinePosition.Line + 1}: inspector field " +
                                     $"'{field.Name}' of {type.Name} has no [Tooltip]");
                    }
                }
            }
            return problems;
        }

        // Components, assets, and [Serializable] classes or structs (shown nested in their fields).
        static bool Inspected(INamedTypeSymbol type)
        {
            if (type.GetAttributes().Any(a => a.AttributeClass?.ToDisplayString() == "System.SerializableAttribute")) return true;
            for (var t = type.BaseType; t != null; t = t.BaseType)
            {
                var name = t.ToDisplayString();
                if (name == "UnityEngine.MonoBehaviour" || name == "UnityEngine.ScriptableObject") return true;
            }
            return false;
        }

        // Unity serialises public instance fields and [SerializeField] ones, unless they are
        // static, const, readonly or [NonSerialized].
        static bool Serialised(IFieldSymbol field) =>
            !field.IsStatic && !field.IsConst && !field.IsReadOnly && !field.IsImplicitlyDeclared &&
            !Has(field, "System.NonSerializedAttribute") &&
            (field.DeclaredAccessibility == Accessibility.Public || Has(field, "UnityEngine.SerializeField"));

        static bool Has(ISymbol symbol, string attribute) =>
            symbol.GetAttributes().Any(a => a.AttributeClass?.ToDisplayString() == attribute);
    }
}
