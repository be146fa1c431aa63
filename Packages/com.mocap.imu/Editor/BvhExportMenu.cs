// Export a recorded take (the .mcpose pose recording TakeRecorder saves next to its clip) to BVH
// through the engine's writer (core BvhExporter: the same files as `mocapctl replay --out`).

using System;
using System.IO;
using Mocap.Imu.Recording;
using UnityEditor;
using UnityEngine;

namespace Mocap.Imu.Editor
{
    public static class BvhExportMenu
    {
        const string MenuPath = "Assets/Mocap/Export Take to BVH...";

        /// <summary>Right-click a take's .mcpose (or its .anim) > Mocap > Export Take to BVH.</summary>
        [MenuItem(MenuPath, false, 2000)]
        static void ExportSelected() => ExportWithDialog(SelectedPosePath());

        [MenuItem(MenuPath, true)]
        static bool ExportSelectedValidate()
        {
            var path = SelectedPosePath();
            return path != null && File.Exists(Path.GetFullPath(path));
        }

        /// <summary>Ask where to save, then export. Errors are shown, never thrown.</summary>
        public static void ExportWithDialog(string posesPath)
        {
            if (string.IsNullOrEmpty(posesPath)) return;
            var target = EditorUtility.SaveFilePanel("Export take to BVH", Path.GetDirectoryName(Path.GetFullPath(posesPath)),
                                                     Path.GetFileNameWithoutExtension(posesPath) + ".bvh", "bvh");
            if (string.IsNullOrEmpty(target)) return;
            try
            {
                long frames = Export(posesPath, target);
                Debug.Log($"Mocap: exported {frames} frames to {target}");
                if (target.Replace('\\', '/').StartsWith(Application.dataPath.Replace('\\', '/'), StringComparison.Ordinal))
                    AssetDatabase.Refresh();
            }
            catch (Exception e) when (e is MocapException || e is IOException || e is ArgumentException)
            {
                EditorUtility.DisplayDialog("BVH export failed", e.Message, "OK");
            }
        }

        /// <summary>Export a pose recording (project-relative or absolute path) to a BVH file; returns the frames written.</summary>
        public static long Export(string posesPath, string bvhPath, BvhExportOptions options = null)
        {
            var recording = PoseRecording.Load(Path.GetFullPath(posesPath));
            return BvhExporter.Export(recording, Path.GetFullPath(bvhPath), options);
        }

        static string SelectedPosePath()
        {
            var selected = Selection.activeObject;
            if (selected == null) return null;
            var path = AssetDatabase.GetAssetPath(selected);
            if (string.IsNullOrEmpty(path)) return null;
            if (path.EndsWith(TakeNaming.PoseExtension, StringComparison.OrdinalIgnoreCase)) return path;
            // A take's clip: its poses lie beside it.
            return path.EndsWith(".anim", StringComparison.OrdinalIgnoreCase) ? TakeNaming.PosePathFor(path) : null;
        }
    }
}
