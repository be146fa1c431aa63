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
    /// Poses of one character gathered during a take. Poses arrive in solve order; the one added
    /// last (same <see cref="MocapPose.Sequence"/>) is ignored, so a caller may hand in the latest
    /// pose every frame without duplicating it, and so is a pose slightly older than the last
    /// (within one second of model frames, and not older than the segment's first pose).
    /// </summary>
    /// <remarks>
    /// A restarted engine (loop playback, a recording restart) numbers its poses from 0 again: a
    /// sequence that goes back further than that, or below the first pose of the current segment,
    /// starts a new segment, which is kept. The take's poses are then the segments one after the
    /// other, in the order they were solved.
    /// </remarks>
    public sealed class PoseTake
    {
        readonly List<MocapPose> _poses;
        readonly ulong _duplicateWindow;
        ulong _lastSequence;
        ulong _segmentFirstSequence;
        int _segmentStart;
        int _segments;
        double _closedSegmentsSeconds;

        /// <summary>A take for poses solved at <paramref name="frameRate"/> on <paramref name="skeleton"/>.</summary>
        public PoseTake(float frameRate, SmplSkeleton skeleton, int contractVersion = 1, int capacity = 1024)
        {
            if (!(frameRate > 0) || float.IsInfinity(frameRate))
                throw new ArgumentOutOfRangeException(nameof(frameRate), frameRate, "must be positive");
            FrameRate = frameRate;
            Skeleton = skeleton ?? throw new ArgumentNullException(nameof(skeleton));
            ContractVersion = contractVersion;
            _poses = new List<MocapPose>(Math.Max(16, capacity));
            // One second of model frames: a pose that far behind the last is a late duplicate.
            _duplicateWindow = (ulong)Math.Max(1.0, Math.Ceiling(frameRate));
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

        /// <summary>Runs of increasing sequence kept so far: 1 plus the engine restarts seen (0 when empty).</summary>
        public int Segments => _segments;

        /// <summary>
        /// Session time covered by the poses, seconds: from the first to the last pose of each
        /// segment, summed over the segments (0 with fewer than two poses).
        /// </summary>
        public double DurationSeconds =>
            _segments == 0 ? 0 : _closedSegmentsSeconds + SegmentSeconds(_segmentStart, _poses.Count - 1);

        /// <summary>
        /// Keep a pose unless it repeats the one added last or is a little older (see the class
        /// remarks); a sequence that goes back further starts a new segment. True when kept.
        /// </summary>
        public bool Add(in MocapPose pose)
        {
            if (_segments > 0 && pose.Sequence <= _lastSequence)
            {
                if (pose.Sequence == _lastSequence) return false;
                bool restarted = pose.Sequence < _segmentFirstSequence || _lastSequence - pose.Sequence > _duplicateWindow;
                if (!restarted) return false;
                _closedSegmentsSeconds += SegmentSeconds(_segmentStart, _poses.Count - 1);
                _segments++;
                _segmentStart = _poses.Count;
                _segmentFirstSequence = pose.Sequence;
            }
            else if (_segments == 0)
            {
                _segments = 1;
                _segmentStart = 0;
                _segmentFirstSequence = pose.Sequence;
            }
            _poses.Add(pose);
            _lastSequence = pose.Sequence;
            return true;
        }

        double SegmentSeconds(int first, int last) =>
            last > first ? _poses[last].TimeSeconds - _poses[first].TimeSeconds : 0;

        /// <summary>Forget every pose (a new take).</summary>
        public void Clear()
        {
            _poses.Clear();
            _segments = 0;
            _segmentStart = 0;
            _segmentFirstSequence = 0;
            _lastSequence = 0;
            _closedSegmentsSeconds = 0;
        }

        /// <summary>The take as a pose recording (copies the poses).</summary>
        public PoseRecording ToRecording() =>
            new PoseRecording(FrameRate, Skeleton, _poses.ToArray(), ContractVersion);
    }

    /// <summary>File names of editor takes and of raw capture recordings.</summary>
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

        /// <summary>Extension of a raw capture recording.</summary>
        public const string CaptureExtension = ".cap";

        /// <summary>
        /// Where a character's raw capture is recorded: "folder/yyyyMMdd-HHmmss-fff-C-Name.cap",
        /// or "...-Name-2.cap", "-3" ... when <paramref name="exists"/> says the path is taken
        /// (the engine's capture writer truncates an existing file, so a name must never be reused:
        /// recordings restarted within a second, loop playback).
        /// </summary>
        public static string CapturePath(string folder, DateTime time, int character, string characterName,
                                         Func<string, bool> exists)
        {
            if (folder == null) throw new ArgumentNullException(nameof(folder));
            if (exists == null) throw new ArgumentNullException(nameof(exists));
            var name = Sanitize(characterName).Replace(' ', '_');
            if (name.Length == 0) name = "character";
            var stem = string.Format(CultureInfo.InvariantCulture, "{0:yyyyMMdd-HHmmss-fff}-{1}-{2}", time, character, name);
            var path = Path.Combine(folder, stem + CaptureExtension);
            for (int n = 2; exists(path); n++)
            {
                if (n > 10000) throw new IOException($"no free capture file name for {stem} in {folder}");
                path = Path.Combine(folder, $"{stem}-{n}{CaptureExtension}");
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
