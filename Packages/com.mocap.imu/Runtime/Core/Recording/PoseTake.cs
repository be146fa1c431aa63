// The engine-side half of an editor take: the solved poses that drove the avatar while the
// editor's TakeRecorder filled an AnimationClip, kept so the take can be saved as a pose
// recording and exported to BVH (BvhExporter) later. Also the take's file naming, so the editor
// and the tests agree on it without Unity.

using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu.Recording
{
    /// <summary>
    /// Poses of one character gathered during a take. Poses arrive in solve order; one already
    /// added (same <see cref="MocapPose.Sequence"/> or older) is ignored, so a caller may hand in
    /// the latest pose every frame without duplicating it.
    /// </summary>
    public sealed class PoseTake
    {
        readonly List<MocapPose> _poses;
        ulong _lastSequence;
        bool _any;

        /// <summary>A take for poses solved at <paramref name="frameRate"/> on <paramref name="skeleton"/>.</summary>
        public PoseTake(float frameRate, SmplSkeleton skeleton, int contractVersion = 1, int capacity = 1024)
        {
            if (!(frameRate > 0) || float.IsInfinity(frameRate))
                throw new ArgumentOutOfRangeException(nameof(frameRate), frameRate, "must be positive");
            FrameRate = frameRate;
            Skeleton = skeleton ?? throw new ArgumentNullException(nameof(skeleton));
            ContractVersion = contractVersion;
            _poses = new List<MocapPose>(Math.Max(16, capacity));
        }

        /// <summary>A take for poses of a loaded model.</summary>
        public PoseTake(ModelInfo model) : this(model?.FrameRate ?? 0, model?.Skeleton, model?.ContractVersion ?? 1)
        {
        }

        public float FrameRate { get; }
        public SmplSkeleton Skeleton { get; }
        public int ContractVersion { get; }

        /// <summary>Poses kept so far.</summary>
        public int Count => _poses.Count;

        /// <summary>Session time from the first to the last pose, seconds (0 with fewer than two).</summary>
        public double DurationSeconds => _poses.Count < 2 ? 0 : _poses[_poses.Count - 1].TimeSeconds - _poses[0].TimeSeconds;

        /// <summary>Keep a pose unless it is the one added last or older. True when kept.</summary>
        public bool Add(in MocapPose pose)
        {
            if (_any && pose.Sequence <= _lastSequence) return false;
            _poses.Add(pose);
            _lastSequence = pose.Sequence;
            _any = true;
            return true;
        }

        /// <summary>Forget every pose (a new take).</summary>
        public void Clear()
        {
            _poses.Clear();
            _any = false;
            _lastSequence = 0;
        }

        /// <summary>The take as a pose recording (copies the poses).</summary>
        public PoseRecording ToRecording() =>
            new PoseRecording(FrameRate, Skeleton, _poses.ToArray(), ContractVersion);
    }

    /// <summary>File names of editor takes.</summary>
    public static class TakeNaming
    {
        /// <summary>The project folder takes are saved in.</summary>
        public const string DefaultFolder = "Assets/Mocap Takes";

        /// <summary>Extension of a take's pose recording (next to its clip).</summary>
        public const string PoseExtension = ".mcpose";

        /// <summary>"Take 2024-05-01 14-03-07" or "Avatar Take 2024-05-01 14-03-07" (no characters a file system refuses).</summary>
        public static string TakeName(DateTime time, string prefix = null)
        {
            var stamp = time.ToString("yyyy-MM-dd HH-mm-ss", CultureInfo.InvariantCulture);
            var clean = Sanitize(prefix);
            return clean.Length == 0 ? "Take " + stamp : clean + " Take " + stamp;
        }

        /// <summary>
        /// "folder/name.ext", or "folder/name 2.ext", "name 3.ext" ... when
        /// <paramref name="exists"/> says the path is taken. Paths use '/' (Unity asset paths).
        /// </summary>
        public static string UniquePath(string folder, string name, string extension, Func<string, bool> exists)
        {
            if (folder == null) throw new ArgumentNullException(nameof(folder));
            if (exists == null) throw new ArgumentNullException(nameof(exists));
            folder = folder.Replace('\\', '/').TrimEnd('/');
            var baseName = Sanitize(name);
            if (baseName.Length == 0) baseName = "Take";
            if (!string.IsNullOrEmpty(extension) && extension[0] != '.') extension = "." + extension;
            var path = $"{folder}/{baseName}{extension}";
            for (int n = 2; exists(path); n++)
            {
                if (n > 10000) throw new IOException($"no free file name for {baseName} in {folder}");
                path = $"{folder}/{baseName} {n}{extension}";
            }
            return path;
        }

        /// <summary>The pose recording path that goes with a clip path ("X.anim" -> "X.mcpose").</summary>
        public static string PosePathFor(string clipPath)
        {
            if (clipPath == null) throw new ArgumentNullException(nameof(clipPath));
            return Path.ChangeExtension(clipPath, PoseExtension).Replace('\\', '/');
        }

        static string Sanitize(string name)
        {
            if (string.IsNullOrEmpty(name)) return string.Empty;
            var invalid = Path.GetInvalidFileNameChars();
            var chars = name.ToCharArray();
            for (int i = 0; i < chars.Length; i++)
            {
                // Also the characters Windows refuses even where this OS allows them.
                if (Array.IndexOf(invalid, chars[i]) >= 0 || "<>:\"/\\|?*".IndexOf(chars[i]) >= 0 || chars[i] < ' ')
                    chars[i] = '_';
            }
            return new string(chars).Trim().TrimEnd('.');
        }
    }
}
