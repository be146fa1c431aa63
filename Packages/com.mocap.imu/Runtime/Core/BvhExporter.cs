// BVH export of solved poses through the engine's own writer (mocap_bvh_open/append/close), so a
// take exported from the editor is byte-for-byte the format `mocapctl replay --out` writes: the
// SMPL-24 skeleton with the model's rest offsets, metres, model frame, Euler angles kept
// continuous between frames, and a header whose frame count is rewritten at every flush (a crash
// leaves a readable file). Read the result back with BvhFile (an independent reader).

using System;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu.Recording
{
    /// <summary>Euler order of the BVH rotation channels (mocap_bvh_rotation_order).</summary>
    public enum BvhRotationOrder
    {
        /// <summary>"Zrotation Xrotation Yrotation" (the engine's default, what most tools expect).</summary>
        Zxy = 0,
        /// <summary>"Xrotation Yrotation Zrotation".</summary>
        Xyz = 1,
    }

    /// <summary>How <see cref="BvhExporter"/> writes (mocap_bvh_options).</summary>
    public sealed class BvhExportOptions
    {
        /// <summary>Euler order of the rotation channels.</summary>
        public BvhRotationOrder RotationOrder { get; set; } = BvhRotationOrder.Zxy;

        /// <summary>Frames per second written as "Frame Time: 1/rate"; 0 = the poses' own rate.</summary>
        public float FrameRate { get; set; }

        /// <summary>Frames between flushes (and header updates); at least 1.</summary>
        public uint FlushEvery { get; set; } = 1;
    }

    /// <summary>
    /// Streams solved poses into a BVH file with the engine's writer. <see cref="Append(in MocapPose)"/>
    /// allocates nothing, so it can run every frame while a take is recorded; <see cref="Export"/>
    /// writes a whole <see cref="PoseRecording"/> at once. One thread per exporter.
    /// </summary>
    public sealed unsafe class BvhExporter : IDisposable
    {
        IntPtr _writer;

        BvhExporter(IntPtr writer, string path, float frameRate)
        {
            _writer = writer;
            Path = path;
            FrameRate = frameRate;
        }

        /// <summary>The file being written.</summary>
        public string Path { get; }

        /// <summary>Frames per second of the file (1 / Frame Time).</summary>
        public float FrameRate { get; }

        /// <summary>The exporter has been closed.</summary>
        public bool IsClosed => _writer == IntPtr.Zero;

        /// <summary>Frames appended so far (the engine's count).</summary>
        public long FrameCount
        {
            get
            {
                var writer = _writer;
                long frames = writer == IntPtr.Zero ? _closedFrames : (long)NativeBvhMethods.mocap_bvh_frames(writer);
                GC.KeepAlive(this);
                return frames;
            }
        }

        long _closedFrames;

        /// <summary>Create (or replace) a BVH file for the poses of a loaded model.</summary>
        public static BvhExporter Create(string path, ModelInfo model, BvhExportOptions options = null)
        {
            if (model == null) throw new ArgumentNullException(nameof(model));
            return Create(path, model.FrameRate, model.Skeleton, options, model.ContractVersion);
        }

        /// <summary>
        /// Create (or replace) a BVH file for poses solved at <paramref name="frameRate"/> on
        /// <paramref name="skeleton"/> (e.g. those of a <see cref="PoseRecording"/>: no model needed).
        /// </summary>
        /// <exception cref="MocapException">The engine could not create the file (its text names it).</exception>
        public static BvhExporter Create(string path, float frameRate, SmplSkeleton skeleton,
                                         BvhExportOptions options = null, int contractVersion = 1)
        {
            if (path == null) throw new ArgumentNullException(nameof(path));
            if (path.Length == 0) throw new ArgumentException("the BVH path is empty", nameof(path));
            if (skeleton == null) throw new ArgumentNullException(nameof(skeleton));
            if (!(frameRate > 0) || float.IsInfinity(frameRate))
                throw new ArgumentOutOfRangeException(nameof(frameRate), frameRate, "must be positive");
            options ??= new BvhExportOptions();
            if (options.FrameRate < 0 || float.IsNaN(options.FrameRate) || float.IsInfinity(options.FrameRate))
                throw new ArgumentOutOfRangeException(nameof(options), options.FrameRate, "FrameRate must be 0 (the poses' rate) or positive");

            MocapEngine.EnsureCompatible();
            NativeModelInfo info;
            FillModelInfo(&info, frameRate, skeleton, contractVersion);
            NativeBvhOptions native;
            NativeMethods.Check(NativeBvhMethods.mocap_bvh_options_defaults(&native));
            native.RotationOrder = (int)options.RotationOrder;
            native.FrameRate = options.FrameRate;
            native.FlushEvery = Math.Max(1u, options.FlushEvery);

            byte[] utf8 = NativeText.ToNullTerminated(path, nameof(path));
            IntPtr writer;
            MocapStatus status;
            fixed (byte* p = utf8)
                status = NativeBvhMethods.mocap_bvh_open(p, &info, &native, out writer);
            if (status != MocapStatus.Ok) throw NativeMethods.Failure(status);
            return new BvhExporter(writer, path, options.FrameRate > 0 ? options.FrameRate : frameRate);
        }

        /// <summary>
        /// Write a whole recording to <paramref name="path"/> and return the frame count. Poses
        /// keep the recording's order; its frame rate is the file's unless the options set one.
        /// The engine writes a temporary file beside <paramref name="path"/>, which replaces it
        /// only after the engine closed it without error: a failure leaves the previous file as it was.
        /// </summary>
        /// <exception cref="MocapException">Writing or replacing failed (the text names <paramref name="path"/>).</exception>
        public static long Export(PoseRecording recording, string path, BvhExportOptions options = null)
        {
            if (recording == null) throw new ArgumentNullException(nameof(recording));
            if (path == null) throw new ArgumentNullException(nameof(path));
            if (path.Length == 0) throw new ArgumentException("the BVH path is empty", nameof(path));
            // The engine refuses paths of MOCAP_PATH_MAX (260) UTF-8 bytes or more.
            string temporary = RecordingFiles.TemporaryPathFor(path, maxUtf8Bytes: 259);
            bool replaced = false;
            try
            {
                long frames;
                try
                {
                    var exporter = Create(temporary, recording.FrameRate, recording.Skeleton, options, recording.ContractVersion);
                    try
                    {
                        exporter.Append(recording.Poses);
                    }
                    catch
                    {
                        exporter.CloseQuietly();
                        throw;
                    }
                    frames = exporter.Close();
                }
                catch (MocapException e)
                {
                    // The engine's text names the temporary: name the file the caller asked for.
                    throw new MocapException(e.Status, e.Message.Replace(temporary, path), e);
                }
                RecordingFiles.Replace(temporary, path, "BVH", syncFirst: true);
                replaced = true;
                return frames;
            }
            finally
            {
                if (!replaced) RecordingFiles.DeleteQuietly(temporary);
            }
        }

        /// <summary>Append one pose (its root position and joint rotations) as one frame. Allocates nothing.</summary>
        public void Append(in MocapPose pose)
        {
            var writer = Writer;
            // A copy on the stack: the engine needs an address and `in` gives a readonly reference.
            MocapPose copy = pose;
            var status = NativeBvhMethods.mocap_bvh_append(writer, &copy);
            // Until the native call has returned, the finalizer must not close the writer.
            GC.KeepAlive(this);
            if (status != MocapStatus.Ok) throw NativeMethods.Failure(status);
        }

        /// <summary>Append poses in order. Allocates nothing.</summary>
        public void Append(ReadOnlySpan<MocapPose> poses)
        {
            var writer = Writer;
            fixed (MocapPose* first = poses)
            {
                for (int i = 0; i < poses.Length; i++)
                {
                    var status = NativeBvhMethods.mocap_bvh_append(writer, first + i);
                    if (status != MocapStatus.Ok) throw NativeMethods.Failure(status);
                }
            }
            GC.KeepAlive(this); // see Append(in MocapPose)
        }

        /// <summary>
        /// Flush, write the final frame count and close the file; returns the frame count.
        /// Closing twice is allowed (the second call returns the same count).
        /// </summary>
        /// <exception cref="MocapException">The first write error of the file (disk full ...).</exception>
        public long Close()
        {
            if (_writer == IntPtr.Zero) return _closedFrames;
            var writer = _writer;
            _closedFrames = (long)NativeBvhMethods.mocap_bvh_frames(writer);
            _writer = IntPtr.Zero;
            GC.SuppressFinalize(this);
            var status = NativeBvhMethods.mocap_bvh_close(writer);
            if (status != MocapStatus.Ok) throw NativeMethods.Failure(status);
            return _closedFrames;
        }

        /// <summary>Same as <see cref="Close"/> (throws the file's first write error).</summary>
        public void Dispose() => Close();

        ~BvhExporter()
        {
            // A leaked exporter still closes its file (errors have nobody to go to here).
            if (_writer != IntPtr.Zero) NativeBvhMethods.mocap_bvh_close(_writer);
        }

        void CloseQuietly()
        {
            try
            {
                Close();
            }
            catch (MocapException)
            {
                // The caller is already failing with the first error.
            }
        }

        IntPtr Writer
        {
            get
            {
                if (_writer == IntPtr.Zero) throw new ObjectDisposedException(nameof(BvhExporter), Path);
                return _writer;
            }
        }

        // The writer reads names, parents, rest offsets and the frame rate of mocap_model_info; the
        // skeleton gives the contract's names and parents and the recording's (or model's) offsets.
        static void FillModelInfo(NativeModelInfo* info, float frameRate, SmplSkeleton skeleton, int contractVersion)
        {
            *info = default;
            info->ContractVersion = contractVersion;
            info->FrameRate = frameRate;
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
            {
                info->JointParents[j] = SmplSkeleton.ParentOf(j);
                var offset = skeleton.RestOffset(j);
                info->RestOffsets[3 * j] = offset.X;
                info->RestOffsets[3 * j + 1] = offset.Y;
                info->RestOffsets[3 * j + 2] = offset.Z;
                NativeText.ToBuffer(SmplSkeleton.NameOf(j), info->JointNames + 32 * j, 32, "joint name");
            }
            NativeText.ToBuffer("fp32", info->Precision, 8, "precision");
        }
    }
}
