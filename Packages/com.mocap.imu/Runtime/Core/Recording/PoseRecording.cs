// Binary pose recordings: solved poses stored exactly, for playback in the editor and PlayMode
// tests (no parsing, no rounding, one seek per frame).
//
// Format, version 1, little-endian throughout:
//   offset  size  field
//        0     8  magic "MCPOSREC"
//        8     4  u32 version (1)
//       12     4  u32 joint count (24)
//       16     4  u32 record size in bytes (760: sizeof(mocap_pose))
//       20     4  f32 frame rate of the model that solved the poses, Hz
//       24     8  u64 pose count (rewritten on every Flush and on close)
//       32     4  i32 model contract version
//       36     4  u32 reserved (0)
//       40   288  f32 rest offsets [24][3] of the model's skeleton (metres, model frame), so the
//                 recording plays without the model
//      328     -  pose records, each the bytes of a mocap_pose (API version 2): u64 sequence,
//                 u64 frame_sequence, f64 time_s, u32 character, u32 flags, f32 rotations [24][4]
//                 (w,x,y,z), f32 positions [24][3], f32 root_position[3], f32 root_velocity[3],
//                 f32 foot_contact[2], i64 newest_receive_ns, i64 frame_emitted_ns,
//                 i64 pose_emitted_ns: no padding.
// A reader requires the file to hold at least `pose count` whole records. Whole records beyond the
// count are read too, and a partial record after them is left out (PoseRecording.DiscardedTailBytes):
// both are what a writer leaves when it dies, or is read, between two Flushes (its file buffer
// hands the OS whatever fits, so the file often ends inside a record).

using System;
using System.Buffers.Binary;
using System.Collections.Generic;
using System.IO;
using System.Runtime.InteropServices;
using System.Text;
using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu.Recording
{
    /// <summary>A binary pose recording held in memory (see the format at the top of PoseRecording.cs).</summary>
    public sealed class PoseRecording
    {
        internal const int Version = 1;
        internal const int HeaderSize = 40 + 4 * 3 * SmplSkeleton.JointCount;
        internal static readonly byte[] Magic = Encoding.ASCII.GetBytes("MCPOSREC");

        /// <summary>Bytes per pose record.</summary>
        public static unsafe int RecordSize => sizeof(MocapPose);

        /// <summary>A recording of <paramref name="poses"/> (copied).</summary>
        public PoseRecording(float frameRate, SmplSkeleton skeleton, ReadOnlySpan<MocapPose> poses, int contractVersion = 1)
        {
            if (!(frameRate > 0) || float.IsInfinity(frameRate))
                throw new ArgumentOutOfRangeException(nameof(frameRate), frameRate, "must be positive");
            FrameRate = frameRate;
            Skeleton = skeleton ?? throw new ArgumentNullException(nameof(skeleton));
            ContractVersion = contractVersion;
            Poses = poses.ToArray();
        }

        /// <summary>Frame rate of the model that solved the poses, Hz.</summary>
        public float FrameRate { get; }
        /// <summary>The model's contract version.</summary>
        public int ContractVersion { get; }
        /// <summary>The model's skeleton (names and parents of the contract, its rest offsets).</summary>
        public SmplSkeleton Skeleton { get; }
        /// <summary>The poses, in recorded order.</summary>
        public MocapPose[] Poses { get; }
        /// <summary>
        /// Bytes of a partial pose at the end of the file that <see cref="Load"/> left out: a writer
        /// that crashed, or was still writing, between two flushes. 0 for a file closed properly.
        /// </summary>
        public int DiscardedTailBytes { get; private set; }

        /// <summary>
        /// Write the recording to <paramref name="path"/>, replacing the file only once every pose
        /// was written (a temporary file beside it is renamed over it).
        /// </summary>
        /// <exception cref="MocapException">InvalidArgument for a pose holding NaN or infinity (which
        /// <see cref="Load"/> would refuse); NotFound, Permission or IO when the file cannot be
        /// written. The previous file is then unchanged.</exception>
        public void Save(string path)
        {
            RecordingFiles.WriteReplacing(path, "pose recording", stream =>
            {
                // Not disposed: the stream is WriteReplacing's, which flushes and closes it.
                var writer = PoseRecordingWriter.Start(stream, path, FrameRate, Skeleton, ContractVersion);
                for (int i = 0; i < Poses.Length; i++)
                {
                    string field = FirstNonFinite(Poses[i]);
                    if (field != null)
                        throw new MocapException(MocapStatus.InvalidArgument,
                            $"pose recording {path}: pose {i}: {field} is not finite; nothing was written");
                    writer.Append(in Poses[i]);
                }
                writer.Flush();
            });
        }

        /// <summary>Read a recording.</summary>
        /// <exception cref="MocapException">NotFound, Permission or IO naming the file and the cause; Format naming the file and what is wrong.</exception>
        public static PoseRecording Load(string path)
        {
            if (!BitConverter.IsLittleEndian) throw new PlatformNotSupportedException("pose recordings need a little-endian CPU");
            using var stream = RecordingFiles.OpenRead(path, "pose recording");
            try
            {
                return Read(stream, path);
            }
            catch (Exception e) when (RecordingFiles.IsFileError(e))
            {
                // A read that fails after the open (a removed drive, a network share gone).
                throw RecordingFiles.Failure(path, "pose recording", "cannot read", e);
            }
        }

        static PoseRecording Read(FileStream stream, string path)
        {
            var header = new byte[HeaderSize];
            if (ReadFully(stream, header) != HeaderSize)
                throw Bad(path, $"{stream.Length} bytes, shorter than the {HeaderSize}-byte header");
            if (!header.AsSpan(0, 8).SequenceEqual(Magic))
                throw Bad(path, "not a pose recording (the magic is not MCPOSREC)");
            uint version = BinaryPrimitives.ReadUInt32LittleEndian(header.AsSpan(8));
            if (version != Version) throw Bad(path, $"format version {version}; this reader knows version {Version}");
            uint joints = BinaryPrimitives.ReadUInt32LittleEndian(header.AsSpan(12));
            if (joints != SmplSkeleton.JointCount) throw Bad(path, $"{joints} joints; version 1 has {SmplSkeleton.JointCount}");
            uint recordSize = BinaryPrimitives.ReadUInt32LittleEndian(header.AsSpan(16));
            if (recordSize != RecordSize) throw Bad(path, $"records of {recordSize} bytes; version 1 has {RecordSize}");
            float frameRate = ReadFloat(header, 20);
            if (!(frameRate > 0) || float.IsInfinity(frameRate)) throw Bad(path, $"frame rate {frameRate} is not positive");
            ulong count = BinaryPrimitives.ReadUInt64LittleEndian(header.AsSpan(24));
            int contract = BinaryPrimitives.ReadInt32LittleEndian(header.AsSpan(32));
            var offsets = new Vec3[SmplSkeleton.JointCount];
            for (int j = 0; j < offsets.Length; j++)
                offsets[j] = new Vec3(ReadFloat(header, 40 + 12 * j), ReadFloat(header, 44 + 12 * j), ReadFloat(header, 48 + 12 * j));
            SmplSkeleton skeleton;
            try
            {
                skeleton = SmplSkeleton.FromRestOffsets(offsets);
            }
            catch (ArgumentException e)
            {
                throw Bad(path, "rest offsets: " + e.Message);
            }

            long body = stream.Length - HeaderSize;
            long whole = body / RecordSize;
            int partial = (int)(body % RecordSize);
            if ((ulong)whole < count)
                throw Bad(path, $"truncated: the header says {count} poses, the file holds {whole}" +
                                (partial != 0 ? $" and {partial} bytes of a partial pose" : ""));
            // The poses are read as one span of bytes, which holds at most int.MaxValue of them.
            if (whole > int.MaxValue / RecordSize)
                throw Bad(path, $"{whole} poses ({body} bytes) are more than one recording read into memory holds " +
                                $"(at most {int.MaxValue / RecordSize} poses)");
            var poses = new MocapPose[whole];
            // Records are mocap_pose's bytes: read them straight into the array.
            var bytes = MemoryMarshal.AsBytes(poses.AsSpan());
            if (ReadFully(stream, bytes) != bytes.Length) throw Bad(path, "the file shrank while being read");
            for (int i = 0; i < poses.Length; i++)
            {
                string field = FirstNonFinite(poses[i]);
                if (field != null) throw Bad(path, $"pose {i}: {field} is not finite (a damaged file?)");
            }
            return new PoseRecording(frameRate, skeleton, poses, contract) { DiscardedTailBytes = partial };
        }

        // The engine never writes NaN or infinity; a pose holding one comes from damage, and would
        // reach Unity transforms (which reject it) or exported files. Null when all are finite.
        internal static string FirstNonFinite(in MocapPose pose)
        {
            if (!double.IsFinite(pose.TimeSeconds)) return "time";
            if (!pose.RootPosition.IsFinite) return "root position";
            if (!pose.RootVelocity.IsFinite) return "root velocity";
            if (!float.IsFinite(pose.LeftFootContact) || !float.IsFinite(pose.RightFootContact)) return "foot contact";
            for (int j = 0; j < MocapPose.JointCount; j++)
            {
                if (!pose.GetJointRotation(j).IsFinite) return $"joint {j} rotation";
                if (!pose.GetJointPosition(j).IsFinite) return $"joint {j} position";
            }
            return null;
        }

        static float ReadFloat(byte[] b, int offset) =>
            BitConverter.Int32BitsToSingle(BinaryPrimitives.ReadInt32LittleEndian(b.AsSpan(offset)));

        static int ReadFully(Stream stream, Span<byte> buffer)
        {
            int total = 0;
            while (total < buffer.Length)
            {
                int n = stream.Read(buffer.Slice(total));
                if (n == 0) break;
                total += n;
            }
            return total;
        }

        static MocapException Bad(string path, string what) =>
            new MocapException(MocapStatus.Format, $"pose recording {path}: {what}");
    }

    /// <summary>
    /// Streams poses into a binary pose recording as they are solved. <see cref="Append(in MocapPose)"/>
    /// allocates nothing, so it can run every frame; the pose count in the header is rewritten by
    /// <see cref="Flush"/> and on <see cref="Dispose"/>. The file is written in place, so a crash
    /// leaves every flushed pose readable.
    /// </summary>
    /// <remarks>
    /// A failed write (disk full) is thrown by the call that met it, as a MocapException (IO)
    /// naming the file; every later Append and Flush repeats it, and Dispose then only closes the
    /// file, so the first failure is not replaced by a second one from Dispose's flush (for
    /// example in a <c>using</c> block). Dispose after no failure reports a failure of its flush.
    /// </remarks>
    public sealed class PoseRecordingWriter : IDisposable
    {
        readonly FileStream _stream;
        readonly string _path;
        ulong _count;
        bool _disposed;
        MocapException _failure;

        PoseRecordingWriter(FileStream stream, string path)
        {
            _stream = stream;
            _path = path;
        }

        /// <summary>Create (or replace) a recording for poses of a model.</summary>
        public static PoseRecordingWriter Create(string path, ModelInfo model)
        {
            if (model == null) throw new ArgumentNullException(nameof(model));
            return Create(path, model.FrameRate, model.Skeleton, model.ContractVersion);
        }

        /// <summary>Create (or replace) a recording.</summary>
        public static PoseRecordingWriter Create(string path, float frameRate, SmplSkeleton skeleton, int contractVersion = 1)
        {
            if (path == null) throw new ArgumentNullException(nameof(path));
            if (skeleton == null) throw new ArgumentNullException(nameof(skeleton));
            if (!(frameRate > 0) || float.IsInfinity(frameRate))
                throw new ArgumentOutOfRangeException(nameof(frameRate), frameRate, "must be positive");
            FileStream stream;
            try
            {
                stream = new FileStream(path, FileMode.Create, FileAccess.Write, FileShare.Read);
            }
            catch (Exception e) when (RecordingFiles.IsFileError(e))
            {
                throw RecordingFiles.Failure(path, "pose recording", "cannot create", e);
            }
            return Start(stream, path, frameRate, skeleton, contractVersion);
        }

        /// <summary>A writer over an open stream: writes the header (the stream stays the caller's to close).</summary>
        internal static PoseRecordingWriter Start(FileStream stream, string path, float frameRate, SmplSkeleton skeleton,
                                                  int contractVersion)
        {
            if (!BitConverter.IsLittleEndian) throw new PlatformNotSupportedException("pose recordings need a little-endian CPU");
            var header = new byte[PoseRecording.HeaderSize];
            PoseRecording.Magic.CopyTo(header, 0);
            BinaryPrimitives.WriteUInt32LittleEndian(header.AsSpan(8), PoseRecording.Version);
            BinaryPrimitives.WriteUInt32LittleEndian(header.AsSpan(12), SmplSkeleton.JointCount);
            BinaryPrimitives.WriteUInt32LittleEndian(header.AsSpan(16), (uint)PoseRecording.RecordSize);
            WriteFloat(header, 20, frameRate);
            BinaryPrimitives.WriteInt32LittleEndian(header.AsSpan(32), contractVersion);
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
            {
                Vec3 o = skeleton.RestOffset(j);
                WriteFloat(header, 40 + 12 * j, o.X);
                WriteFloat(header, 44 + 12 * j, o.Y);
                WriteFloat(header, 48 + 12 * j, o.Z);
            }
            var writer = new PoseRecordingWriter(stream, path);
            writer.Write(header);
            return writer;
        }

        /// <summary>Poses appended so far.</summary>
        public long Count => (long)_count;

        /// <summary>The file being written.</summary>
        public string Path => _path;

        /// <summary>Append one pose. Allocates nothing.</summary>
        /// <exception cref="MocapException">IO: writing failed (now or before).</exception>
        public unsafe void Append(in MocapPose pose)
        {
            ThrowIfUnusable();
            // A record is the pose's own bytes (see the format above).
            fixed (MocapPose* p = &pose)
                Write(new ReadOnlySpan<byte>(p, sizeof(MocapPose)));
            _count++;
        }

        /// <summary>Append poses in order. Allocates nothing.</summary>
        /// <exception cref="MocapException">IO: writing failed (now or before).</exception>
        public void Append(ReadOnlySpan<MocapPose> poses)
        {
            ThrowIfUnusable();
            Write(MemoryMarshal.AsBytes(poses));
            _count += (ulong)poses.Length;
        }

        /// <summary>Write buffered poses and the pose count to disk.</summary>
        /// <exception cref="MocapException">IO: writing failed (now or before).</exception>
        public void Flush()
        {
            ThrowIfUnusable();
            try
            {
                long end = _stream.Position;
                Span<byte> count = stackalloc byte[8];
                BinaryPrimitives.WriteUInt64LittleEndian(count, _count);
                _stream.Position = 24;
                _stream.Write(count);
                _stream.Position = end;
                _stream.Flush(flushToDisk: false);
            }
            catch (Exception e) when (RecordingFiles.IsFileError(e))
            {
                throw Fail(e);
            }
        }

        /// <summary>
        /// Flush and close the file. After a failed Append or Flush (already thrown) it only
        /// closes the file; otherwise a failure of the final flush is thrown once the file is closed.
        /// </summary>
        /// <exception cref="MocapException">IO: the final flush failed.</exception>
        public void Dispose()
        {
            if (_disposed) return;
            MocapException failure = null;
            if (_failure == null)
            {
                try
                {
                    Flush();
                }
                catch (MocapException e)
                {
                    failure = e;
                }
            }
            _disposed = true;
            try
            {
                _stream.Dispose();
            }
            catch (Exception e) when (RecordingFiles.IsFileError(e))
            {
                // Closing repeats a write failure already met (or met just above): report that one.
                if (failure == null && _failure == null) failure = Fail(e);
            }
            if (failure != null) throw failure;
        }

        void Write(ReadOnlySpan<byte> bytes)
        {
            try
            {
                _stream.Write(bytes);
            }
            catch (Exception e) when (RecordingFiles.IsFileError(e))
            {
                throw Fail(e);
            }
        }

        MocapException Fail(Exception e)
        {
            _failure = RecordingFiles.Failure(_path, "pose recording", "cannot write", e);
            return _failure;
        }

        void ThrowIfUnusable()
        {
            if (_disposed) throw new ObjectDisposedException(nameof(PoseRecordingWriter), _path);
            // Nothing more is written after a failure: the file ends at a whole record or less.
            if (_failure != null)
                throw new MocapException(_failure.Status, $"pose recording {_path}: not writing since a write failed: {_failure.Message}",
                                         _failure);
        }

        static void WriteFloat(byte[] b, int offset, float value) =>
            BinaryPrimitives.WriteInt32LittleEndian(b.AsSpan(offset), BitConverter.SingleToInt32Bits(value));
    }
}
