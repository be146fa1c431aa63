// Where the pose model and ONNX Runtime are found, in the editor and in a built player. The Unity
// glue describes the running context (RunningContext: editor or player, OS, CPU, Application's
// paths) and opens what this returns; every decision about paths lives here so it is tested
// without Unity on folders laid out like each platform's build.
//
// Layouts (Unity manual, Application.dataPath and Streaming Assets):
//   editor          dataPath = <project>/Assets, project-relative paths ("Packages/...") resolve
//                   against the project root (or the package folder Unity resolved, for packages
//                   that live in Library/PackageCache)
//   Windows player  dataPath = <Game>_Data, plugins in <Game>_Data/Plugins/x86_64 (ARM64 on arm64),
//                   streamingAssetsPath = <Game>_Data/StreamingAssets
//   Linux player    dataPath = <Game>_Data, plugins in <Game>_Data/Plugins (x86_64/ in some versions),
//                   streamingAssetsPath = <Game>_Data/StreamingAssets
//   macOS player    dataPath = <Game>.app/Contents, plugins in Contents/PlugIns,
//                   streamingAssetsPath = Contents/Resources/Data/StreamingAssets
// A player does not contain the package's Models folder: a build step copies the configured model
// to Assets/StreamingAssets/com.mocap.imu/<file name> (ModelBuildCopy), which Unity copies verbatim
// into the player's StreamingAssets.

using System;
using System.Collections.Generic;
using System.IO;
using System.Runtime.InteropServices;
using System.Text;

namespace Mocap.Imu
{
    /// <summary>The operating system a player or editor runs on.</summary>
    public enum HostOs
    {
        /// <summary>Windows.</summary>
        Windows,
        /// <summary>macOS.</summary>
        MacOS,
        /// <summary>Linux.</summary>
        Linux,
    }

    /// <summary>The CPU architecture of the running process (picks the plugin build).</summary>
    public enum HostArchitecture
    {
        /// <summary>x86-64.</summary>
        X64,
        /// <summary>64-bit ARM (Apple silicon, Windows on ARM).</summary>
        Arm64,
    }

    /// <summary>
    /// What the glue knows about where it runs: Unity's <c>Application</c> paths as plain strings.
    /// </summary>
    public sealed class RunningContext
    {
        /// <summary>True in the Unity editor (edit or play mode), false in a built player.</summary>
        public bool IsEditor;

        /// <summary>The OS of the editor or player.</summary>
        public HostOs Os;

        /// <summary>The process architecture.</summary>
        public HostArchitecture Architecture = HostArchitecture.X64;

        /// <summary>Editor: the project folder (the parent of Assets). Unused in a player.</summary>
        public string ProjectRoot;

        /// <summary><c>Application.dataPath</c>: Assets in the editor, the data folder in a player.</summary>
        public string DataPath;

        /// <summary><c>Application.streamingAssetsPath</c>.</summary>
        public string StreamingAssetsPath;

        /// <summary>
        /// Editor: folders of packages that do not live under &lt;project&gt;/Packages (a registry or
        /// git package sits in Library/PackageCache/name@hash); key "com.github.asus4.onnxruntime",
        /// value its folder (Unity: <c>Path.GetFullPath("Packages/com.github.asus4.onnxruntime")</c>).
        /// A package missing here is looked for under &lt;project&gt;/Packages.
        /// </summary>
        public Dictionary<string, string> PackageFolders = new Dictionary<string, string>();

        /// <summary><c>Application.persistentDataPath</c> (a player's recordings and captures), or null.</summary>
        public string PersistentDataPath;

        /// <summary>The value of $MOCAP_ONNXRUNTIME_PATH, or null; when set it is the only candidate.</summary>
        public string OnnxRuntimeOverride;

        /// <summary>A context for the editor of a project.</summary>
        public static RunningContext Editor(HostOs os, string projectRoot, HostArchitecture architecture = HostArchitecture.X64) =>
            new RunningContext
            {
                IsEditor = true,
                Os = os,
                Architecture = architecture,
                ProjectRoot = projectRoot,
                DataPath = projectRoot == null ? null : Path.Combine(projectRoot, "Assets"),
                StreamingAssetsPath = projectRoot == null ? null : Path.Combine(projectRoot, "Assets", "StreamingAssets"),
            };

        /// <summary>
        /// A context for a player whose <c>Application.dataPath</c> is <paramref name="dataPath"/>;
        /// the StreamingAssets folder is where Unity puts it on <paramref name="os"/>.
        /// </summary>
        public static RunningContext Player(HostOs os, string dataPath, HostArchitecture architecture = HostArchitecture.X64) =>
            new RunningContext
            {
                IsEditor = false,
                Os = os,
                Architecture = architecture,
                DataPath = dataPath,
                StreamingAssetsPath = dataPath == null ? null : PlayerPaths.StreamingAssetsFolder(os, dataPath),
            };
    }

    /// <summary>The outcome of looking for a file: the path found, or every path tried and why none fits.</summary>
    public sealed class PathLookup
    {
        internal PathLookup(string what, string found, string[] tried, string note)
        {
            What = what;
            Path = found;
            Tried = tried;
            Note = note;
        }

        /// <summary>"pose model" or "ONNX Runtime library".</summary>
        public string What { get; }

        /// <summary>The first candidate that exists, or null.</summary>
        public string Path { get; }

        /// <summary>True when a candidate exists.</summary>
        public bool Found => Path != null;

        /// <summary>The candidates in the order they were tried.</summary>
        public IReadOnlyList<string> Tried { get; }

        /// <summary>Why the candidates are what they are (e.g. no plugin for this CPU), or null.</summary>
        public string Note { get; }

        /// <summary>Null when found; else a sentence naming every path tried.</summary>
        public string Error
        {
            get
            {
                if (Found) return null;
                var text = new StringBuilder();
                text.Append("the ").Append(What).Append(" was not found");
                if (Tried.Count == 0) text.Append(" (no place to look)");
                else
                {
                    text.Append("; tried: ");
                    for (int i = 0; i < Tried.Count; i++) text.Append(i == 0 ? "" : ", ").Append(Tried[i]);
                }
                if (Note != null) text.Append(". ").Append(Note);
                return text.ToString();
            }
        }

        /// <summary>The path found.</summary>
        /// <exception cref="MocapException">NotFound, with <see cref="Error"/> as the message.</exception>
        public string Require() => Found ? Path : throw new MocapException(MocapStatus.NotFound, Error);
    }

    /// <summary>A file the build step copies into the project before a player build.</summary>
    public readonly struct ModelBuildCopy
    {
        /// <summary>Creates a copy instruction.</summary>
        public ModelBuildCopy(string source, string projectRelativeTarget, string absoluteTarget)
        {
            Source = source;
            ProjectRelativeTarget = projectRelativeTarget;
            AbsoluteTarget = absoluteTarget;
        }

        /// <summary>The model file in the editor (absolute).</summary>
        public string Source { get; }

        /// <summary>"Assets/StreamingAssets/com.mocap.imu/&lt;file&gt;" ('/' separators, for the AssetDatabase).</summary>
        public string ProjectRelativeTarget { get; }

        /// <summary>The same target as an absolute path.</summary>
        public string AbsoluteTarget { get; }
    }

    /// <summary>Model and ONNX Runtime locations for the editor and for players.</summary>
    public static class PlayerPaths
    {
        /// <summary>The model the package ships and settings default to.</summary>
        public const string DefaultModelPath = "Packages/com.mocap.imu/Runtime/Models/mocap_pose_int8.onnx";

        /// <summary>The folder under StreamingAssets that holds the model in a player.</summary>
        public const string StreamingFolderName = "com.mocap.imu";

        /// <summary>The package that ships ONNX Runtime's native plugins.</summary>
        public const string OnnxRuntimePackage = "com.github.asus4.onnxruntime";

        const string PackagesPrefix = "Packages/";

        /// <summary>The OS this process runs on.</summary>
        public static HostOs CurrentOs() =>
            RuntimeInformation.IsOSPlatform(OSPlatform.Windows) ? HostOs.Windows
            : RuntimeInformation.IsOSPlatform(OSPlatform.OSX) ? HostOs.MacOS
            : HostOs.Linux;

        /// <summary>The architecture of this process (an x64 editor under Rosetta is X64: it loads x64 plugins).</summary>
        public static HostArchitecture CurrentArchitecture() =>
            RuntimeInformation.ProcessArchitecture == Architecture.Arm64 ? HostArchitecture.Arm64 : HostArchitecture.X64;

        /// <summary>
        /// A data file the settings name (a capture to play back, a calibration to load). Editor: an
        /// absolute path as is, a relative one against the project. Player: an absolute path as is;
        /// a relative one under persistentDataPath (where the player records), then under
        /// StreamingAssets (the path as given unless it names an editor folder, Assets/ or Packages/,
        /// then the bare file name).
        /// </summary>
        /// <exception cref="ArgumentException"><paramref name="configuredPath"/> is empty.</exception>
        public static PathLookup FindFile(RunningContext context, string configuredPath, string what, Func<string, bool> exists = null)
        {
            CheckContext(context);
            if (string.IsNullOrWhiteSpace(configuredPath)) throw new ArgumentException($"no {what} path is set", nameof(configuredPath));
            string configured = configuredPath.Trim();
            var candidates = new List<string>(3);
            if (Path.IsPathRooted(configured)) candidates.Add(Path.GetFullPath(configured));
            else if (context.IsEditor) candidates.Add(ResolveInProject(context, configured));
            else
            {
                if (!string.IsNullOrEmpty(context.PersistentDataPath))
                    candidates.Add(Path.GetFullPath(Path.Combine(context.PersistentDataPath, ToOs(configured))));
                if (!IsProjectAssetPath(configured))
                    AddUnique(candidates, Path.GetFullPath(Path.Combine(RequireStreaming(context), ToOs(configured))));
                AddUnique(candidates, Path.GetFullPath(Path.Combine(RequireStreaming(context), Path.GetFileName(configured))));
            }
            return Lookup(what, candidates, exists ?? File.Exists, null);
        }

        /// <summary>
        /// The folder recordings go to: an absolute <paramref name="configuredFolder"/> as is, else
        /// under the project (editor) or persistentDataPath (player); empty means "Captures".
        /// </summary>
        public static string RecordingFolder(RunningContext context, string configuredFolder)
        {
            CheckContext(context);
            string folder = string.IsNullOrWhiteSpace(configuredFolder) ? "Captures" : configuredFolder.Trim();
            if (Path.IsPathRooted(folder)) return Path.GetFullPath(folder);
            if (context.IsEditor) return ResolveInProject(context, folder);
            if (string.IsNullOrEmpty(context.PersistentDataPath))
                throw new ArgumentException("a player context needs Application.persistentDataPath for recordings", nameof(context));
            return Path.GetFullPath(Path.Combine(context.PersistentDataPath, ToOs(folder)));
        }

        /// <summary>
        /// <c>Application.streamingAssetsPath</c> of a player with data folder <paramref name="dataPath"/>:
        /// &lt;Data&gt;/StreamingAssets on Windows and Linux, Contents/Resources/Data/StreamingAssets on macOS.
        /// </summary>
        public static string StreamingAssetsFolder(HostOs os, string dataPath)
        {
            if (dataPath == null) throw new ArgumentNullException(nameof(dataPath));
            return os == HostOs.MacOS
                ? Path.Combine(dataPath, "Resources", "Data", "StreamingAssets")
                : Path.Combine(dataPath, "StreamingAssets");
        }

        /// <summary>
        /// The model file to open, in the order tried. Editor: an absolute path as is, a relative one
        /// against the project (Packages/&lt;name&gt;/... against that package's folder). Player: an absolute
        /// path, then StreamingAssets/com.mocap.imu/&lt;file name&gt; (where the build step puts it),
        /// then StreamingAssets/&lt;the relative path&gt; and StreamingAssets/&lt;file name&gt; for a model
        /// placed there by hand. Empty <paramref name="configuredModelPath"/> means the default model.
        /// </summary>
        public static PathLookup FindModel(RunningContext context, string configuredModelPath, Func<string, bool> exists = null)
        {
            CheckContext(context);
            var candidates = ModelCandidates(context, configuredModelPath);
            return Lookup("pose model", candidates, exists ?? File.Exists, null);
        }

        /// <summary>The candidates <see cref="FindModel"/> tries, without looking at the disk.</summary>
        public static List<string> ModelCandidates(RunningContext context, string configuredModelPath)
        {
            CheckContext(context);
            string configured = NormaliseConfigured(configuredModelPath);
            var candidates = new List<string>(4);
            if (Path.IsPathRooted(configured))
            {
                candidates.Add(Path.GetFullPath(configured));
                if (!context.IsEditor) AddUnique(candidates, InStreamingFolder(context, configured));
                return candidates;
            }
            if (context.IsEditor)
            {
                candidates.Add(ResolveInProject(context, configured));
                return candidates;
            }
            AddUnique(candidates, InStreamingFolder(context, configured));
            if (!IsProjectAssetPath(configured))
                AddUnique(candidates, Path.GetFullPath(Path.Combine(RequireStreaming(context), configured)));
            AddUnique(candidates, Path.GetFullPath(Path.Combine(RequireStreaming(context), Path.GetFileName(configured))));
            return candidates;
        }

        /// <summary>
        /// What the player build step copies: the configured model as the editor finds it, to
        /// Assets/StreamingAssets/com.mocap.imu/&lt;file name&gt;.
        /// </summary>
        /// <exception cref="ArgumentException"><paramref name="editor"/> is not an editor context.</exception>
        /// <exception cref="MocapException">NotFound: the configured model does not exist in the editor.</exception>
        public static ModelBuildCopy ModelCopyForBuild(RunningContext editor, string configuredModelPath, Func<string, bool> exists = null)
        {
            CheckContext(editor);
            if (!editor.IsEditor) throw new ArgumentException("the build step runs in the editor", nameof(editor));
            string source = FindModel(editor, configuredModelPath, exists).Require();
            string relative = ModelTargetInProject(configuredModelPath);
            return new ModelBuildCopy(source, relative,
                Path.GetFullPath(Path.Combine(editor.ProjectRoot, relative.Replace('/', Path.DirectorySeparatorChar))));
        }

        /// <summary>"Assets/StreamingAssets/com.mocap.imu/&lt;file name of the configured model&gt;".</summary>
        public static string ModelTargetInProject(string configuredModelPath) =>
            "Assets/StreamingAssets/" + StreamingFolderName + "/" + ModelFileName(configuredModelPath);

        /// <summary>The file name the model has in a player (that of the configured model; the int8 one by default).</summary>
        public static string ModelFileName(string configuredModelPath)
        {
            string name = Path.GetFileName(NormaliseConfigured(configuredModelPath));
            if (name.Length == 0) throw new ArgumentException($"the model path '{configuredModelPath}' names a folder, not a file", nameof(configuredModelPath));
            return name;
        }

        /// <summary>
        /// The ONNX Runtime library to load. $MOCAP_ONNXRUNTIME_PATH (the context's override) is the
        /// only candidate when set; then an explicit <paramref name="configuredPath"/> (absolute, or
        /// relative to the project in the editor and to the data folder in a player); else the
        /// com.github.asus4.onnxruntime plugin for this OS and CPU (see the file header for each layout).
        /// </summary>
        public static PathLookup FindOnnxRuntime(RunningContext context, string configuredPath = null, Func<string, bool> exists = null)
        {
            var candidates = OnnxRuntimeCandidates(context, configuredPath, out string note);
            return Lookup("ONNX Runtime library", candidates, exists ?? File.Exists, note);
        }

        /// <summary>The candidates <see cref="FindOnnxRuntime"/> tries, and a note when the package has no build for this CPU.</summary>
        public static List<string> OnnxRuntimeCandidates(RunningContext context, string configuredPath, out string note)
        {
            CheckContext(context);
            note = null;
            var candidates = new List<string>(3);
            if (!string.IsNullOrEmpty(context.OnnxRuntimeOverride))
            {
                candidates.Add(Path.GetFullPath(context.OnnxRuntimeOverride));
                note = "$MOCAP_ONNXRUNTIME_PATH is set, so no other place is tried";
                return candidates;
            }
            if (!string.IsNullOrWhiteSpace(configuredPath))
            {
                string configured = configuredPath.Trim();
                if (Path.IsPathRooted(configured)) candidates.Add(Path.GetFullPath(configured));
                else if (context.IsEditor) candidates.Add(ResolveInProject(context, configured));
                else candidates.Add(Path.GetFullPath(Path.Combine(RequireData(context), configured)));
                return candidates;
            }
            string library = LibraryFileName(context.Os);
            bool arm = context.Architecture == HostArchitecture.Arm64;
            if (context.IsEditor)
            {
                string plugins = ResolveInProject(context, PackagesPrefix + OnnxRuntimePackage + "/Plugins");
                switch (context.Os)
                {
                    case HostOs.Windows:
                        candidates.Add(Path.Combine(plugins, "Windows", arm ? "arm64" : "x64", library));
                        break;
                    case HostOs.MacOS:
                        if (arm) candidates.Add(Path.Combine(plugins, "macOS", "arm64", library));
                        else note = "com.github.asus4.onnxruntime ships macOS for Apple silicon only; set the ONNX Runtime path or $MOCAP_ONNXRUNTIME_PATH to an x64 build";
                        break;
                    default:
                        if (!arm) candidates.Add(Path.Combine(plugins, "Linux", "x64", library));
                        else note = "com.github.asus4.onnxruntime ships Linux for x64 only; set the ONNX Runtime path or $MOCAP_ONNXRUNTIME_PATH to an arm64 build";
                        break;
                }
                return candidates;
            }
            string data = RequireData(context);
            switch (context.Os)
            {
                case HostOs.Windows:
                    candidates.Add(Path.Combine(data, "Plugins", arm ? "ARM64" : "x86_64", library));
                    candidates.Add(Path.Combine(data, "Plugins", library));
                    break;
                case HostOs.MacOS:
                    candidates.Add(Path.Combine(data, "PlugIns", library));
                    candidates.Add(Path.Combine(data, "Plugins", library));
                    break;
                default:
                    candidates.Add(Path.Combine(data, "Plugins", library));
                    candidates.Add(Path.Combine(data, "Plugins", arm ? "arm64" : "x86_64", library));
                    break;
            }
            for (int i = 0; i < candidates.Count; i++) candidates[i] = Path.GetFullPath(candidates[i]);
            return candidates;
        }

        /// <summary>onnxruntime.dll, libonnxruntime.dylib or libonnxruntime.so.</summary>
        public static string LibraryFileName(HostOs os) => os switch
        {
            HostOs.Windows => "onnxruntime.dll",
            HostOs.MacOS => "libonnxruntime.dylib",
            _ => "libonnxruntime.so",
        };

        /// <summary>
        /// A project-relative path in the editor: "Packages/&lt;name&gt;/rest" against the package's
        /// folder when the context knows it, else against the project root, like everything else.
        /// </summary>
        public static string ResolveInProject(RunningContext editor, string relativePath)
        {
            CheckContext(editor);
            if (relativePath == null) throw new ArgumentNullException(nameof(relativePath));
            if (string.IsNullOrEmpty(editor.ProjectRoot))
                throw new ArgumentException("an editor context needs the project root", nameof(editor));
            string path = relativePath.Replace('\\', '/');
            if (path.StartsWith(PackagesPrefix, StringComparison.Ordinal) && editor.PackageFolders != null)
            {
                int slash = path.IndexOf('/', PackagesPrefix.Length);
                string package = slash < 0 ? path.Substring(PackagesPrefix.Length) : path.Substring(PackagesPrefix.Length, slash - PackagesPrefix.Length);
                if (editor.PackageFolders.TryGetValue(package, out var folder) && !string.IsNullOrEmpty(folder))
                {
                    string rest = slash < 0 ? string.Empty : path.Substring(slash + 1);
                    return Path.GetFullPath(Path.Combine(folder, ToOs(rest)));
                }
            }
            return Path.GetFullPath(Path.Combine(editor.ProjectRoot, ToOs(path)));
        }

        static PathLookup Lookup(string what, List<string> candidates, Func<string, bool> exists, string note)
        {
            foreach (var candidate in candidates)
                if (exists(candidate)) return new PathLookup(what, candidate, candidates.ToArray(), note);
            return new PathLookup(what, null, candidates.ToArray(), note);
        }

        static string InStreamingFolder(RunningContext context, string configured) =>
            Path.GetFullPath(Path.Combine(RequireStreaming(context), StreamingFolderName, ModelFileName(configured)));

        // Assets/... and Packages/... name editor files, which a player has only where the build put them.
        static bool IsProjectAssetPath(string path)
        {
            string p = path.Replace('\\', '/');
            return p.StartsWith(PackagesPrefix, StringComparison.Ordinal) || p.StartsWith("Assets/", StringComparison.Ordinal);
        }

        static string NormaliseConfigured(string configured) =>
            string.IsNullOrWhiteSpace(configured) ? DefaultModelPath : configured.Trim();

        static string ToOs(string path) => path.Replace('/', Path.DirectorySeparatorChar);

        static void AddUnique(List<string> list, string path)
        {
            if (!list.Contains(path)) list.Add(path);
        }

        static string RequireStreaming(RunningContext context) =>
            !string.IsNullOrEmpty(context.StreamingAssetsPath)
                ? context.StreamingAssetsPath
                : throw new ArgumentException("a player context needs Application.streamingAssetsPath", nameof(context));

        static string RequireData(RunningContext context) =>
            !string.IsNullOrEmpty(context.DataPath)
                ? context.DataPath
                : throw new ArgumentException("a player context needs Application.dataPath", nameof(context));

        static void CheckContext(RunningContext context)
        {
            if (context == null) throw new ArgumentNullException(nameof(context));
            if (!Enum.IsDefined(typeof(HostOs), context.Os))
                throw new ArgumentOutOfRangeException(nameof(context), context.Os, "unknown OS");
        }
    }
}
