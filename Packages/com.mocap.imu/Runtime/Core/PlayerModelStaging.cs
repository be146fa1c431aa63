// The player build step's file work: before a build, copy each configured pose model into
// Assets/StreamingAssets/com.mocap.imu/ (Unity ships that folder verbatim); after the build, remove
// what the step created and nothing else. What was created is also written to a list under the
// project's Library folder, because Unity does not call the post-build step when a build fails:
// the next build (or editor start) removes those leftovers first.

using System;
using System.Collections.Generic;
using System.IO;
using System.Text;
using Mocap.Imu.Recording;

namespace Mocap.Imu
{
    /// <summary>Copies the pose models into StreamingAssets for a player build and removes them afterwards.</summary>
    public static class PlayerModelStaging
    {
        /// <summary>The list of staged files, relative to the project (Library is never shipped).</summary>
        public const string StagedListPath = "Library/com.mocap.imu/staged-player-files.txt";

        /// <summary>
        /// The copies a build needs for the configured model paths (each settings asset's; an empty
        /// one, or none at all, means the default model). The same source twice is one copy; two different
        /// sources with one file name are refused, since both would land on the same player path.
        /// </summary>
        /// <exception cref="MocapException">NotFound: a configured model is missing; InvalidArgument: a file name clash.</exception>
        public static List<ModelBuildCopy> Plan(RunningContext editor, IEnumerable<string> configuredModelPaths, Func<string, bool> exists = null)
        {
            var configured = new List<string>();
            if (configuredModelPaths != null)
                foreach (var path in configuredModelPaths)
                    configured.Add(string.IsNullOrWhiteSpace(path) ? PlayerPaths.DefaultModelPath : path);
            if (configured.Count == 0) configured.Add(PlayerPaths.DefaultModelPath);

            var copies = new List<ModelBuildCopy>();
            foreach (var path in configured)
            {
                var copy = PlayerPaths.ModelCopyForBuild(editor, path, exists);
                var clash = copies.Find(c => PathsEqual(c.AbsoluteTarget, copy.AbsoluteTarget));
                if (clash.Source == null) copies.Add(copy);
                else if (!PathsEqual(clash.Source, copy.Source))
                    throw new MocapException(MocapStatus.InvalidArgument,
                        $"two configured pose models share the file name {Path.GetFileName(copy.Source)} ({clash.Source} and {copy.Source}); " +
                        "a player keeps one file per name, so rename one of them");
            }
            return copies;
        }

        /// <summary>
        /// Copy the planned models into the project (creating StreamingAssets/com.mocap.imu as
        /// needed) and record what was created. A target that already holds the same bytes is left
        /// alone and not recorded (someone put it there on purpose); one with other bytes is refused.
        /// Leftovers of a failed earlier build are removed first. Returns the project-relative files created.
        /// </summary>
        /// <exception cref="MocapException">A target differs from its model (InvalidArgument) or a copy failed (IO, Permission).</exception>
        public static List<string> Stage(string projectRoot, IReadOnlyList<ModelBuildCopy> copies)
        {
            CheckRoot(projectRoot);
            if (copies == null) throw new ArgumentNullException(nameof(copies));
            Unstage(projectRoot);
            var created = new List<string>();
            try
            {
                foreach (var copy in copies)
                {
                    if (File.Exists(copy.AbsoluteTarget))
                    {
                        if (SameBytes(copy.Source, copy.AbsoluteTarget)) continue;
                        throw new MocapException(MocapStatus.InvalidArgument,
                            $"{copy.ProjectRelativeTarget} already exists and is not the configured model {copy.Source}; " +
                            "remove it, or point the settings' model path at it");
                    }
                    CreateFolders(projectRoot, Path.GetDirectoryName(copy.ProjectRelativeTarget).Replace('\\', '/'), created);
                    // Recorded before the copy so a failure half way still gets cleaned up.
                    created.Add(copy.ProjectRelativeTarget);
                    WriteList(projectRoot, created);
                    using (var input = RecordingFiles.OpenRead(copy.Source, "pose model"))
                        RecordingFiles.WriteReplacing(copy.AbsoluteTarget, "staged pose model", output => input.CopyTo(output));
                }
            }
            catch
            {
                Unstage(projectRoot);
                throw;
            }
            return created;
        }

        /// <summary>
        /// Remove every file and folder the last <see cref="Stage"/> created (with the .meta files
        /// the editor made for them), deepest first; a folder that now holds something else stays.
        /// Returns the project-relative paths removed.
        /// </summary>
        public static List<string> Unstage(string projectRoot)
        {
            CheckRoot(projectRoot);
            var removed = new List<string>();
            string list = Path.Combine(projectRoot, StagedListPath);
            if (!File.Exists(list)) return removed;
            var staged = new List<string>(RecordingFiles.ReadAllLines(list, "list of staged player files"));
            for (int i = staged.Count - 1; i >= 0; i--)
            {
                string relative = staged[i].Trim();
                if (relative.Length == 0 || !IsStreamingPath(relative)) continue;
                string full = Path.Combine(projectRoot, relative.Replace('/', Path.DirectorySeparatorChar));
                if (relative.EndsWith("/", StringComparison.Ordinal))
                {
                    string folder = full.TrimEnd(Path.DirectorySeparatorChar);
                    if (Directory.Exists(folder) && IsEmptyButMeta(folder))
                    {
                        Directory.Delete(folder, recursive: true);
                        DeleteIfExists(folder + ".meta");
                        removed.Add(relative);
                    }
                }
                else if (File.Exists(full))
                {
                    File.Delete(full);
                    DeleteIfExists(full + ".meta");
                    removed.Add(relative);
                }
            }
            File.Delete(list);
            return removed;
        }

        static void CreateFolders(string projectRoot, string relativeFolder, List<string> created)
        {
            var parts = relativeFolder.Split('/');
            string relative = string.Empty;
            foreach (var part in parts)
            {
                relative = relative.Length == 0 ? part : relative + "/" + part;
                string full = Path.Combine(projectRoot, relative.Replace('/', Path.DirectorySeparatorChar));
                if (Directory.Exists(full)) continue;
                created.Add(relative + "/");
                WriteList(projectRoot, created);
                Directory.CreateDirectory(full);
            }
        }

        static void WriteList(string projectRoot, List<string> created)
        {
            string list = Path.Combine(projectRoot, StagedListPath);
            Directory.CreateDirectory(Path.GetDirectoryName(list));
            var text = new StringBuilder();
            foreach (var path in created) text.Append(path).Append('\n');
            RecordingFiles.WriteReplacing(list, "list of staged player files", stream =>
            {
                var bytes = Encoding.UTF8.GetBytes(text.ToString());
                stream.Write(bytes, 0, bytes.Length);
            });
        }

        // Only ever delete below Assets/StreamingAssets, whatever the list says.
        static bool IsStreamingPath(string relative) =>
            relative.StartsWith("Assets/StreamingAssets", StringComparison.Ordinal) && relative.IndexOf("..", StringComparison.Ordinal) < 0;

        static bool IsEmptyButMeta(string folder)
        {
            foreach (var entry in Directory.EnumerateFileSystemEntries(folder))
                if (!entry.EndsWith(".meta", StringComparison.Ordinal) || Directory.Exists(entry)) return false;
            return true;
        }

        static bool SameBytes(string a, string b)
        {
            using var x = RecordingFiles.OpenRead(a, "pose model");
            using var y = RecordingFiles.OpenRead(b, "staged pose model");
            if (x.Length != y.Length) return false;
            var bx = new byte[81920];
            var by = new byte[81920];
            while (true)
            {
                int n = x.Read(bx, 0, bx.Length);
                if (n == 0) return true;
                int m = 0;
                while (m < n)
                {
                    int r = y.Read(by, m, n - m);
                    if (r == 0) return false;
                    m += r;
                }
                for (int i = 0; i < n; i++)
                    if (bx[i] != by[i]) return false;
            }
        }

        static void DeleteIfExists(string path)
        {
            if (File.Exists(path)) File.Delete(path);
        }

        static bool PathsEqual(string a, string b) =>
            string.Equals(Path.GetFullPath(a), Path.GetFullPath(b), StringComparison.Ordinal);

        static void CheckRoot(string projectRoot)
        {
            if (string.IsNullOrEmpty(projectRoot)) throw new ArgumentException("the project root is empty", nameof(projectRoot));
            if (!Directory.Exists(projectRoot)) throw new MocapException(MocapStatus.NotFound, $"the project folder {projectRoot} does not exist");
        }
    }
}
