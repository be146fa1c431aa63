// The pure C# capture reader, cross-checked against the engine: on intact, truncated and
// damaged files the C# reader must deliver exactly the bytes the engine's replay delivers,
// and refuse bad headers with the engine's own status and message.

using System;
using System.Diagnostics;
using System.IO;
using System.Text;
using Mocap.Imu.Capture;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed class CaptureReaderTests
    {
        SynthCapture _capture;
        string _dir;

        [OneTimeSetUp]
        public void Generate()
        {
            TestPaths.RequireEngine();
            _capture = TestPaths.Synth("walk", seconds: 6);
            _dir = TestPaths.NewTempDirectory("capture");
        }

        struct Totals
        {
            public long Records, Bytes, FirstNs, LastNs;
            public long Chunks, Skipped;
            public bool Tail;
        }

        static Totals ReadAll(string path)
        {
            var t = new Totals { FirstNs = -1 };
            using var reader = new CaptureReader(path);
            long previous = long.MinValue;
            while (reader.TryReadNext(out var record))
            {
                Assert.That(record.Bytes.Length, Is.InRange(1, CaptureReader.MaxRecord));
                Assert.GreaterOrEqual(record.ReceiveNs, previous, "receive times never go back");
                previous = record.ReceiveNs;
                if (t.FirstNs < 0) t.FirstNs = record.ReceiveNs;
                t.LastNs = record.ReceiveNs;
                t.Records++;
                t.Bytes += record.Bytes.Length;
            }
            Assert.IsTrue(reader.IsEnded);
            Assert.IsFalse(reader.TryReadNext(out _), "stays ended");
            t.Chunks = reader.Chunks;
            t.Skipped = reader.SkippedChunks;
            t.Tail = reader.TruncatedTail;
            return t;
        }

        /// <summary>Bytes the engine's replay of a file receives (fast replay to the end).</summary>
        static MocapSessionStats EngineReplay(string path)
        {
            using var session = MocapSession.Open(SessionConfig.Replay(path));
            session.Start();
            var buffer = new MocapFrame[64];
            var watch = Stopwatch.StartNew();
            while (session.Drain(buffer, out _) != MocapPollResult.EndOfStream)
            {
                Assert.Less(watch.Elapsed.TotalSeconds, 60, "replay did not end");
                System.Threading.Thread.Sleep(1);
            }
            return session.GetStats();
        }

        static long[] ChunkOffsets(byte[] file)
        {
            var offsets = new System.Collections.Generic.List<long>();
            for (int i = 284; i + 4 <= file.Length; i++)
                if (file[i] == 'M' && file[i + 1] == 'C' && file[i + 2] == 'H' && file[i + 3] == 'K')
                    offsets.Add(i);
            return offsets.ToArray();
        }

        [Test]
        public void Crc32MatchesTheStandardCheckValue()
        {
            var data = Encoding.ASCII.GetBytes("123456789");
            Assert.AreEqual(0xCBF43926u, Crc32.Compute(data, 0, data.Length));
            Assert.AreEqual(0xCBF43926u, Crc32.Update(Crc32.Compute(data, 0, 4), data, 4, 5), "incremental");
        }

        [Test]
        public void ReadsTheHeaderAndEveryRecordOfASynthCapture()
        {
            using (var reader = new CaptureReader(_capture.CapturePath))
            {
                Assert.AreEqual(1, reader.Header.Version);
                Assert.AreEqual(284, reader.Header.HeaderSize);
                Assert.IsNotNull(reader.Header.Source);
                TestContext.WriteLine($"source '{reader.Header.Source}', created {reader.Header.CreatedUtc}");
            }
            var t = ReadAll(_capture.CapturePath);
            // 14 s at 100 packets per second, one record per packet.
            Assert.That(t.Records, Is.InRange(1390, 1410));
            Assert.AreEqual(14.0, (t.LastNs - t.FirstNs) * 1e-9, 0.05);
            Assert.AreEqual(0, t.Skipped);
            Assert.IsFalse(t.Tail);
            Assert.Greater(t.Chunks, 1);

            var engine = EngineReplay(_capture.CapturePath);
            Assert.AreEqual((ulong)t.Bytes, engine.BytesReceived, "C# and the engine read the same bytes");
            Assert.AreEqual((ulong)t.Records, engine.FramesDecoded, "one HiPNUC frame per record");
        }

        [Test]
        public void TruncatedTailEndsCleanlyLikeTheEngine()
        {
            var bytes = File.ReadAllBytes(_capture.CapturePath);
            var offsets = ChunkOffsets(bytes);
            // Cut in the middle of the last chunk, as a writer killed mid-write leaves it.
            long cut = offsets[offsets.Length - 1] + 500;
            var path = Path.Combine(_dir, "truncated.cap");
            File.WriteAllBytes(path, bytes.AsSpan(0, (int)cut).ToArray());

            var whole = ReadAll(_capture.CapturePath);
            var t = ReadAll(path);
            Assert.IsTrue(t.Tail, "the truncated chunk is reported as a damaged tail");
            Assert.AreEqual(0, t.Skipped);
            Assert.AreEqual(whole.Chunks - 1, t.Chunks);
            Assert.Less(t.Bytes, whole.Bytes);
            Assert.AreEqual((ulong)t.Bytes, EngineReplay(path).BytesReceived);
        }

        [Test]
        public void DamagedChunkIsSkippedLikeTheEngine()
        {
            var bytes = File.ReadAllBytes(_capture.CapturePath);
            var offsets = ChunkOffsets(bytes);
            Assert.GreaterOrEqual(offsets.Length, 3);
            bytes[offsets[1] + 36 + 1000] ^= 0x5A; // a payload byte of the second chunk
            var path = Path.Combine(_dir, "damaged.cap");
            File.WriteAllBytes(path, bytes);

            var whole = ReadAll(_capture.CapturePath);
            var t = ReadAll(path);
            Assert.AreEqual(1, t.Skipped, "one damaged chunk");
            Assert.IsFalse(t.Tail);
            Assert.AreEqual(whole.Chunks - 1, t.Chunks);
            Assert.Less(t.Bytes, whole.Bytes);
            Assert.AreEqual((ulong)t.Bytes, EngineReplay(path).BytesReceived, "the engine skips the same chunk");
        }

        [Test]
        public void BadHeadersAreRefusedWithTheEngineStatusAndMessage()
        {
            var good = File.ReadAllBytes(_capture.CapturePath);

            var empty = Write("empty.cap", Array.Empty<byte>());
            var notCapture = Write("text.cap", Encoding.ASCII.GetBytes("hello, this is not a capture file at all"));
            var truncated = Write("short.cap", good.AsSpan(0, 100).ToArray());
            var newer = (byte[])good.Clone();
            newer[8] = 2; // version 2, before the CRC check
            var newerPath = Write("newer.cap", newer);
            var badCrc = (byte[])good.Clone();
            badCrc[30] ^= 0xFF; // inside the source text
            var badCrcPath = Write("crc.cap", badCrc);

            foreach (var (path, expected) in new[]
                     {
                         (empty, "empty file"), (notCapture, "not a mocap capture file"), (truncated, "truncated header"),
                         (newerPath, "newer than this build"), (badCrcPath, "header CRC mismatch"),
                     })
            {
                var mine = Assert.Throws<MocapException>(() => new CaptureReader(path).Dispose());
                var engine = Assert.Throws<MocapException>(() => MocapSession.Open(SessionConfig.Replay(path)));
                Assert.AreEqual(MocapStatus.Format, mine.Status, path);
                Assert.AreEqual(engine.Status, mine.Status, path);
                Assert.AreEqual(engine.Message, mine.Message, "the same text as the engine");
                StringAssert.Contains(expected, mine.Message);
                StringAssert.Contains(path, mine.Message, "the message names the file");
            }

            var missing = Path.Combine(_dir, "missing.cap");
            var e = Assert.Throws<MocapException>(() => new CaptureReader(missing));
            Assert.AreEqual(MocapStatus.NotFound, e.Status);
            StringAssert.Contains(missing, e.Message);
        }

        [Test]
        public void ReadsFromAnyStream()
        {
            var bytes = File.ReadAllBytes(_capture.CapturePath);
            using var reader = new CaptureReader(new MemoryStream(bytes, writable: false), "memory");
            Assert.IsTrue(reader.TryReadNext(out var first));
            Assert.AreEqual(ReadAll(_capture.CapturePath).FirstNs, first.ReceiveNs);
            // A HiPNUC frame starts with 0x5A 0xA5.
            Assert.AreEqual(0x5A, first.Bytes[0]);
            Assert.AreEqual(0xA5, first.Bytes[1]);
        }

        string Write(string name, byte[] bytes)
        {
            var path = Path.Combine(_dir, name);
            File.WriteAllBytes(path, bytes);
            return path;
        }
    }
}
