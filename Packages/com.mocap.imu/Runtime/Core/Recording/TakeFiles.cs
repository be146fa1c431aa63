// The files of one editor take, named together: the Humanoid clip, the Generic clip, the solved
// poses, the raw sensor capture and the calibration it was solved with. They share one stem, so a
// take numbered " 2" because its clip name was taken is " 2" in every file, and a take never
// overwrites any file of another.

using System;
using System.Collections.Generic;
using System.IO;

namespace Mocap.Imu.Recording
{
    /// <summary>Paths of one take's files ('/'-separated, like Unity asset paths).</summary>
    public sealed class TakeFiles
    {
        /// <summary>Suffix of the Generic clip's name ("Take ... Generic.anim").</summary>
        public const string GenericSuffix = " Generic";

        /// <summary>Extension of the calibration kept with a take (mocapctl --save-calibration writes the same format).</summary>
        public const string CalibrationExtension = ".calibration";

        TakeFiles(string stem)
        {
            HumanoidClip = stem + ".anim";
            GenericClip = stem + GenericSuffix + ".anim";
            Poses = stem + TakeNaming.PoseExtension;
            Capture = stem + TakeNaming.CaptureExtension;
            Calibration = stem + CalibrationExtension;
        }

        /// <summary>"folder/name.anim": plays on any Humanoid avatar.</summary>
        public string HumanoidClip { get; }

        /// <summary>"folder/name Generic.anim": the recorded rig's own bones.</summary>
        public string GenericClip { get; }

        /// <summary>"folder/name.mcpose": the solved poses (BVH export).</summary>
        public string Poses { get; }

        /// <summary>"folder/name.cap": the raw sensor capture, replayable through the engine.</summary>
        public string Capture { get; }

        /// <summary>"folder/name.calibration": the calibration the poses were solved with.</summary>
        public string Calibration { get; }

        /// <summary>Every path of the take.</summary>
        public IReadOnlyList<string> All => new[] { HumanoidClip, GenericClip, Poses, Capture, Calibration };

        /// <summary>
        /// The files for a take called <paramref name="name"/> in <paramref name="folder"/>: "name",
        /// else "name 2", "name 3" ... the first stem for which <paramref name="exists"/> is false
        /// for every one of the take's files.
        /// </summary>
        public static TakeFiles Reserve(string folder, string name, Func<string, bool> exists)
        {
            if (folder == null) throw new ArgumentNullException(nameof(folder));
            if (exists == null) throw new ArgumentNullException(nameof(exists));
            // TakeNaming numbers the clip path; a number is free only when all siblings are free.
            string clip = TakeNaming.UniquePath(folder, name, ".anim", path => AnyExists(new TakeFiles(Stem(path)), exists));
            return new TakeFiles(Stem(clip));
        }

        /// <summary>
        /// Copy the raw capture <paramref name="capturePath"/> to <see cref="Capture"/> (relative
        /// paths against <paramref name="projectRoot"/>). The capture may still be open for writing.
        /// </summary>
        /// <exception cref="MocapException">The capture cannot be read (NotFound, ...) or the copy cannot be written.</exception>
        public string KeepCapture(string capturePath, string projectRoot) =>
            KeepCopy(capturePath, Capture, projectRoot, "raw capture");

        /// <summary>Copy a saved calibration file to <see cref="Calibration"/>.</summary>
        /// <exception cref="MocapException">The file cannot be read or the copy cannot be written.</exception>
        public string KeepCalibration(string calibrationPath, string projectRoot) =>
            KeepCopy(calibrationPath, Calibration, projectRoot, "calibration");

        /// <summary>An absolute path for one of the take's paths.</summary>
        public static string Absolute(string takePath, string projectRoot)
        {
            if (takePath == null) throw new ArgumentNullException(nameof(takePath));
            string native = takePath.Replace('/', Path.DirectorySeparatorChar);
            if (Path.IsPathRooted(native)) return Path.GetFullPath(native);
            if (string.IsNullOrEmpty(projectRoot)) throw new ArgumentException("a relative take path needs the project root", nameof(projectRoot));
            return Path.GetFullPath(Path.Combine(projectRoot, native));
        }

        static string KeepCopy(string source, string target, string projectRoot, string what)
        {
            if (string.IsNullOrEmpty(source)) throw new ArgumentException($"no {what} file to keep", nameof(source));
            string from = Absolute(source, projectRoot);
            string to = Absolute(target, projectRoot);
            if (string.Equals(from, to, StringComparison.Ordinal)) return to;
            using (var input = RecordingFiles.OpenRead(from, what))
                RecordingFiles.WriteReplacing(to, what, output => input.CopyTo(output));
            return to;
        }

        static bool AnyExists(TakeFiles files, Func<string, bool> exists)
        {
            foreach (var path in files.All)
                if (exists(path)) return true;
            return false;
        }

        static string Stem(string clipPath) => clipPath.Substring(0, clipPath.Length - ".anim".Length);
    }
}
