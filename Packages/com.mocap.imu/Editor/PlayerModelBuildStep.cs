// A player does not contain the package's Models folder, so before every player build the pose
// model of each MocapSettings asset is copied into Assets/StreamingAssets/com.mocap.imu/, which Unity
// ships verbatim and where the player looks for it (PlayerPaths.FindModel). After the build the
// copies are removed again, unless they were there before. Thin: what to copy, the copying and
// the clean-up (also of a failed build, which gets no post-build call) live in the core's
// PlayerModelStaging.

using System.Collections.Generic;
using System.IO;
using UnityEditor;
using UnityEditor.Build;
using UnityEditor.Build.Reporting;
using UnityEngine;

namespace Mocap.Imu.Editor
{
    /// <summary>Stages the pose models for a player build and removes them after it.</summary>
    internal sealed class PlayerModelBuildStep : IPreprocessBuildWithReport, IPostprocessBuildWithReport
    {
        public int callbackOrder => 0;

        public void OnPreprocessBuild(BuildReport report)
        {
            string project = ProjectRoot();
            var models = new List<string>();
            foreach (var guid in AssetDatabase.FindAssets("t:" + nameof(MocapSettings)))
            {
                var settings = AssetDatabase.LoadAssetAtPath<MocapSettings>(AssetDatabase.GUIDToAssetPath(guid));
                if (settings != null) models.Add(settings.modelPath);
            }
            try
            {
                var plan = PlayerModelStaging.Plan(EditorContext(project), models);
                var created = PlayerModelStaging.Stage(project, plan);
                AssetDatabase.Refresh();
                foreach (var copy in plan)
                    Debug.Log($"Mocap: {copy.Source} ships as {copy.ProjectRelativeTarget}" +
                              (created.Contains(copy.ProjectRelativeTarget) ? "" : " (already there)"));
            }
            catch (MocapException e)
            {
                throw new BuildFailedException("Mocap: the pose model cannot be added to the player: " + e.Message);
            }
        }

        public void OnPostprocessBuild(BuildReport report)
        {
            if (PlayerModelStaging.Unstage(ProjectRoot()).Count > 0) AssetDatabase.Refresh();
        }

        static string ProjectRoot() => Path.GetDirectoryName(Application.dataPath);

        /// <summary>
        /// The editor's context. "Packages/com.mocap.imu" maps to wherever Unity keeps the package
        /// (embedded, local or Library/PackageCache): Path.GetFullPath resolves package paths in the editor.
        /// </summary>
        internal static RunningContext EditorContext(string project)
        {
            HostOs os = Application.platform == RuntimePlatform.WindowsEditor ? HostOs.Windows
                      : Application.platform == RuntimePlatform.OSXEditor ? HostOs.MacOS
                      : HostOs.Linux;
            var context = RunningContext.Editor(os, project);
            context.PackageFolders["com.mocap.imu"] = Path.GetFullPath("Packages/com.mocap.imu");
            return context;
        }
    }
}
