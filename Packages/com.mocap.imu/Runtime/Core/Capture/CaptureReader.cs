// A pure C# reader of the engine's raw capture files (Native~/docs/capture-format.md), so the
// editor can inspect and play captures without loading the engine. It follows the engine's
// reader rule for rule (src/io/capture_file.c): the same header checks and messages, the same
// chunk validation, the same resynchronisation after a damaged chunk and the same counters, so
// both see exactly the same records in the same file (the tests check this against a replay).

using System;
using System.IO;
using System.Text;
using Mocap.Imu.Recording;

namespace Mocap.Imu.Capture
{
    /// <summary>The file header of a capture.</summary>
    public readonly struct CaptureHeader
    {
        public CaptureHeader(int version, int headerSize, uint flags, long createdUnixNs, string source)
        {
            Version = version;
            HeaderSize = headerSize;
            Flags = flags;
            CreatedUnixNs = createdUnixNs;
            Source = source;
        }

        /// <summary>Format version (1).</summary>
        public int Version { get; }
        /// <summary>Bytes in the header; the first chunk starts here.</summary>
        public int HeaderSize { get; }
        public uint Flags { get; }
        /// <summary>Creation time, ns since the Unix epoch (UTC); 0 if unknown.</summary>
        public long CreatedUnixNs { get; }
        /// <summary>Free-form description of the source, e.g. "serial port /dev/ttyUSB0".</summary>
        public string Source { get; }

        /// <summary>Creation time, or null when the writer did not know it.</summary>
        public DateTime? CreatedUtc =>
            CreatedUnixNs == 0 ? (DateTime?)null
                               : new DateTime(1970, 1, 1, 0, 0, 0, DateTimeKind.Utc).AddTicks(CreatedUnixNs / 100);
    }

    /// <summary>
    /// One record: the bytes of one transport read and their receive time on the session clock.
    /// <see cref="Bytes"/> points into the reader's buffer and is valid until the next read.
    /// </summary>
    public readonly ref struct CaptureRecord
    {
        public CaptureRecord(long receiveNs, ReadOnlySpan<byte> bytes)
        {
            ReceiveNs = receiveNs;
            Bytes = bytes;
        }

        /// <summary>Receive time, ns on the session clock (absolute).</summary>
        public long ReceiveNs { get; }
        /// <summary>The received bytes, unchanged.</summary>
        public ReadOnlySpan<byte> Bytes { get; }
    }

    /// <summary>
    /// Reads a capture file record by record. Damaged chunks are skipped (counted in
    /// <see cref="SkippedChunks"/>); a truncated or corrupt end sets <see cref="TruncatedTail"/>.
    /// Reading allocates nothing after construction (one 64 KiB chunk buffer).
    /// </summary>
    public sealed class CaptureReader : IDisposable
    {
        /// <summary>Format version this reader understands.</summary>
        public const int FormatVersion = 1;
        /// <summary>Largest payload of one chunk.</summary>
        public const int ChunkCapacity = 65536;
        /// <summary>Largest record.</summary>
        public const int MaxRecord = 4096;

        static readonly byte[] FileMagic = Encoding.ASCII.GetBytes("MOCAPRAW");
        const int HeaderFixed = 12;
        const int HeaderV1Size = 284;
        const int HeaderMax = 65535;
        const int SourceOffset = 24;
        const int SourceField = 256;
        const int ChunkHeaderSize = 36;
        const int ChunkCrcOffset = 32;
        const int RecordHeaderSize = 10;
        const int ChunkBufferSize = ChunkHeaderSize + ChunkCapacity;

        enum ChunkResult { Valid, Eof, Short, Invalid }

        readonly Stream _stream;
        readonly string _name;
        readonly byte[] _buffer = new byte[Math.Max(ChunkBufferSize, HeaderMax)];
        long _nextOffset;
        int _recordOffset;
        uint _recordsLeft;
        bool _ended;

        /// <summary>Open a capture file.</summary>
        /// <exception cref="MocapException">NotFound for a missing file, Permission or IO when it
        /// cannot be opened or read; Format for a file that is not a capture (the message names the
        /// file and the cause, as the engine's does).</exception>
        public CaptureReader(string path)
        {
            if (path == null) throw new ArgumentNullException(nameof(path));
            _name = path;
            _stream = RecordingFiles.OpenRead(path, "capture file", FileShare.ReadWrite | FileShare.Delete);
            try
            {
                Header = ReadHeader();
            }
            catch (Exception e) when (RecordingFiles.IsFileError(e))
            {
                _stream.Dispose();
                throw RecordingFiles.Failure(path, "capture file", "cannot read", e);
            }
            catch
            {
                _stream.Dispose();
                throw;
            }
        }

        /// <summary>Read a capture from any seekable stream (name is used in messages).</summary>
        public CaptureReader(Stream stream, string name)
        {
            _stream = stream ?? throw new ArgumentNullException(nameof(stream));
            if (!stream.CanSeek || !stream.CanRead)
                throw new ArgumentException("the stream must be readable and seekable", nameof(stream));
            _name = name ?? "stream";
            Header = ReadHeader();
        }

        /// <summary>The file header.</summary>
        public CaptureHeader Header { get; }

        /// <summary>Valid chunks read so far.</summary>
        public long Chunks { get; private set; }

        /// <summary>Damaged chunks skipped so far (a damaged end is not counted: see <see cref="TruncatedTail"/>).</summary>
        public long SkippedChunks { get; private set; }

        /// <summary>The file ended in a truncated or corrupt chunk (typically a writer killed mid-chunk).</summary>
        public bool TruncatedTail { get; private set; }

        /// <summary>Every record has been read.</summary>
        public bool IsEnded => _ended;

        /// <summary>
        /// The next record, or false at the end of the file. The record's bytes are valid until
        /// the next call.
        /// </summary>
        /// <exception cref="MocapException">IO (or NotFound, Permission) naming the file when reading fails.</exception>
        public bool TryReadNext(out CaptureRecord record)
        {
            record = default;
            if (_ended) return false;
            if (_recordsLeft == 0 && !NextChunk()) return false;
            int p = ChunkHeaderSize + _recordOffset;
            long ns = GetI64(_buffer, p);
            int length = GetU16(_buffer, p + 8);
            record = new CaptureRecord(ns, new ReadOnlySpan<byte>(_buffer, p + RecordHeaderSize, length));
            _recordOffset += RecordHeaderSize + length;
            _recordsLeft--;
            return true;
        }

        public void Dispose() => _stream.Dispose();

        CaptureHeader ReadHeader()
        {
            int got = ReadAt(0, _buffer, 0, HeaderMax);
            string prefix = $"capture file {_name}: ";
            if (got == 0)
                throw new MocapException(MocapStatus.Format, prefix + "empty file, not a mocap capture file");
            for (int i = 0; i < Math.Min(got, FileMagic.Length); i++)
                if (_buffer[i] != FileMagic[i])
                    throw new MocapException(MocapStatus.Format, prefix + "not a mocap capture file");
            if (got < HeaderFixed)
                throw new MocapException(MocapStatus.Format, prefix + $"truncated header ({got} bytes)");
            int version = GetU16(_buffer, 8);
            int headerSize = GetU16(_buffer, 10);
            if (version > FormatVersion)
                throw new MocapException(MocapStatus.Format,
                    prefix + $"format version {version} is newer than this build reads (version {FormatVersion}); update the package");
            if (version == 0 || headerSize < HeaderV1Size)
                throw new MocapException(MocapStatus.Format,
                    prefix + $"invalid header (version {version}, header size {headerSize})");
            if (got < headerSize)
                throw new MocapException(MocapStatus.Format, prefix + $"truncated header ({got} of {headerSize} bytes)");
            if (Crc32.Compute(_buffer, 0, headerSize - 4) != GetU32(_buffer, headerSize - 4))
                throw new MocapException(MocapStatus.Format, prefix + "header CRC mismatch");

            int sourceLength = 0;
            while (sourceLength < SourceField - 1 && _buffer[SourceOffset + sourceLength] != 0) sourceLength++;
            string source = Encoding.UTF8.GetString(_buffer, SourceOffset, sourceLength);
            _nextOffset = headerSize;
            return new CaptureHeader(version, headerSize, GetU32(_buffer, 12), GetI64(_buffer, 16), source);
        }

        bool NextChunk()
        {
            long offset = _nextOffset;
            switch (LoadChunk(offset, out _))
            {
                case ChunkResult.Valid:
                    Chunks++;
                    return true;
                case ChunkResult.Eof:
                    _ended = true;
                    return false;
                default:
                    return Resync(offset);
            }
        }

        // Load the chunk at offset and check everything the writer guarantees, so TryReadNext
        // never meets a malformed record. plausible: the header looked like a real chunk's.
        ChunkResult LoadChunk(long offset, out bool plausible)
        {
            plausible = false;
            int got = ReadAt(offset, _buffer, 0, ChunkHeaderSize);
            if (got == 0) return ChunkResult.Eof;
            if (got < ChunkHeaderSize) return ChunkResult.Short;
            if (_buffer[0] != 'M' || _buffer[1] != 'C' || _buffer[2] != 'H' || _buffer[3] != 'K')
                return ChunkResult.Invalid;
            uint payload = GetU32(_buffer, 4);
            uint count = GetU32(_buffer, 8);
            if (payload == 0 || payload > ChunkCapacity || count == 0 ||
                (ulong)count * (RecordHeaderSize + 1) > payload)
                return ChunkResult.Invalid;
            plausible = true;
            int length = (int)payload;
            got = ReadAt(offset + ChunkHeaderSize, _buffer, ChunkHeaderSize, length);
            if (got < length) return ChunkResult.Short;
            uint crc = Crc32.Update(0, _buffer, 0, ChunkCrcOffset);
            crc = Crc32.Update(crc, _buffer, ChunkHeaderSize, length);
            if (crc != GetU32(_buffer, ChunkCrcOffset)) return ChunkResult.Invalid;

            int pos = 0;
            long first = 0, last = 0;
            for (uint i = 0; i < count; i++)
            {
                if (length - pos < RecordHeaderSize) return ChunkResult.Invalid;
                long ns = GetI64(_buffer, ChunkHeaderSize + pos);
                int recordLength = GetU16(_buffer, ChunkHeaderSize + pos + 8);
                if (recordLength == 0 || recordLength > MaxRecord ||
                    length - pos - RecordHeaderSize < recordLength)
                    return ChunkResult.Invalid;
                if (i == 0) first = ns;
                last = ns;
                pos += RecordHeaderSize + recordLength;
            }
            if (pos != length || first != GetI64(_buffer, 16) || last != GetI64(_buffer, 24))
                return ChunkResult.Invalid;
            _recordOffset = 0;
            _recordsLeft = count;
            _nextOffset = offset + ChunkHeaderSize + length;
            return ChunkResult.Valid;
        }

        // After a damaged chunk: scan forward for "MCHK" candidates, each proven by its CRC and
        // structure. The chunk buffer doubles as the scan window.
        bool Resync(long badOffset)
        {
            long damaged = 1;
            long scan = badOffset + 1;
            for (;;)
            {
                int got = ReadAt(scan, _buffer, 0, ChunkBufferSize);
                int hit = -1;
                for (int i = 0; i + 4 <= got; i++)
                {
                    if (_buffer[i] == 'M' && _buffer[i + 1] == 'C' && _buffer[i + 2] == 'H' && _buffer[i + 3] == 'K')
                    {
                        hit = i;
                        break;
                    }
                }
                if (hit < 0)
                {
                    if (got < ChunkBufferSize) break; // end of file: nothing valid follows
                    scan += got - 3;                  // keep a magic split across windows
                    continue;
                }
                long candidate = scan + hit;
                if (LoadChunk(candidate, out bool plausible) == ChunkResult.Valid)
                {
                    SkippedChunks += damaged;
                    Chunks++;
                    return true;
                }
                // A damaged chunk of its own, unless the magic was just bytes inside a payload.
                if (plausible) damaged++;
                scan = candidate + 1;
            }
            TruncatedTail = true;
            _ended = true;
            return false;
        }

        int ReadAt(long offset, byte[] buffer, int index, int count)
        {
            try
            {
                _stream.Position = offset;
                int total = 0;
                while (total < count)
                {
                    int n = _stream.Read(buffer, index + total, count - total);
                    if (n <= 0) break;
                    total += n;
                }
                return total;
            }
            catch (Exception e) when (RecordingFiles.IsFileError(e))
            {
                // A read failing after the open (a removed drive, a network share gone).
                throw RecordingFiles.Failure(_name, "capture file", "cannot read", e);
            }
        }

        static int GetU16(byte[] b, int p) => b[p] | (b[p + 1] << 8);

        static uint GetU32(byte[] b, int p) =>
            (uint)(b[p] | (b[p + 1] << 8) | (b[p + 2] << 16) | (b[p + 3] << 24));

        static long GetI64(byte[] b, int p) => (long)((ulong)GetU32(b, p) | ((ulong)GetU32(b, p + 4) << 32));
    }

    /// <summary>CRC-32/ISO-HDLC (zlib's crc32), as the capture format uses.</summary>
    public static class Crc32
    {
        static readonly uint[] Table = BuildTable();

        static uint[] BuildTable()
        {
            var table = new uint[256];
            for (uint n = 0; n < 256; n++)
            {
                uint c = n;
                for (int k = 0; k < 8; k++) c = (c & 1) != 0 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
                table[n] = c;
            }
            return table;
        }

        /// <summary>Continue a CRC (start with 0) over data[offset, offset + count).</summary>
        public static uint Update(uint crc, byte[] data, int offset, int count)
        {
            crc = ~crc;
            for (int i = offset; i < offset + count; i++) crc = Table[(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
            return ~crc;
        }

        /// <summary>The CRC of data[offset, offset + count).</summary>
        public static uint Compute(byte[] data, int offset, int count) => Update(0, data, offset, count);
    }
}
