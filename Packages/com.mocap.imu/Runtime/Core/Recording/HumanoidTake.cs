// The engine-free half of an editor take that plays on any Humanoid avatar. Each solved pose is
// applied to the avatar; the editor reads it back through Unity's HumanPoseHandler (body position
// and rotation, the muscle array) and the avatar's bone transforms, and hands those numbers to
// HumanoidTake.Add. At the end the take becomes curve data the editor writes into two
// AnimationClips with AnimationUtility.SetEditorCurve:
//   Humanoid clip  Animator curves on path "": RootT.x/y/z (HumanPose.bodyPosition, the centre of
//                  mass already divided by the avatar's human scale), RootQ.x/y/z/w
//                  (HumanPose.bodyRotation), one curve per muscle, named as Unity's own Humanoid
//                  clips name them (HumanTrait.MuscleName, except the finger muscles, which clips
//                  store as "LeftHand.Thumb.1 Stretched" where HumanTrait says "Left Thumb 1 Stretched")
//   Generic clip   Transform curves per bone path: m_LocalRotation.x/y/z/w, plus m_LocalPosition.x/y/z
//                  of the first bone (the hips), which carries the walk.
// Keys sit exactly on the model's frame clock (frame index / rate, computed per key, so a long take
// does not drift), every quaternion stream keeps one sign from key to key (no flips for the curve
// interpolation to spin through), and every frame is a key unless a reduction with explicit
// tolerances is asked for.

using System;
using System.Collections.Generic;
using Mocap.Imu.Maths;

namespace Mocap.Imu.Recording
{
    /// <summary>The component a curve animates.</summary>
    public enum CurveTarget
    {
        /// <summary>The Animator (humanoid root and muscle curves; path "").</summary>
        Animator,
        /// <summary>A Transform of the recorded hierarchy.</summary>
        Transform,
    }

    /// <summary>One float curve: where it binds and its keys.</summary>
    public sealed class TakeCurve
    {
        internal TakeCurve(string path, CurveTarget target, string property, float[] times, float[] values)
        {
            Path = path;
            Target = target;
            Property = property;
            Times = times;
            Values = values;
        }

        /// <summary>Transform path relative to the animated root ("" for Animator curves).</summary>
        public string Path { get; }

        /// <summary>The component type bound (EditorCurveBinding.type).</summary>
        public CurveTarget Target { get; }

        /// <summary>The property name (EditorCurveBinding.propertyName).</summary>
        public string Property { get; }

        /// <summary>Key times, seconds from the take's first frame.</summary>
        public float[] Times { get; }

        /// <summary>Key values, one per time.</summary>
        public float[] Values { get; }

        /// <summary>
        /// Per key, the slope that arrives at it (Keyframe.inTangent) and the one that leaves it
        /// (Keyframe.outTangent): the slopes of the straight lines between neighbouring keys, so a
        /// Unity curve passes linearly from key to key, the interpolation the reduction's error
        /// bound assumes (the ends repeat their one neighbour's slope; a lone key has 0).
        /// </summary>
        public void LinearTangents(int key, out float inTangent, out float outTangent)
        {
            if ((uint)key >= (uint)Times.Length) throw new ArgumentOutOfRangeException(nameof(key), key, $"the curve has {Times.Length} keys");
            float before = key > 0 ? Slope(key - 1) : float.NaN;
            float after = key + 1 < Times.Length ? Slope(key) : float.NaN;
            inTangent = float.IsNaN(before) ? (float.IsNaN(after) ? 0f : after) : before;
            outTangent = float.IsNaN(after) ? (float.IsNaN(before) ? 0f : before) : after;
        }

        float Slope(int from) => (Values[from + 1] - Values[from]) / (Times[from + 1] - Times[from]);
    }

    /// <summary>
    /// Optional key reduction. Every tolerance is explicit: a key is dropped only while linear
    /// interpolation between the kept keys (normalised for quaternions, as Unity evaluates a
    /// rotation curve with linear tangents) stays within it at every recorded frame.
    /// </summary>
    public readonly struct KeyReduction
    {
        /// <summary>A reduction with the given tolerances (each at least 0).</summary>
        public KeyReduction(float angleDegrees, float muscle, float position)
        {
            if (!(angleDegrees >= 0) || !(muscle >= 0) || !(position >= 0) ||
                float.IsInfinity(angleDegrees) || float.IsInfinity(muscle) || float.IsInfinity(position))
                throw new ArgumentOutOfRangeException(nameof(angleDegrees),
                    $"tolerances must be finite and at least 0 (angle {angleDegrees} deg, muscle {muscle}, position {position})");
            AngleDegrees = angleDegrees;
            MuscleTolerance = muscle;
            PositionTolerance = position;
            Enabled = true;
        }

        /// <summary>No reduction: every frame is a key (the default).</summary>
        public static KeyReduction None => default;

        /// <summary>False for <see cref="None"/>.</summary>
        public bool Enabled { get; }

        /// <summary>Largest rotation error, degrees (RootQ and bone rotations).</summary>
        public float AngleDegrees { get; }

        /// <summary>Largest muscle error, in muscle units (-1..1 is the full range).</summary>
        public float MuscleTolerance { get; }

        /// <summary>Largest position error: metres for bones, human-scale units for RootT.</summary>
        public float PositionTolerance { get; }
    }

    /// <summary>Curve names of Humanoid and Generic clips.</summary>
    public static class HumanoidCurveNames
    {
        /// <summary>Body (centre of mass) position curves' prefix.</summary>
        public const string RootPosition = "RootT";

        /// <summary>Body rotation curves' prefix.</summary>
        public const string RootRotation = "RootQ";

        /// <summary>Transform local rotation property prefix.</summary>
        public const string LocalRotation = "m_LocalRotation";

        /// <summary>Transform local position property prefix.</summary>
        public const string LocalPosition = "m_LocalPosition";

        static readonly string[] Fingers = { "Thumb", "Index", "Middle", "Ring", "Little" };

        /// <summary>"RootT.x" ... for axis 0..2 (position) or 0..3 (rotation, w last).</summary>
        public static string Component(string prefix, int axis)
        {
            if (axis < 0 || axis > 3) throw new ArgumentOutOfRangeException(nameof(axis), axis, "0..3 (x, y, z, w)");
            return prefix + "." + "xyzw"[axis];
        }

        /// <summary>
        /// The clip property of a muscle named <paramref name="humanTraitName"/> by
        /// HumanTrait.MuscleName: the same name for body muscles ("Spine Front-Back"), and
        /// "LeftHand.Thumb.1 Stretched" / "RightHand.Index.Spread" for "Left Thumb 1 Stretched" /
        /// "Right Index Spread".
        /// </summary>
        public static string MuscleProperty(string humanTraitName)
        {
            if (string.IsNullOrWhiteSpace(humanTraitName)) throw new ArgumentException("a muscle name is empty", nameof(humanTraitName));
            var words = humanTraitName.Split(' ');
            if (words.Length < 3 || (words[0] != "Left" && words[0] != "Right") || Array.IndexOf(Fingers, words[1]) < 0)
                return humanTraitName;
            string hand = words[0] + "Hand." + words[1];
            if (words.Length == 3 && words[2] == "Spread") return hand + ".Spread";
            if (words.Length == 4 && words[3] == "Stretched" && words[2].Length == 1 && words[2][0] >= '1' && words[2][0] <= '3')
                return hand + "." + words[2] + " Stretched";
            return humanTraitName;
        }
    }

    /// <summary>
    /// Samples of one avatar gathered during a take (body, muscles, generic bones), turned into
    /// Humanoid and Generic clip curves at the model's rate. <see cref="Add"/> allocates nothing
    /// while the take fits the capacity given (storage doubles when it does not).
    /// </summary>
    public sealed class HumanoidTake
    {
        const int BodyStride = 7; // RootT xyz, RootQ xyzw

        readonly string[] _muscleProperties;
        readonly string[] _bonePaths;
        readonly int _boneStride;
        readonly ulong _duplicateWindow;

        long[] _frameIndex;
        float[] _body;
        float[] _muscles;
        float[] _bones; // per frame: root bone position xyz, then xyzw per bone
        int _count;

        ulong _lastSequence;
        ulong _segmentFirstSequence;
        long _segmentBase;

        /// <summary>
        /// A take at <paramref name="frameRate"/> (the model's) for an avatar with the muscles
        /// <paramref name="muscleNames"/> (HumanTrait.MuscleName order, the order of HumanPose.muscles)
        /// and the generic bones <paramref name="bonePaths"/> (transform paths relative to the
        /// animated root; the first is the hips; empty for no generic clip).
        /// </summary>
        public HumanoidTake(float frameRate, IReadOnlyList<string> muscleNames, IReadOnlyList<string> bonePaths, int capacityFrames = 3600)
        {
            if (!(frameRate > 0) || float.IsInfinity(frameRate))
                throw new ArgumentOutOfRangeException(nameof(frameRate), frameRate, "must be positive");
            if (muscleNames == null) throw new ArgumentNullException(nameof(muscleNames));
            if (capacityFrames < 1) throw new ArgumentOutOfRangeException(nameof(capacityFrames), capacityFrames, "must be at least 1");
            FrameRate = frameRate;
            _muscleProperties = new string[muscleNames.Count];
            var seen = new HashSet<string>(StringComparer.Ordinal);
            for (int i = 0; i < muscleNames.Count; i++)
            {
                _muscleProperties[i] = HumanoidCurveNames.MuscleProperty(muscleNames[i]);
                if (!seen.Add(_muscleProperties[i])) throw new ArgumentException($"muscle '{muscleNames[i]}' is listed twice", nameof(muscleNames));
            }
            _bonePaths = new string[bonePaths?.Count ?? 0];
            seen.Clear();
            for (int i = 0; i < _bonePaths.Length; i++)
            {
                var path = bonePaths[i] ?? throw new ArgumentException($"bone path {i} is null", nameof(bonePaths));
                if (path.StartsWith("/", StringComparison.Ordinal) || path.EndsWith("/", StringComparison.Ordinal) || path.Contains("\\"))
                    throw new ArgumentException($"bone path '{path}' must be relative to the root, '/'-separated, without a leading or trailing '/'", nameof(bonePaths));
                if (!seen.Add(path)) throw new ArgumentException($"bone path '{path}' is listed twice", nameof(bonePaths));
                _bonePaths[i] = path;
            }
            _boneStride = _bonePaths.Length == 0 ? 0 : 3 + 4 * _bonePaths.Length;
            _duplicateWindow = (ulong)Math.Max(1.0, Math.Ceiling(frameRate));
            Allocate(capacityFrames);
        }

        /// <summary>The model's frame rate: keys are 1/FrameRate apart.</summary>
        public float FrameRate { get; }

        /// <summary>Muscles per sample.</summary>
        public int MuscleCount => _muscleProperties.Length;

        /// <summary>Generic bones per sample (0: no generic clip).</summary>
        public int BoneCount => _bonePaths.Length;

        /// <summary>Samples kept.</summary>
        public int Count => _count;

        /// <summary>Frames the storage holds before it grows.</summary>
        public int Capacity => _frameIndex.Length;

        /// <summary>Model frames between the first and the last sample that have no sample (poses the editor never saw).</summary>
        public long MissingFrames => _count == 0 ? 0 : _frameIndex[_count - 1] + 1 - _count;

        /// <summary>Seconds from the first to the last key.</summary>
        public double DurationSeconds => _count == 0 ? 0 : _frameIndex[_count - 1] / (double)FrameRate;

        /// <summary>
        /// Keep one sample. <paramref name="sequence"/> is the pose's model frame
        /// (<see cref="MocapPose.Sequence"/>): the same sequence again, or one a little older (within a
        /// second of frames) is a late duplicate and ignored (false); one that goes back further is a
        /// restarted engine, whose frames continue after the last kept one. Muscles in
        /// HumanTrait order, bone rotations in the order of the bone paths, local to each parent.
        /// </summary>
        /// <exception cref="ArgumentException">A count does not match the take, or a value is not finite.</exception>
        public bool Add(ulong sequence, Vec3 bodyPosition, Quat bodyRotation, ReadOnlySpan<float> muscles,
                        Vec3 hipsLocalPosition, ReadOnlySpan<Quat> boneLocalRotations)
        {
            if (muscles.Length != _muscleProperties.Length)
                throw new ArgumentException($"{muscles.Length} muscles given, the take has {_muscleProperties.Length}", nameof(muscles));
            if (boneLocalRotations.Length != _bonePaths.Length)
                throw new ArgumentException($"{boneLocalRotations.Length} bone rotations given, the take has {_bonePaths.Length}", nameof(boneLocalRotations));
            CheckFinite(bodyPosition, bodyRotation, muscles, hipsLocalPosition, boneLocalRotations);

            long frame;
            if (_count == 0)
            {
                _segmentFirstSequence = sequence;
                _segmentBase = 0;
                frame = 0;
            }
            else if (sequence > _lastSequence)
            {
                frame = _segmentBase + (long)(sequence - _segmentFirstSequence);
            }
            else
            {
                if (sequence == _lastSequence) return false;
                bool late = sequence >= _segmentFirstSequence && _lastSequence - sequence <= _duplicateWindow;
                if (late) return false;
                _segmentBase = _frameIndex[_count - 1] + 1;
                _segmentFirstSequence = sequence;
                frame = _segmentBase;
            }
            if (_count == _frameIndex.Length) Grow();

            int i = _count;
            _frameIndex[i] = frame;
            int b = i * BodyStride;
            _body[b] = bodyPosition.X;
            _body[b + 1] = bodyPosition.Y;
            _body[b + 2] = bodyPosition.Z;
            StoreContinuous(_body, b + 3, bodyRotation, i == 0 ? -1 : b + 3 - BodyStride);
            muscles.CopyTo(new Span<float>(_muscles, i * _muscleProperties.Length, _muscleProperties.Length));
            if (_boneStride > 0)
            {
                int o = i * _boneStride;
                _bones[o] = hipsLocalPosition.X;
                _bones[o + 1] = hipsLocalPosition.Y;
                _bones[o + 2] = hipsLocalPosition.Z;
                for (int k = 0; k < boneLocalRotations.Length; k++)
                {
                    int at = o + 3 + 4 * k;
                    StoreContinuous(_bones, at, boneLocalRotations[k], i == 0 ? -1 : at - _boneStride);
                }
            }
            _count++;
            _lastSequence = sequence;
            return true;
        }

        /// <summary>Forget every sample (a new take), keeping the storage.</summary>
        public void Clear()
        {
            _count = 0;
            _lastSequence = 0;
            _segmentFirstSequence = 0;
            _segmentBase = 0;
        }

        /// <summary>Time of the key of sample <paramref name="index"/>: its model frame / the rate.</summary>
        public float KeyTime(int index)
        {
            if ((uint)index >= (uint)_count) throw new ArgumentOutOfRangeException(nameof(index), index, $"the take has {_count} samples");
            return (float)(_frameIndex[index] / (double)FrameRate);
        }

        /// <summary>
        /// The Humanoid clip's curves: RootT.x/y/z, RootQ.x/y/z/w, then one per muscle (path "",
        /// Animator). Every sample is a key unless <paramref name="reduction"/> is enabled.
        /// </summary>
        public List<TakeCurve> HumanoidCurves(KeyReduction reduction = default)
        {
            var curves = new List<TakeCurve>(BodyStride + _muscleProperties.Length);
            if (_count == 0) return curves;
            var position = KeepFrames(_body, BodyStride, 0, 3, ErrorKind.Position, reduction.PositionTolerance, reduction.Enabled);
            for (int a = 0; a < 3; a++)
                curves.Add(Curve("", CurveTarget.Animator, HumanoidCurveNames.Component(HumanoidCurveNames.RootPosition, a), _body, BodyStride, a, position));
            var rotation = KeepFrames(_body, BodyStride, 3, 4, ErrorKind.Rotation, reduction.AngleDegrees, reduction.Enabled);
            for (int a = 0; a < 4; a++)
                curves.Add(Curve("", CurveTarget.Animator, HumanoidCurveNames.Component(HumanoidCurveNames.RootRotation, a), _body, BodyStride, 3 + a, rotation));
            int m = _muscleProperties.Length;
            for (int k = 0; k < m; k++)
            {
                var keep = KeepFrames(_muscles, m, k, 1, ErrorKind.Scalar, reduction.MuscleTolerance, reduction.Enabled);
                curves.Add(Curve("", CurveTarget.Animator, _muscleProperties[k], _muscles, m, k, keep));
            }
            return curves;
        }

        /// <summary>
        /// The Generic clip's curves: m_LocalPosition.x/y/z of the first bone, then
        /// m_LocalRotation.x/y/z/w of every bone (Transform, by path). Empty without bones.
        /// </summary>
        public List<TakeCurve> GenericCurves(KeyReduction reduction = default)
        {
            var curves = new List<TakeCurve>(3 + 4 * _bonePaths.Length);
            if (_count == 0 || _boneStride == 0) return curves;
            var position = KeepFrames(_bones, _boneStride, 0, 3, ErrorKind.Position, reduction.PositionTolerance, reduction.Enabled);
            for (int a = 0; a < 3; a++)
                curves.Add(Curve(_bonePaths[0], CurveTarget.Transform, HumanoidCurveNames.Component(HumanoidCurveNames.LocalPosition, a), _bones, _boneStride, a, position));
            for (int k = 0; k < _bonePaths.Length; k++)
            {
                int offset = 3 + 4 * k;
                var keep = KeepFrames(_bones, _boneStride, offset, 4, ErrorKind.Rotation, reduction.AngleDegrees, reduction.Enabled);
                for (int a = 0; a < 4; a++)
                    curves.Add(Curve(_bonePaths[k], CurveTarget.Transform, HumanoidCurveNames.Component(HumanoidCurveNames.LocalRotation, a), _bones, _boneStride, offset + a, keep));
            }
            return curves;
        }

        // ---- storage ------------------------------------------------------------------------

        void Allocate(int frames)
        {
            _frameIndex = new long[frames];
            _body = new float[frames * BodyStride];
            _muscles = new float[frames * Math.Max(1, _muscleProperties.Length)];
            _bones = new float[frames * Math.Max(1, _boneStride)];
        }

        void Grow()
        {
            int frames = checked(_frameIndex.Length * 2);
            Array.Resize(ref _frameIndex, frames);
            Array.Resize(ref _body, frames * BodyStride);
            Array.Resize(ref _muscles, frames * Math.Max(1, _muscleProperties.Length));
            Array.Resize(ref _bones, frames * Math.Max(1, _boneStride));
        }

        // q and -q are one rotation; the curves interpolate components, so each key takes the sign
        // nearer the previous key's, else the avatar spins the long way round between them.
        static void StoreContinuous(float[] store, int at, Quat q, int previous)
        {
            float sign = 1f;
            if (previous >= 0)
            {
                float dot = store[previous] * q.X + store[previous + 1] * q.Y + store[previous + 2] * q.Z + store[previous + 3] * q.W;
                if (dot < 0f) sign = -1f;
            }
            store[at] = sign * q.X;
            store[at + 1] = sign * q.Y;
            store[at + 2] = sign * q.Z;
            store[at + 3] = sign * q.W;
        }

        static void CheckFinite(Vec3 bodyPosition, Quat bodyRotation, ReadOnlySpan<float> muscles, Vec3 hips, ReadOnlySpan<Quat> bones)
        {
            if (!IsFinite(bodyPosition) || !bodyRotation.IsFinite || !IsFinite(hips))
                throw new ArgumentException("the body position, body rotation or hips position is not finite");
            for (int i = 0; i < muscles.Length; i++)
                if (!float.IsFinite(muscles[i])) throw new ArgumentException($"muscle {i} is not finite ({muscles[i]})", nameof(muscles));
            for (int i = 0; i < bones.Length; i++)
                if (!bones[i].IsFinite || !(bones[i].LengthSquared > 0f))
                    throw new ArgumentException($"bone rotation {i} is not a finite non-zero quaternion ({bones[i]})", nameof(bones));
        }

        static bool IsFinite(Vec3 v) => float.IsFinite(v.X) && float.IsFinite(v.Y) && float.IsFinite(v.Z);

        // ---- curves -------------------------------------------------------------------------

        TakeCurve Curve(string path, CurveTarget target, string property, float[] store, int stride, int channel, int[] keep)
        {
            var times = new float[keep.Length];
            var values = new float[keep.Length];
            for (int k = 0; k < keep.Length; k++)
            {
                int i = keep[k];
                times[k] = (float)(_frameIndex[i] / (double)FrameRate);
                values[k] = store[i * stride + channel];
            }
            return new TakeCurve(path, target, property, times, values);
        }

        enum ErrorKind
        {
            Scalar,
            Position,
            Rotation,
        }

        /// <summary>Sample indices kept as keys for the channel group store[i*stride + offset .. + width).</summary>
        int[] KeepFrames(float[] store, int stride, int offset, int width, ErrorKind kind, float tolerance, bool reduce)
        {
            if (!reduce || _count <= 2)
            {
                var all = new int[_count];
                for (int i = 0; i < _count; i++) all[i] = i;
                return all;
            }
            // Tolerance in the units the error is measured in (radians for rotations).
            float limit = kind == ErrorKind.Rotation ? tolerance * (MathF.PI / 180f) : tolerance;
            var keep = new bool[_count];
            keep[0] = keep[_count - 1] = true;
            // Douglas-Peucker over frame time: split each span at its worst sample until every
            // sample lies within the limit of the interpolation between the span's ends.
            var spans = new Stack<(int First, int Last)>();
            spans.Push((0, _count - 1));
            while (spans.Count > 0)
            {
                var (first, last) = spans.Pop();
                if (last - first < 2) continue;
                int worst = -1;
                float worstError = limit;
                for (int i = first + 1; i < last; i++)
                {
                    float e = Error(store, stride, offset, width, kind, first, last, i);
                    if (e > worstError)
                    {
                        worstError = e;
                        worst = i;
                    }
                }
                if (worst < 0) continue;
                keep[worst] = true;
                spans.Push((first, worst));
                spans.Push((worst, last));
            }
            int kept = 0;
            for (int i = 0; i < _count; i++)
                if (keep[i]) kept++;
            var indices = new int[kept];
            for (int i = 0, k = 0; i < _count; i++)
                if (keep[i]) indices[k++] = i;
            return indices;
        }

        float Error(float[] store, int stride, int offset, int width, ErrorKind kind, int first, int last, int i)
        {
            double span = _frameIndex[last] - _frameIndex[first];
            float t = (float)((_frameIndex[i] - _frameIndex[first]) / span);
            int a = first * stride + offset, b = last * stride + offset, s = i * stride + offset;
            switch (kind)
            {
                case ErrorKind.Scalar:
                    return MathF.Abs(store[a] + (store[b] - store[a]) * t - store[s]);
                case ErrorKind.Position:
                {
                    float sum = 0;
                    for (int c = 0; c < width; c++)
                    {
                        float d = store[a + c] + (store[b + c] - store[a + c]) * t - store[s + c];
                        sum += d * d;
                    }
                    return MathF.Sqrt(sum);
                }
                default:
                {
                    var interpolated = new Quat(
                        store[a] + (store[b] - store[a]) * t,
                        store[a + 1] + (store[b + 1] - store[a + 1]) * t,
                        store[a + 2] + (store[b + 2] - store[a + 2]) * t,
                        store[a + 3] + (store[b + 3] - store[a + 3]) * t);
                    var sample = new Quat(store[s], store[s + 1], store[s + 2], store[s + 3]);
                    return Quat.Angle(interpolated.Normalized, sample);
                }
            }
        }
    }
}
